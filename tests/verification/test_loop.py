"""Loop transfer at the plant input: against its hand derivation and python-control; closed-loop zeros."""

from __future__ import annotations

import control
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from designkit.families import synthesize
from designkit.schema.loader import parse_spec
from designkit.verification import loop
from tests.problems import COMPLEX_YAML, POSSPEED_YAML, TRACKING_YAML


def _design(text):
    return synthesize(parse_spec(text).spec)


@pytest.mark.parametrize("text", [POSSPEED_YAML, COMPLEX_YAML])
def test_servo_loop_transfer_matches_hand_derivation(text):
    """L(s) = C(s) P(s), C = K1 + K2 s + K3/s on x1, P = Km / (s (tau s + 1))."""
    design = _design(text)
    g, Km, tau = design.gains, design.plant.Km, design.plant.tau
    w = np.logspace(-1, 3, 25)
    s = 1j * w
    hand = Km * (g["K2"] * s**2 + g["K1"] * s + g["K3"]) / (s**2 * (tau * s + 1))
    np.testing.assert_allclose(loop.loop_frequency_response(design, w), hand, rtol=1e-10)


def test_tracking_loop_transfer_matches_hand_derivation():
    design = _design(TRACKING_YAML)
    g, Km, tau = design.gains, design.plant.Km, design.plant.tau
    w = np.logspace(-1, 3, 25)
    s = 1j * w
    hand = ((Km * g["K2"] - 1) * s**2 + Km * g["K1"] * s + Km * g["K3"]) / (s**2 * (tau * s + 1))
    np.testing.assert_allclose(loop.loop_frequency_response(design, w), hand, rtol=1e-10)


@pytest.mark.parametrize("text", [POSSPEED_YAML, COMPLEX_YAML, TRACKING_YAML])
def test_loop_equals_minus_one_at_the_closed_loop_poles(text):
    """1 + L(p) = 0 at every closed-loop pole: the loop really closes into the design's poles."""
    design = _design(text)
    A, b, c = loop.loop_matrices(design)
    for p in design.poles:
        L = (c @ np.linalg.solve(p * np.eye(3) - A, b))[0, 0]
        assert abs(1 + L) < 1e-9 * (1 + abs(L))


def test_margins_agree_with_python_control_on_the_hand_transfer():
    design = _design(POSSPEED_YAML)
    g, Km, tau = design.gains, design.plant.Km, design.plant.tau
    L = control.tf([Km * g["K2"], Km * g["K1"], Km * g["K3"]], [tau, 1, 0, 0])
    gm, pm, _, _, wgc, _ = control.stability_margins(L)
    m = loop.loop_margins(design)
    assert m.phase_margin == pytest.approx(pm, rel=1e-6)
    assert m.w_gain_crossover == pytest.approx(wgc, rel=1e-6)
    assert np.isinf(m.gain_margin) and np.isinf(gm)
    assert 0 < m.modulus_margin <= 1.0 + 1e-6


def test_achieved_zero_is_the_requested_zero():
    design = _design(POSSPEED_YAML)
    np.testing.assert_allclose(loop.achieved_zeros(design), [-3.0], atol=1e-9)
    assert loop.achieved_zeros(_design(TRACKING_YAML)).size == 0


def test_siso_zeros_of_a_known_transfer():
    sys = control.ss(control.tf([1, 3, 2], [1, 6, 11, 6]))  # zeros -1, -2
    z = loop.siso_zeros(np.asarray(sys.A), np.asarray(sys.B)[:, 0], np.asarray(sys.C)[0], float(sys.D[0, 0]))
    np.testing.assert_allclose(np.sort(z.real), [-2.0, -1.0], atol=1e-9)


@settings(max_examples=80, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 5))
def test_margins_agree_with_python_control_on_random_loops(seed, n):
    """Exact crossovers (polynomial roots) against python-control's ``stability_margins``."""
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(n, n)) * rng.uniform(0.2, 5.0)
    b, c = rng.normal(size=(n, 1)), rng.normal(size=(1, n)) * rng.uniform(0.5, 20.0)
    gm, pm, _sm, wpc, wgc, _ = control.stability_margins(control.ss(A, b, c, 0.0))
    ours = loop.classical_margins(A, b, c)
    for mine, ref in zip(ours, (gm, pm, wpc, wgc), strict=True):
        if np.isfinite(ref):
            assert mine == pytest.approx(ref, rel=1e-6, abs=1e-9)
        else:
            assert not np.isfinite(mine) or (np.isnan(ref) and np.isnan(mine))


def test_random_siso_zeros_and_dc_gain_agree_with_python_control():
    from designkit.verification.pole_zero import Siso, dc_gain, finite_zeros

    rng = np.random.default_rng(7)
    for n in range(1, 6):
        for _ in range(20):
            A = rng.normal(size=(n, n)) - 2.0 * np.eye(n)
            B, C, D = rng.normal(size=(n, 1)), rng.normal(size=(1, n)), rng.normal(size=(1, 1)) * rng.integers(0, 2)
            sys = control.ss(A, B, C, D)
            z, _ = finite_zeros(Siso(A, B, C, D))
            ref = np.asarray(control.zeros(sys))
            ref = ref[np.isfinite(ref) & (np.abs(ref) < 1e8)]
            assert len(z) == len(ref)
            if len(ref):
                np.testing.assert_allclose(np.sort_complex(z), np.sort_complex(ref), rtol=1e-7, atol=1e-9)
            assert dc_gain(Siso(A, B, C, D)) == pytest.approx(complex(control.dcgain(sys)), rel=1e-9, abs=1e-12)
