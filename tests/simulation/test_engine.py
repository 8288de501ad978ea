"""The simulation engine beyond the link PIDs: any plant, laws with a discrete memory, the variable-step
integrator, repeated trials."""

from __future__ import annotations

import casadi as ca
import control
import numpy as np
import pytest
from scipy.signal import place_poles

from designkit.models.elastic import ElasticJointPlant, elastic_state_space
from designkit.models.robots.elastic_link import DEFAULTS, elastic_link
from designkit.schema.spec import Spec
from designkit.simulation.run import build, simulate
from designkit.simulation.trials import run_trials
from designkit.synthesis.design import Design, Gain, Gains
from designkit.synthesis.law import Law, law_symbols
from tests.simulation.helpers import TRACKING, design_of, make_spec
from tests.tolerances import TOL

# ----------------------------------------------------------------------------- a law with memory


def _discrete_pi_law(design: Design, Ts: float) -> Law:
    """The PID servo with its integral kept in the law's discrete memory: ``m <- m + Ts (y1 - xD)``."""
    K1, K2, K3, K4 = (float(design.gains[k]) for k in ("K1", "K2", "K3", "K4"))
    y, xc, m, r = law_symbols(2, 0, 1, 1)
    e = y[0] - r[0]
    args, names = [y, xc, m, r], ["y", "xc", "m", "r"]
    g = ca.SX.sym("gate", 0)
    return Law(
        kind="discrete_pi", state_names=(), memory_names=("integral",), initial_memory=(0.0,),
        command=ca.Function("dpi_command", args, [-K1 * e - K2 * y[1] - K3 * m[0] + K3 * K4 * r[0]], names, ["u"]),
        derivative=ca.Function("dpi_derivative", [*args, g], [ca.SX(0, 1)], [*names, "gate"], ["xc_dot"]),
        gate=ca.Function("dpi_gate", args, [ca.SX(0, 1)], names, ["gate"]),
        project=ca.Function("dpi_project", [xc], [xc], ["xc"], ["xc_projected"]),
        update=ca.Function("dpi_update", args, [m + Ts * e], names, ["m_next"]),
    )


