"""The example runs: V non-increasing along the run (computed in the run, re-judged here from its record), the
tracking error going to zero, the estimates converging on the exciting trajectory and not on the poor one, and
the not-SPR design failing its certificate while V rises."""

from __future__ import annotations

import numpy as np
import pytest

from designkit.families.adaptive_computed_torque.laws import estimates


def _check(result, name):
    return next(c for c in result.checks if c.name == name)


def _V_from_record(result) -> np.ndarray:
    """V recomputed from the recorded errors and estimates with the closed-form KYP matrix (independently of the
    law's own signal)."""
    sim, a = result.simulation, result.design.data.adaptation
    K1, K2, psi, K = (np.asarray(getattr(a, k), dtype=float) for k in ("K1", "K2", "psi", "gain"))
    ref = np.asarray(sim.reference)
    x = np.asarray(sim.state)
    n = len(K1)
    e, ed = ref[:, :, 0] - x[:, :n], ref[:, :, 1] - x[:, n:2 * n]
    phi = np.asarray(result.design.data.true) - estimates(sim, a.names)
    return np.sum((K2 + psi * K1) * e**2 + 2 * e * ed + psi * ed**2, axis=1) + np.sum(phi**2 / K, axis=1)


def test_v_is_non_increasing_along_the_exciting_run(simnog_result):
    V = _V_from_record(simnog_result)
    np.testing.assert_allclose(V, simnog_result.simulation.signals["V"], rtol=1e-9, atol=1e-12)
    assert np.all(np.diff(V) <= 1e-9 * V[0])
    assert V[-1] < 1e-6 * V[0]
    assert _check(simnog_result, "adaptive_lyapunov").passed is True


def test_v_rises_when_the_filter_is_not_spr(not_spr_result):
    V = _V_from_record(not_spr_result)
    rise = np.max(V - np.minimum.accumulate(V))
    assert rise > 0.05 * V[0]
    check = _check(not_spr_result, "adaptive_lyapunov")
    assert check.passed is False and check.achieved == pytest.approx(rise / V[0], rel=1e-6)


def test_exciting_run_tracks_and_estimates_converge(simnog_result):
    sim = simnog_result.simulation
    t = np.asarray(sim.time)
    e = np.asarray(sim.reference)[:, :, 0] - np.asarray(sim.state)[:, :2]
    assert np.max(np.abs(e[t > 18.0])) < 1e-6 < np.max(np.abs(e))
    final = estimates(sim, ("m1", "m2"))[-1]
    np.testing.assert_allclose(final, [5.0, 3.0], rtol=1e-4)  # the true SIMNOG masses (planar2r DEFAULTS)
    conv = _check(simnog_result, "estimate_convergence")
    assert conv.passed is True and conv.required and conv.certificate["exciting"]
    assert simnog_result.verified


def test_poor_run_tracks_but_estimates_stay_wrong(poor_result):
    sim = poor_result.simulation
    t = np.asarray(sim.time)
    e = np.asarray(sim.reference)[:, :, 0] - np.asarray(sim.state)[:, :2]
    assert np.max(np.abs(e[t > 9.0])) < 1e-5
    est = estimates(sim, ("m1", "m2"))
    assert np.all(np.abs(est[-1] - [5.0, 3.0]) / [5.0, 3.0] > 0.1)
    # in the upright pose at rest the update has nothing to act on: the estimates stop moving
    np.testing.assert_allclose(est[t > 5.0][0], est[-1], rtol=1e-6)
    conv = _check(poor_result, "estimate_convergence")
    assert conv.passed is False and not conv.required and not conv.certificate["exciting"]
    assert conv.certificate["alpha_min"] < 1e-6 < _excitation_alpha()
    assert _check(poor_result, "tracking_convergence").passed is True
    assert poor_result.verified


def _excitation_alpha() -> float:
    """The exciting example's smallest windowed eigenvalue of the integral of W'W, for comparison (computed from
    the regressor on the sine directly)."""
    from designkit.models.robot_plant import zoo_plant

    plant = zoo_plant("planar2r")
    t = np.linspace(15.0, 20.0, 2001)
    w = 2 * np.pi * 0.5
    A = np.array([1.0, 1.2])
    q, qd, qdd = A * np.sin(w * t)[:, None], A * w * np.cos(w * t)[:, None], -A * w * w * np.sin(w * t)[:, None]
    names = list(plant.robot.parameter_names)
    W = np.asarray(plant.robot.regressor(q, qd, qdd, p=plant.model_parameters()))[:, :, [names.index("m1"),
                                                                                          names.index("m2")]]
    G = np.trapezoid(np.einsum("kia,kib->kab", W, W), t, axis=0)
    return float(np.linalg.eigvalsh(G)[0])


def test_not_spr_certificate_fails_and_says_which_psi_would_do(not_spr_result):
    check = _check(not_spr_result, "spr_certificate")
    assert check.passed is False
    assert check.achieved == pytest.approx(0.02 * 20 - 1)
    assert "ψ > 1/K2 = 0.05 s" in check.detail
    assert not not_spr_result.verified


def test_filtered_acceleration_also_converges_with_v_within_its_tolerance():
    """The filtered velocity derivative (two more controller states) instead of the ideal accelerometer: the loop
    still converges on the exciting sine, and V stays non-increasing within the check's looser tolerance."""
    from designkit.pipeline import run
    from designkit.schema.loader import parse_spec
    from tests.families.adaptive_computed_torque.conftest import SPECS

    text = (SPECS / "adaptive-ct-simnog.yaml").read_text().replace(
        "  delta: 0.05\n", "  delta: 0.05\n  acceleration: filtered\n  bandwidth: 200\n")
    result = run(parse_spec(text))
    sim = result.simulation
    assert "vf1" in sim.controller_state_names and "vf2" in sim.controller_state_names
    V = _V_from_record(result)
    assert np.max(V - np.minimum.accumulate(V)) <= 1e-2 * V[0]
    np.testing.assert_allclose(estimates(sim, ("m1", "m2"))[-1], [5.0, 3.0], rtol=1e-3)
    assert _check(result, "adaptive_lyapunov").passed is True
