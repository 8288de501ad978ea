"""The closed-loop simulator against python-control, and the effect of each POSSPEED element."""

from __future__ import annotations

import json

import control
import numpy as np
import pytest

from designkit.schema.spec import Spec
from designkit.simulation.linear import linear_response
from designkit.simulation.reference import quintic, step_reference
from designkit.simulation.run import simulate
from tests.simulation.helpers import (
    OTHER_PLANT,
    TOL,
    TRACKING,
    design_of,
    make_spec,
    overshoot,
    scaled_error,
)

QUINTIC = {"kind": "quintic", "amplitude": 1.0, "duration": 1.0}


# ----------------------------------------------------------------------------- linear equivalence


def _servo_error(dt: float) -> tuple[float, float]:
    spec = Spec.model_validate({**make_spec(duration=3.0, dt=dt).model_dump(), "numerics": {"integrator": "rk4"}})
    design = design_of(spec)
    res = simulate(spec, design)
    x1, u = linear_response(design, res.time, res.reference)  # exact for a constant input
    return scaled_error(res.position, x1[:, 0]), scaled_error(res.u_command[:, 0], u[:, 0])


def test_servo_step_equals_python_control_and_converges_as_dt4():
    e_coarse, _ = _servo_error(0.02)
    e_fine, e_u = _servo_error(0.01)
    assert 12.0 < e_coarse / e_fine < 24.0, (e_coarse, e_fine)
    e_default, e_u_default = _servo_error(0.0025)
    assert e_default < TOL["rk4_vs_exact"] and e_u_default < 10 * TOL["rk4_vs_exact"]


def _tracking_error(dt: float) -> float:
    spec = make_spec(TRACKING, duration=2.0, dt=dt, trajectory=QUINTIC)
    res = simulate(spec, design_of(spec))
    return float(np.max(np.abs(res.tracking_error)))  # the nominal loop tracks exactly: x1 = xD


def test_nominal_tracking_follows_the_quintic_exactly_up_to_rk4_error():
    e_coarse, e_fine = _tracking_error(0.01), _tracking_error(0.005)
    assert 12.0 < e_coarse / e_fine < 24.0, (e_coarse, e_fine)
    assert e_fine < TOL["rk4_vs_exact"]


@pytest.mark.parametrize("controller", [None, TRACKING], ids=["servo", "tracking"])
def test_mismatched_plant_equals_python_control(controller):
    scenario = {"trajectory": QUINTIC} if controller is not None else {}  # a servo follows simulation.step
    spec = make_spec(controller, duration=2.5, dt=0.001, **scenario)
    design = design_of(spec)
    res = simulate(spec, design, plant=OTHER_PLANT)
    fine = np.linspace(0.0, 2.5, 25001)  # python-control holds inputs first-order: use a finer grid
    ref = (step_reference(1.0) if controller is None else quintic(1.0, 1.0)).evaluate(fine)
    x1, u = linear_response(design, fine, ref, plant=OTHER_PLANT)
    assert res.settings["plant"] == {"Km": 2.4, "tau": 0.6}
    assert scaled_error(res.position, x1[::10, 0]) < TOL["rk4_vs_foh"]
    assert scaled_error(res.u_command[:, 0], u[::10, 0]) < 10 * TOL["rk4_vs_foh"]


# ----------------------------------------------------------------------------- saturation


def test_large_saturation_equals_no_saturation_and_small_caps_the_control():
    free = simulate(spec := make_spec(duration=2.0), design := design_of(spec))
    big = simulate(make_spec(duration=2.0, nonlinearity={"kind": "saturation", "limit": 1e6}), design)
    np.testing.assert_array_equal(big.state, free.state)
    small = simulate(make_spec(duration=2.0, nonlinearity={"kind": "saturation", "limit": 5.0}), design)
    assert np.max(np.abs(small.u_applied)) <= 5.0
    assert np.max(np.abs(small.u_command)) > 30.0  # the controller did ask for more
    np.testing.assert_array_equal(small.u_applied, np.clip(small.u_command, -5.0, 5.0))


# ----------------------------------------------------------------------------- delay and sampling


def test_delay_shifts_the_applied_control_by_exactly_d():
    spec = make_spec(duration=2.0, dt=0.001, delay=0.012, nonlinearity={"kind": "saturation", "limit": 20})
    res = simulate(spec, design_of(spec))
    nd = 12
    assert res.settings["delay_steps"] == nd
    np.testing.assert_array_equal(res.u_applied[:nd], 0.0)
    np.testing.assert_array_equal(res.u_applied[nd:], np.clip(res.u_command[:-nd], -20, 20))
    assert np.max(np.abs(res.u_command)) > 20


