"""The Coulomb compensation's boundary layer (``controller.friction_layer``) of computed torque.

Expected values come from an independent route: the smoothstep written out in NumPy from its definition and
the Coulomb levels of the DH table (not from the module's ``coulomb_levels``), the total variation of the
commanded torque summed in NumPy from the run, and the design's linearization compared with and without the
layer.
"""

from __future__ import annotations

import numpy as np
import pytest

from designkit.pipeline import design as design_of
from designkit.pipeline import plant as plant_of
from designkit.pipeline import run
from designkit.schema.loader import parse_spec
from tests.cli_input import assert_bad_input

FC = (5.0, 2.0)
"""Coulomb levels of the two joints (N*m), as the DH table below writes them."""

TEXT = """
name: two-link-coulomb
plant:
  kind: robot
  dh:
    - {{a: 0.5, alpha: 0, d: 0, mass: 5.0, com: [-0.25, 0, 0], inertia: [0.01, 0.1, 0.1, 0, 0, 0], viscous: 0.5,
        coulomb: 5.0}}
    - {{a: 0.4, alpha: 0, d: 0, mass: 3.0, com: [-0.2, 0, 0], inertia: [0.01, 0.04, 0.04, 0, 0, 0], viscous: 0.2,
        coulomb: 2.0}}
controller: {{kind: computed_torque, damping: 1.0, natural_frequency: 10{layer}}}
simulation:
  duration: 2.0
  trajectory: {{kind: quintic, amplitude: [0.0, 1.0], duration: 1.0}}
"""
"""A horizontal two-link arm whose first joint is held still while the second moves: the coupling leaves the
first joint's speed at round-off, where ``sign`` switches."""


def _spec(layer: float | None):
    return parse_spec(TEXT.format(layer="" if layer is None else f", friction_layer: {layer}"))


def _smoothstep(x: np.ndarray) -> np.ndarray:
    a = np.clip(np.abs(x), 0.0, 1.0)
    return np.sign(x) * (3.0 * a**2 - 2.0 * a**3)


def test_the_default_is_the_exact_sign():
    assert _spec(None).spec.controller.friction_layer == 0.0


def test_inside_the_layer_the_compensation_is_the_smoothstep_and_outside_it_is_unchanged():
    layer = 0.05
    exact = design_of(_spec(0.0))
    smooth = design_of(_spec(layer))
    rng = np.random.default_rng(3)
    for _ in range(20):
        q = rng.uniform(-2, 2, 2)
        qd = rng.uniform(-2 * layer, 2 * layer, 2)  # inside and outside the layer
        y = np.concatenate([q, qd])
        r = rng.normal(size=6)
        args = (y, np.zeros(0), np.zeros(0), r)
        diff = np.asarray(smooth.law.command(*args)).ravel() - np.asarray(exact.law.command(*args)).ravel()
        want = np.asarray(FC) * (_smoothstep(qd / layer) - np.sign(qd))
        np.testing.assert_allclose(diff, want, rtol=1e-9, atol=1e-9)
        assert np.all(diff[np.abs(qd) >= layer] == pytest.approx(0.0, abs=1e-9))
        assert np.all(np.abs(diff) <= np.asarray(FC) + 1e-12)  # the residual is bounded by Fc


def test_the_smoothstep_is_continuously_differentiable_at_the_layer_edge_and_flat_at_rest():
    h = 1e-6
    for x in (0.0, 1.0, -1.0):
        slope = (_smoothstep(np.array(x + h)) - _smoothstep(np.array(x - h))) / (2 * h)
        assert abs(float(slope)) < 1e-5


def test_the_layer_leaves_the_designed_linearization_unchanged():
    exact, smooth = design_of(_spec(0.0)), design_of(_spec(0.2))
    np.testing.assert_allclose(smooth.closed_loop.A, exact.closed_loop.A, rtol=0, atol=1e-12)
    np.testing.assert_allclose(smooth.closed_loop.B, exact.closed_loop.B, rtol=0, atol=1e-12)


def test_the_layer_is_named_in_the_laws_description():
    smooth = design_of(_spec(0.05))
    assert any("boundary layer φ = 0.05 rad/s" in n for n in smooth.notes)
    assert any("s(q̇/φ)" in f for f in smooth.formulas)
    assert smooth.law.settings["friction_layer"] == 0.05


def _total_variation(result) -> np.ndarray:
    u = np.asarray(result.simulation.u_command, dtype=float)
    return np.sum(np.abs(np.diff(u, axis=0)), axis=0)


def test_a_layer_removes_the_chatter_of_the_joint_held_still():
    exact, smooth = run(_spec(0.0)), run(_spec(0.05))
    chatter = {r: next(c for c in r.checks if c.name == "command_chatter") for r in (exact, smooth)}
    assert chatter[exact].passed is False and "Coulomb friction compensation" in chatter[exact].detail
    assert chatter[smooth].passed is True
    tv_exact, tv_smooth = _total_variation(exact), _total_variation(smooth)
    # the first joint's command: 2 Fc per reversal with the sign, far less with the layer
    assert tv_smooth[0] < 0.5 * tv_exact[0]
    # what the layer costs: the exact compensation cancels the plant's friction to round-off; with the layer the
    # plant's own friction acts inside it, and the first joint's error stays far below Fc / (M11 K1)
    arm = plant_of(_spec(0.0))
    m11 = float(np.asarray(arm.robot.mass_matrix(np.zeros(2), p=arm.model_parameters()))[0, 0])
    err_exact = np.max(np.abs(exact.simulation.tracking_errors), axis=0)
    err_smooth = np.max(np.abs(smooth.simulation.tracking_errors), axis=0)
    assert err_exact[0] < 1e-9
    assert 0 < err_smooth[0] < FC[0] / (m11 * 100.0)


def test_a_chattering_input_is_warned_of_once(monkeypatch):
    """command_switching leaves to command_chatter (which names the source) the inputs that check warns of: with
    every input made to look switching-dominated, only the inputs that do not chatter are warned of by it."""
    import designkit.verification.switching as switching

    monkeypatch.setattr(switching, "warning", lambda m, unit: f"planted: {m.name} switches")
    exact = run(_spec(0.0))
    chatter = next(c for c in exact.checks if c.name == "command_chatter")
    warned = {w.split()[1] for w in next(c for c in exact.checks if c.name == "command_switching").warnings}
    chattering = {i["input"] for i in chatter.certificate["inputs"] if i["chatters"]}
    calm = {i["input"] for i in chatter.certificate["inputs"] if not i["chatters"]}
    assert chattering and warned == calm


@pytest.mark.parametrize(("value", "message"), [
    ("-0.1", "controller.friction_layer: "),
    ("1e-9", "controller.friction_layer: "),
    ("2e3", "controller.friction_layer: "),
    ('"wide"', "controller.friction_layer: "),
])
def test_a_bad_layer_is_refused_with_its_key_path(tmp_path, capsys, value, message):
    assert_bad_input(tmp_path, capsys, TEXT.format(layer=f", friction_layer: {value}"), message)
