"""CVODES over the whole output grid (``numerics.integrator: cvodes`` on a smooth loop) against independent routes:
python-control's exact response of a linear PID link (a step, and a load step landed on exactly), scipy's DOP853
at rtol 1e-12 on the nonlinear SIMNOG arm, the exact solution ``q = qD`` of computed torque and the
Dormand-Prince run on a moving reference, the closed form of the stiff link; its error control, its method choice,
its failure on a diverging loop, and the interpreted functions against the compiled ones."""

from __future__ import annotations

import ctypes
from pathlib import Path

import control
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from designkit.errors import SpecError
from designkit.families import synthesize
from designkit.models.codegen import find_compiler
from designkit.schema.loader import load_spec, parse_spec
from designkit.schema.spec import Spec
from designkit.simulation.cvodes_grid import FIXED_POINT_RATIO, choose_method, failure_words
from designkit.simulation.run import build, simulate
from tests.simulation.helpers import design_of, make_spec, scaled_error

SPECS = Path(__file__).resolve().parents[2] / "specs"
needs_cc = pytest.mark.skipif(find_compiler() is None, reason="the compiled library is what these tests time and read")


def _with_numerics(spec: Spec, **numerics: object) -> Spec:
    return Spec.model_validate({**spec.model_dump(exclude={"numerics"}), "numerics": numerics})


def _cvodes(spec: Spec, **numerics: object) -> Spec:
    return _with_numerics(spec, integrator="cvodes", **numerics)