def test_memory_law_equals_the_sampled_pid_with_a_held_integrand():
    """Two implementations of the same digital PID: the built-in sampled servo (continuous integral state
    whose derivative is held over the sampling period) and a law keeping the integral in its memory."""
    spec = make_spec(duration=1.5, dt=0.001, sampling_period=0.01)
    design = design_of(spec)
    builtin = simulate(spec, design)
    memory = build(spec, design, law=_discrete_pi_law(design, 0.01)).run()
    np.testing.assert_allclose(memory.u_command, builtin.u_command, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(memory.state, builtin.state, rtol=1e-9, atol=1e-12)


def test_continuous_memory_updates_every_step():
    spec = make_spec(duration=0.5, dt=0.001)
    design = design_of(spec)
    law = _discrete_pi_law(design, 0.001)  # updated every integration step: a rectangle-rule integral
    res = build(spec, design, law=law).run()
    continuous = simulate(spec, design)
    assert np.max(np.abs(res.position - continuous.position)) < 1e-3  # first-order integral vs the exact one


# ----------------------------------------------------------------------------- the elastic joint


def _elastic_design(plant: ElasticJointPlant, poles) -> Design:
    A, B = elastic_state_space(plant.params)
    K = place_poles(A, B, poles).gain_matrix
    return Design(kind="pid_servo", plant=plant, gains=Gains.of([Gain("K", K[0], "input/rad")]), poles=tuple(poles),
                  reference="step")


def _state_feedback(design: Design) -> Law:
    """``u = -K (x - x_ref)`` with ``x_ref = (xD, 0, xD, 0)`` (rest at the reference, spring unstretched)."""
    K = np.asarray(design.gains["K"], dtype=float)
    y, xc, m, r = law_symbols(4, 0, 0, 1)
    x_ref = ca.vertcat(r[0], 0, r[0], 0)
    args, names = [y, xc, m, r], ["y", "xc", "m", "r"]
    g = ca.SX.sym("gate", 0)
    return Law(
        kind="state_feedback", state_names=(),
        command=ca.Function("sf_command", args, [-ca.mtimes(ca.DM(K).T, y - x_ref)], names, ["u"]),
        derivative=ca.Function("sf_derivative", [*args, g], [ca.SX(0, 1)], [*names, "gate"], ["xc_dot"]),
        gate=ca.Function("sf_gate", args, [ca.SX(0, 1)], names, ["gate"]),
        project=ca.Function("sf_project", [xc], [xc], ["xc"], ["xc_projected"]),
        update=ca.Function("sf_update", args, [m], names, ["m_next"]),
    )


def _elastic_spec(integrator: str, dt: float) -> Spec:
    # no family is designed for the elastic joint yet: the spec only carries the scenario and the numerics,
    # the plant and the law are given to build() directly
    return Spec.model_validate({
        "name": "elastic", "plant": {"kind": "link", "Km": 1.0, "tau": 1.0},
        "controller": {"kind": "pid_servo", "poles": [-4, -5, -20]},
        "simulation": {"duration": 1.0, "dt": dt, "step": 0.5},
        "numerics": {"integrator": integrator, "rtol": 1e-10, "atol": 1e-12},
    })


def test_elastic_joint_under_state_feedback_matches_the_linear_model_with_both_integrators():
    plant = ElasticJointPlant(DEFAULTS)  # mgl = 0: the plant is linear
    poles = [-20.0, -25.0, -30 + 10j, -30 - 10j]
    design = _elastic_design(plant, poles)
    law = _state_feedback(design)
    A, B = elastic_state_space(plant.params)
    K = np.asarray(design.gains["K"])
    Ak = A - B @ K[None, :]
    Bk = B @ (K[None, :] @ np.array([[1.0], [0.0], [1.0], [0.0]]))  # the reference enters through x_ref
    rk4 = build(_elastic_spec("rk4", 1e-4), design, law=law).run()
    cvodes = build(_elastic_spec("cvodes", 1e-3), design, law=law).run()
    for res in (rk4, cvodes):
        resp = control.forced_response(control.ss(Ak, Bk, np.eye(4), 0), T=res.time, U=np.full(res.time.size, 0.5))
        ref = np.asarray(resp.outputs).T
        assert np.max(np.abs(res.state - ref)) < TOL["cvodes"] * np.max(np.abs(ref)) + 1e-9
    assert "cvodes" in cvodes.settings["integrator"]


def test_elastic_joint_with_gravity_agrees_between_integrators():
    plant = ElasticJointPlant(elastic_link(mgl=5.0))
    design = _elastic_design(plant, [-20.0, -25.0, -30 + 10j, -30 - 10j])
    law = _state_feedback(design)
    fine = build(_elastic_spec("rk4", 1e-4), design, law=law).run()
    variable = build(_elastic_spec("cvodes", 1e-3), design, law=law).run()
    np.testing.assert_allclose(variable.state, fine.state[::10], atol=0.1 * TOL["cvodes"])
    assert abs(fine.joint_positions[-1, 0] - 0.5) > 1e-3  # gravity leaves an offset without integral action


# ----------------------------------------------------------------------------- repeated trials


def test_learning_between_trials_reduces_the_tracking_error():
    """A D-type learning rule on the velocity error, u_{k+1} = u_k + g (xD' - x2): for the link the first
    Markov parameter from u to x2 is Km/tau = 4, so g = 0.2 contracts the velocity error (|1 - 4 g| = 0.2 < 1);
    the position error follows, more slowly."""
    spec = make_spec({**TRACKING, "poles": [-1, -1.2, -1.5]}, duration=2.0, dt=0.001,
                     trajectory={"kind": "sine", "amplitude": 0.5, "frequency": 1.0})
    design = design_of(spec)
    simulator = build(spec, design)

    def learn(res, ff):
        return ff + 0.2 * (res.reference[:, :, 1] - res.state[:, list(res.velocities)])

    out = run_trials(simulator, 8, learn)
    rms = out.rms_tracking_errors
    assert len(out.results) == 8 and np.all(out.feedforward[0] == 0.0)
    assert np.all(np.diff(rms) < 0), rms
    assert rms[-1] < 0.6 * rms[0]
    np.testing.assert_array_equal(out.results[0].state, simulator.run().state)  # trial 0 is the plain run
    with pytest.raises(ValueError, match="shape"):
        run_trials(simulator, 2, lambda res, ff: ff[:-1])


# ----------------------------------------------------------------------------- compiled evaluation


def test_compiled_step_gives_the_interpreted_numbers(tmp_path, monkeypatch):
    from designkit.models.codegen import find_compiler

    if find_compiler() is None:
        pytest.skip("no C compiler on PATH: the compiled path cannot be exercised here")
    monkeypatch.setenv("DESIGNKIT_CACHE_DIR", str(tmp_path))
    # long enough (20,000 steps) for auto to look the library up; the rolled RK4 step (the default for a
    # smooth loop, the Dormand-Prince pair, always runs compiled: tests/simulation/test_dopri5.py)
    base = {"duration": 20.0, "dt": 0.001, "nonlinearity": {"kind": "saturation", "limit": 20.0}}
    never = Spec.model_validate({**make_spec(**base).model_dump(), "numerics": {"compile": "never",
                                                                              "integrator": "rk4"}})
    always = Spec.model_validate({**make_spec(**base).model_dump(), "numerics": {"compile": "always",
                                                                               "integrator": "rk4"}})
    design = design_of(never)
    a, b = build(never, design), build(always, design)
    assert a.compiled["compiled"] is False and b.compiled["compiled"] is True
    np.testing.assert_array_equal(a.run().state, b.run().state)  # -O1, no FMA: bit for bit
    auto = Spec.model_validate({**make_spec(**base).model_dump(), "numerics": {"compile": "auto", "integrator": "rk4"}})
    assert build(auto, design).compiled["why"] == "cached library"  # the library is reused
    short = Spec.model_validate({**make_spec(duration=0.5).model_dump(), "numerics": {"compile": "auto",
                                                                                     "integrator": "rk4"}})
    assert build(short, design).compiled["compiled"] is False  # nothing to gain on a short run


# ----------------------------------------------------------------------------- parameters as an input


def test_run_with_other_parameters_equals_a_simulator_built_on_that_plant():
    spec = make_spec(duration=1.0, dt=0.001)
    design = design_of(spec)
    other = design.plant.with_params(Km=2.6, tau=0.45)
    swept = build(spec, design).run(parameters={"Km": 2.6, "tau": 0.45})
    built = simulate(spec, design, plant=other)
    np.testing.assert_array_equal(swept.state, built.state)
    assert dict(swept.settings["plant"]) == {"Km": 2.6, "tau": 0.45}
    with pytest.raises(Exception, match="Km"):
        build(spec, design).run(parameters={"Km": -1.0})