def test_zero_order_hold_is_piecewise_constant_on_sampling_intervals():
    spec = make_spec(duration=1.0, dt=0.001, sampling_period=0.01)
    design = design_of(spec)
    res = simulate(spec, design)
    blocks = res.u_applied[: 1000].reshape(100, 10)
    np.testing.assert_array_equal(blocks, blocks[:, :1].repeat(10, axis=1))
    assert np.count_nonzero(np.diff(blocks[:, 0])) > 90  # it does change at every sampling instant
    # At a sampling instant the command is the servo law on the samples of that instant.
    g = design.gains
    k = np.arange(0, 1000, 10)
    y1, y2, x3, xD = res.measured[k, 0], res.measured[k, 1], res.controller_state[k, 0], res.desired[k, 0]
    law = -g["K1"] * (y1 - xD) - g["K2"] * y2 - g["K3"] * x3 + g["K3"] * g["K4"] * xD
    np.testing.assert_allclose(res.u_command[k, 0], law, rtol=1e-12, atol=1e-12)
    # The digital integral is rectangular: x3 grows by Ts * (y1 - xD) of the last sampling instant.
    np.testing.assert_allclose(np.diff(x3), 0.01 * (y1 - xD)[:-1], rtol=1e-9, atol=1e-12)


def test_fast_sampling_approaches_the_continuous_loop():
    continuous = simulate(spec := make_spec(duration=2.0, dt=0.0005), design := design_of(spec))
    errors = [np.max(np.abs(simulate(make_spec(duration=2.0, dt=0.0005, sampling_period=ts), design).position
                            - continuous.position)) for ts in (0.01, 0.005)]
    assert errors[1] < 0.7 * errors[0] and errors[1] < 0.02


# ----------------------------------------------------------------------------- perturbation


def test_servo_rejects_a_constant_perturbation():
    spec = make_spec(duration=5.0, perturbation={"value": -5.0, "time": 0.0})
    res = simulate(spec, design_of(spec))
    assert np.max(np.abs(res.tracking_error)) > 0.1  # it did disturb the response
    assert abs(res.tracking_error[-1]) < TOL["settled"]
    assert abs(res.u_command[-1, 0] - 5.0) < 1e-3  # the integral supplies -xi


def test_servo_perturbation_step_matches_python_control():
    spec = make_spec(duration=4.0, dt=0.001, perturbation={"value": 3.0, "time": 1.5})
    design = design_of(spec)
    res = simulate(spec, design)
    assert res.settings["perturbation"]["time_applied"] == pytest.approx(1.5)
    # Superposition of two exact linear responses (constant inputs): the step, and xi from 1.5 s.
    expected = linear_response(design, res.time, res.reference)[0][:, 0]
    after = res.time >= 1.5 - 1e-12
    t_after = res.time[after] - res.time[after][0]
    x_xi = linear_response(design, t_after, np.zeros((t_after.size, 3)), np.full(t_after.size, 3.0))[0][:, 0]
    expected[after] += x_xi
    assert np.max(np.abs(x_xi)) > 1e-2
    assert scaled_error(res.position, expected) < TOL["rk4_vs_exact"]


def test_tracking_error_response_to_a_xi_step_is_Km_over_tau_s_over_poles():
    spec = make_spec(TRACKING, duration=2.5, dt=0.001, trajectory=QUINTIC, perturbation={"value": 2.0, "time": 0.5})
    design = design_of(spec)
    res = simulate(spec, design)
    s = control.tf("s")
    p1, p2, p3 = design.poles
    f2 = (2.0 / 0.5) * s / ((s - p1.real) * (s - p2.real) * (s - p3.real))
    after = res.time >= 0.5 - 1e-12
    _, expected = control.step_response(f2, T=res.time[after] - res.time[after][0])
    assert np.max(np.abs(res.tracking_error[~after])) < 1e-9
    assert np.max(np.abs(expected)) > 1e-3
    assert scaled_error(res.tracking_error[after], 2.0 * expected) < TOL["rk4_vs_exact"]


# ----------------------------------------------------------------------------- anti-windup


def test_integral_saturation_bounds_the_integral_and_reduces_overshoot():
    # |K3 K4 xD| = 16.7 N*m is what the integral must hold at rest: the bound must exceed it.
    base = {"duration": 6.0, "nonlinearity": {"kind": "saturation", "limit": 5.0}}
    design = design_of(make_spec(**base))
    wound = simulate(make_spec(**base), design)
    clamping = make_spec(**base, anti_windup={"kind": "saturation", "value": 20.0})
    clamped = simulate(clamping, design_of(clamping))  # the anti-windup is part of the designed law
    k3 = design.gains["K3"]
    assert np.max(np.abs(k3 * wound.controller_state)) > 22.0
    assert np.max(np.abs(k3 * clamped.controller_state)) <= 20.0 + 1e-9
    assert overshoot(clamped.position, 1.0) < overshoot(wound.position, 1.0) - 3.0
    assert abs(clamped.tracking_error[-1]) < 1e-3 and abs(wound.tracking_error[-1]) < 1e-3