def _exact_link(design, t: np.ndarray, *, load: float = 0.0, at: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Position and command of the linear closed loop (inputs xD, xD', xD'', xi) to xD = 1 rad from t = 0 and a load
    ``xi = load`` from ``t[at]`` on, by python-control: two responses to constant inputs (each exact), the second
    from the state the first reaches at ``t[at]``."""
    cl = design.closed_loop
    sys = control.ss(cl.A, cl.B, cl.C, cl.D)
    at = t.size - 1 if at is None else at
    u1 = np.zeros((4, at + 1))
    u1[0] = 1.0
    first = control.forced_response(sys, T=t[:at + 1], U=u1, X0=np.zeros(cl.A.shape[0]), return_x=True)
    if at == t.size - 1:
        return first.outputs[0], first.outputs[1]
    u2 = np.zeros((4, t.size - at))
    u2[0], u2[3] = 1.0, load
    second = control.forced_response(sys, T=t[at:] - t[at], U=u2, X0=first.states[:, -1], return_x=True)
    return (np.concatenate([first.outputs[0][:-1], second.outputs[0]]),
            np.concatenate([first.outputs[1][:-1], second.outputs[1]]))


# ----------------------------------------------------------------------------- the method


def test_the_method_follows_the_stiffness_and_the_spread_of_the_poles():
    stiff = choose_method("auto", 1e6, 2.0)  # the stiff link: -1e6 against -1, -2
    assert (stiff.name, stiff.iteration) == ("bdf", "newton") and "stiff" in stiff.why
    calm = choose_method("auto", 20.0, 20.0)  # computed torque: every pole at -20
    assert (calm.name, calm.iteration) == ("adams", "functional") and "no Jacobian" in calm.why
    spread = choose_method("auto", 162.0, 5.0)  # SIMNOG's PID: one pole at -162, the others near -5
    assert (spread.name, spread.iteration) == ("adams", "newton")
    assert choose_method("auto", FIXED_POINT_RATIO * 5.0, 5.0).iteration == "functional"
    assert choose_method("adams", 1e6, 2.0).name == "adams" and choose_method("bdf", 1.0, 1.0).name == "bdf"
    assert choose_method("auto", 3.0, 0.0).iteration == "newton"  # no median known: the safe iteration
    with pytest.raises(ValueError, match="cvodes method"):
        choose_method("rk45", 1.0, 1.0)


def test_a_bad_cvodes_method_is_refused_naming_the_key():
    with pytest.raises(SpecError) as info:
        parse_spec("name: x\nplant: {kind: link, Km: 2, tau: 0.5}\n"
                   "controller: {kind: pid_servo, poles: [-4, -5, -20], zero: -3}\nnumerics: {cvodes_method: rk45}\n")
    assert info.value.path == "numerics.cvodes_method"


def test_a_cvodes_failure_is_said_in_words():
    words = failure_words('Error in Function::call for \'dk_cvodes\' [CvodesInterface] at .../cvodes_interface.cpp:403:'
                          ' CVode returned "CV_TOO_MUCH_WORK". Consult CVODES documentation.')
    assert words == "CVODES returned CV_TOO_MUCH_WORK: more than 10,000 steps between two grid points"


# ----------------------------------------------------------------------------- against independent routes


@needs_cc
@pytest.mark.parametrize("method", ["auto", "bdf"])
def test_a_pid_link_matches_python_control(method):
    """POSSPEED link servo (linear), step of 1 rad: one CVODES call over the grid equals python-control's exact
    response within its tolerances; the settings say what ran and the work it took."""
    spec = _cvodes(make_spec(duration=3.0), rtol=1e-10, atol=1e-12, cvodes_method=method)
    design = design_of(spec)
    sim = build(spec, design)
    assert sim.cvodes is not None
    res = sim.run()
    x1, u = _exact_link(design, res.time)
    assert scaled_error(res.position, x1) < 1e-8
    assert scaled_error(res.u_command[:, 0], u) < 1e-6
    words = res.settings["integrator"]
    assert words.startswith("cvodes (CVODES over the whole output grid in one call")
    assert ("BDF" if method == "bdf" else "Adams-Moulton") in words and "rtol 1e-10, atol 1e-12" in words
    work = res.settings["integrator_work"]
    assert "evaluations of the right-hand side" in work and "CVODES steps" in work and "3,000 output steps" in work
    assert sim.compiled["integrator"] == "cvodes" and sim.compiled["compiled"]


@needs_cc
@pytest.mark.parametrize("method", ["auto", "bdf"])
def test_the_error_falls_with_the_tolerance(method):
    """Error control: the error against the exact response falls by more than ten times per two decades of rtol,
    from 1e-5 to 1e-11, and stays within a hundred times rtol."""
    base = make_spec(duration=3.0)
    design = design_of(base)
    errors = []
    for rtol in (1e-5, 1e-7, 1e-9, 1e-11):
        res = simulate(_cvodes(base, rtol=rtol, atol=rtol * 1e-2, cvodes_method=method), design)
        errors.append(scaled_error(res.position, _exact_link(design, res.time)[0]))
    assert all(e < 100 * r for e, r in zip(errors, (1e-5, 1e-7, 1e-9, 1e-11), strict=True)), errors
    assert all(a > 10 * b for a, b in zip(errors[:-1], errors[1:], strict=True)), errors


@needs_cc
@pytest.mark.parametrize("method", ["auto", "bdf"])
def test_a_load_step_is_landed_on_exactly(method):
    """A -5 N*m load from t = 1.5 s (a breakpoint): the run equals the exact piecewise response at the tolerance's
    level, as it can only if the jump acts exactly at 1.5 s (a jump smeared over one 1 ms step would leave an error
    of the order of its effect over that step, about 1e-6 rad), and CVODES starts afresh there (kept across the
    jump, the BDF's error test fails repeatedly at rtol 1e-10: CV_ERR_FAILURE)."""
    spec = _cvodes(make_spec(duration=3.0, perturbation={"value": -5.0, "time": 1.5}), rtol=1e-10, atol=1e-12,
                   cvodes_method=method)
    design = design_of(spec)
    res = simulate(spec, design)
    at = int(np.flatnonzero(res.time >= 1.5 - 1e-12)[0])
    assert res.time[at] == pytest.approx(1.5) and "integrator_failure" not in res.settings
    x1, u = _exact_link(design, res.time, load=-5.0, at=at)
    assert scaled_error(res.position, x1) < 1e-8
    assert scaled_error(res.u_command[:, 0], u) < 1e-6
    assert res.perturbation[at - 1, 0] == 0.0 and res.perturbation[at, 0] == -5.0
    assert "CVODES started afresh at the breakpoint" in res.settings["integrator_work"]


def _simnog(method: str) -> Spec:
    spec = load_spec(SPECS / "simnog-decentralized-pid.yaml").spec
    return Spec.model_validate({**spec.model_dump(exclude={"simulation", "numerics"}),
                                "simulation": {**spec.simulation.model_dump(exclude_unset=True), "duration": 2.0},
                                "numerics": {"integrator": "cvodes", "rtol": 1e-10, "atol": 1e-12,
                                             "cvodes_method": method}})


@pytest.fixture(scope="module")
def simnog_scipy() -> tuple[np.ndarray, np.ndarray]:
    """``(time, states)`` of SIMNOG's 2 s by scipy's DOP853 at rtol 1e-12 on the same right-hand side, integrated
    from the plant's ODE and the law's functions."""
    spec = _simnog("auto")
    sim = build(spec, synthesize(spec))
    plant, law = sim.plant, sim.law
    ode, p = plant.ode(), np.asarray(plant.parameter_vector, dtype=float)
    nx, nc, nref = len(plant.states), law.n_state, 3 * len(plant.positions)
    r = sim.inputs[:nref, 1]  # the step's target, constant after t = 0
    assert np.all(sim.inputs[:nref, 1:] == r[:, None])
    empty = np.zeros(0)

    def rhs(t: float, s: np.ndarray) -> np.ndarray:
        x, xc = s[:nx], s[nx:]
        u = law.command(x, xc, empty, r).full().ravel()
        gate = law.gate(x, xc, empty, r).full().ravel()
        return np.concatenate([ode(x, u, np.zeros(len(plant.disturbances)), p).full().ravel(),
                               law.derivative(x, xc, empty, r, gate).full().ravel()])

    sol = solve_ivp(rhs, (0.0, float(sim.time[-1])), sim.z0[:nx + nc], method="DOP853", t_eval=sim.time,
                    rtol=1e-12, atol=1e-14)
    assert sol.success
    return sim.time, sol.y.T


@needs_cc
@pytest.mark.parametrize("method", ["auto", "bdf"])
def test_simnog_pid_matches_scipy_at_tight_tolerance(method, simnog_scipy):
    """The nonlinear two-link arm under decentralized PID: the grid agrees with scipy's DOP853 at rtol 1e-12.  Its
    pole at -162 against a median of -5 makes auto take Adams with Newton iteration."""
    sim = build(_simnog(method), synthesize(_simnog(method)))
    assert sim.cvodes is not None
    assert sim.cvodes.method.iteration == "newton"
    assert sim.cvodes.method.name == ("bdf" if method == "bdf" else "adams")
    res = sim.run()
    time, exact = simnog_scipy
    np.testing.assert_array_equal(res.time, time)
    ours = np.hstack([res.state, res.controller_state])
    scale = 1.0 + np.abs(exact).max(axis=0)
    assert np.max(np.abs(ours[1:] - exact[1:]) / scale) < 1e-8  # t = 0: the step acts from there on


@needs_cc
def test_computed_torque_on_a_moving_reference_agrees_with_the_exact_solution_and_the_pair():
    """SIMNOG computed torque on the exact model along a quintic: the exact solution is q(t) = qD(t).  The reference
    inside each output interval is the same quadratic for CVODES and the Dormand-Prince pair, so the two runs agree
    within their tolerances; the poles all at -20 make auto take Adams with fixed-point iteration."""
    spec = load_spec(SPECS / "simnog-computed-torque.yaml").spec
    design = synthesize(spec)
    pair = simulate(spec, design)
    sim = build(_cvodes(spec, rtol=1e-10, atol=1e-12), design)
    assert sim.cvodes is not None and sim.cvodes.method.iteration == "functional"
    res = sim.run()
    q, qd = list(res.positions), list(res.velocities)
    assert np.abs(res.state[:, q] - res.reference[:, :, 0]).max() < 1e-10
    assert np.abs(res.state[:, qd] - res.reference[:, :, 1]).max() < 1e-9
    assert pair.settings["integrator"].startswith("dopri5")
    assert np.abs(res.state[:, q] - pair.state[:, q]).max() < 1e-9
    assert np.abs(res.state - pair.state).max() < 1e-8  # the pair's velocities are within 3e-9 of qD'
    assert sim.cvodes.stats["nlinsetups"] == 0  # fixed-point iteration: no Jacobian evaluated, none compiled
    assert "jacobian_flags" not in sim.compiled
    assert not hasattr(ctypes.CDLL(str(sim.cvodes.library)), "jacF")


@needs_cc
def test_the_stiff_link_runs_bdf_across_the_grid():
    """The stiff link (poles -1, -2, -1e6) by default: CVODES' BDF in one call, fewer steps than output steps (it
    steps across the grid; restarted at every output step it took several per step), the step response equal to the
    linear closed loop's (python-control) within its tolerances; Adams needs ten times the steps there."""
    spec = load_spec(SPECS / "stiff-link.yaml").spec
    design = synthesize(spec)
    sim = build(spec, design)
    assert sim.cvodes is not None and sim.cvodes.method.name == "bdf"
    res = sim.run()
    assert "BDF because the loop is stiff" in res.settings["integrator"]
    assert sim.cvodes.stats["nsteps"] < res.time.size - 1
    x1, _ = _exact_link(design, res.time)
    assert scaled_error(res.position, x1) < 1e-6  # rtol 1e-8, atol 1e-10 by default
    bdf_steps = sim.cvodes.stats["nsteps"]
    adams = build(_with_numerics(spec, cvodes_method="adams"), design)
    adams.run()
    assert adams.cvodes.stats["nsteps"] > 5 * bdf_steps


# ----------------------------------------------------------------------------- failure, evaluation, scope


@needs_cc
def test_a_diverging_loop_ends_with_nan_records_and_the_reason():
    """mrac-gamma-unstable diverges (its adaptation gain is too high): CVODES gives up (too much work between two
    grid points); the records are finite up to the failure and NaN from there, and the settings say where and why."""
    spec = _cvodes(load_spec(SPECS / "mrac-gamma-unstable.yaml").spec)
    sim = build(spec, synthesize(spec))
    assert sim.cvodes is not None
    res = sim.run()
    failure = res.settings["integrator_failure"]
    assert failure.startswith("the integrator stopped at t = ") and "CVODES returned CV_TOO_MUCH_WORK" in failure
    t_fail = float(failure.split("t = ")[1].split(" s")[0])
    k = int(np.argmin(np.abs(res.time - t_fail)))
    assert 0 < k < res.time.size - 1
    assert np.isfinite(res.state[:k]).all() and np.isnan(res.state[k:]).all()
    assert np.isnan(res.u_command[k:]).all()
    assert "counted up to the last grid point reached" in res.settings["integrator_work"]


@needs_cc
def test_the_interpreted_functions_give_the_compiled_run():
    """numerics.compile: never runs the same integrator on CasADi's interpreted functions; the generated C computes
    the same operations (no fused multiply-add), so the runs are identical."""
    spec = _cvodes(make_spec(duration=3.0, perturbation={"value": -5.0, "time": 1.5}), cvodes_method="bdf")
    design = design_of(spec)
    compiled, interpreted = build(spec, design), build(_with_numerics(spec, integrator="cvodes", compile="never",
                                                                      cvodes_method="bdf"), design)
    assert compiled.cvodes.library is not None and interpreted.cvodes.library is None
    a, b = compiled.run(), interpreted.run()
    assert "interpreted: numerics.compile: never" in b.settings["integrator"]
    np.testing.assert_array_equal(b.state, a.state)
    np.testing.assert_array_equal(b.u_command, a.u_command)


@needs_cc
def test_a_run_on_other_parameters_uses_them():
    """Simulator.run(parameters=...) on the whole-grid path: the true plant's parameters change the response, as
    python-control's response of the loop designed for the other plant shows (the law is the nominal design's, so
    the reference is the nominal design on the other plant: compared with the same run from a fresh build)."""
    spec = _cvodes(make_spec(duration=2.0), rtol=1e-10, atol=1e-12)
    design = design_of(spec)
    sim = build(spec, design)
    other = sim.run(parameters={"Km": 2.4, "tau": 0.6})
    fresh = simulate(spec, design, plant=design.plant.with_params(Km=2.4, tau=0.6))
    np.testing.assert_allclose(other.state, fresh.state, rtol=0, atol=1e-12)
    assert np.abs(other.state - sim.run().state).max() > 1e-3


def test_a_held_loop_keeps_cvodes_inside_each_step_and_ignores_the_method():
    relay = make_spec(duration=1.0, nonlinearity={"kind": "relay", "amplitude": 5.0, "hysteresis": 0.01})
    sim = build(_cvodes(relay, cvodes_method="adams"), design_of(relay))
    assert sim.cvodes is None
    assert sim.settings["integrator"].startswith("cvodes (variable-step BDF inside each step")
    assert any(item.startswith("numerics.cvodes_method") for item in sim.settings["ignored"])