def test_integral_threshold_freezes_integration_far_from_the_target():
    base = {"duration": 6.0, "nonlinearity": {"kind": "saturation", "limit": 5.0}}
    design = design_of(make_spec(**base))
    wound = simulate(make_spec(**base), design)
    gating = make_spec(**base, anti_windup={"kind": "threshold", "value": 0.5})
    gated = simulate(gating, design_of(gating))
    far = np.abs(gated.tracking_error) > 0.5 + 1e-3
    assert far[0] and np.all(gated.controller_state[: np.argmin(far)] == 0.0)
    assert overshoot(gated.position, 1.0) < overshoot(wound.position, 1.0) - 3.0
    assert abs(gated.tracking_error[-1]) < 1e-3


# ----------------------------------------------------------------------------- noise, elements in the loop


def test_noise_is_reproducible_by_seed():
    def run(seed):
        spec = make_spec(duration=1.0, noise={"std": 1e-3, "seed": seed})
        return simulate(spec, design_of(spec))

    a, b, c = run(7), run(7), run(8)
    np.testing.assert_array_equal(a.state, b.state)
    np.testing.assert_array_equal(a.measured, b.measured)
    assert not np.array_equal(a.measured, c.measured) and not np.array_equal(a.state, c.state)
    noise = a.measured - a.state
    assert 0.8e-3 < np.std(noise) < 1.2e-3


@pytest.mark.parametrize(
    ("nonlinearity", "check"),
    [
        ({"kind": "relay", "amplitude": 20.0, "hysteresis": 0.5},
         lambda r: set(np.unique(r.u_applied)) <= {-20.0, 0.0, 20.0}),
        ({"kind": "quantizer", "step": 0.25},
         lambda r: np.allclose(r.u_applied / 0.25, np.round(r.u_applied / 0.25), atol=1e-9)),
        ({"kind": "dead_zone", "width": 1.0},
         lambda r: np.allclose(r.u_applied, np.sign(r.u_command) * np.maximum(np.abs(r.u_command) - 1.0, 0.0))),
    ],
    ids=["relay", "quantizer", "dead_zone"],
)
def test_element_in_the_loop(nonlinearity, check):
    spec = make_spec(duration=3.0, nonlinearity=nonlinearity)
    res = simulate(spec, design_of(spec))
    assert check(res)
    assert abs(res.position[-1] - 1.0) < 0.05


def test_result_is_complete_and_settings_are_json():
    spec = make_spec(TRACKING, trajectory={"kind": "sine", "amplitude": 0.5, "frequency": 0.5},
                     noise={"std": 1e-4, "seed": 2}, delay=0.004, sampling_period=0.002)
    res = simulate(spec, design_of(spec))
    n = res.time.size
    assert res.kind == "trajectory" and res.reference.shape == (n, 1, 3) and res.state.shape == (n, 2)
    assert res.controller_state.shape == (n, 1) and res.measured.shape == (n, 2)
    assert res.u_command.shape == res.u_applied.shape == res.perturbation.shape == (n, 1)
    settings = json.loads(json.dumps(res.settings))
    assert settings["steps_per_sample"] * settings["dt"] == pytest.approx(0.002)
    assert settings["delay_steps"] * settings["dt"] == pytest.approx(0.004)
    assert settings["noise"]["seed"] == 2 and settings["reference"]["kind"] == "sine"


def test_a_simulator_keeps_its_regime_and_reads_records_it_is_given():
    """``Simulator.regime`` is the loop's (a PID smooth, a relay law held per step); ``Simulator.result`` splits
    records laid out as the step writes them (x, xc, u_command, u_applied, y, d) into the result's signals."""
    from pathlib import Path

    import designkit as dk
    from designkit.simulation.integrate import run_steps
    from designkit.simulation.run import build

    specs = Path(__file__).resolve().parents[2] / "specs"
    pid = dk.load_spec(specs / "posspeed-link.yaml").spec
    sim = build(pid, dk.synthesize(pid))
    assert sim.regime.smooth and not sim.regime.held_law
    relay = dk.load_spec(specs / "vsc-link.yaml").spec
    assert not build(relay, dk.synthesize(relay)).regime.smooth
    rec = run_steps(sim.step, sim.z0, sim.inputs)
    res = sim.result(rec + 1.0)
    nx, nc, nu = 2, sim.law.n_state, 1
    assert np.array_equal(res.state, rec[:nx].T + 1.0)
    assert np.array_equal(res.controller_state, rec[nx:nx + nc].T + 1.0)
    assert np.array_equal(res.u_command, rec[nx + nc:nx + nc + nu].T + 1.0)
    assert res.time is sim.time and res.settings == sim.settings
