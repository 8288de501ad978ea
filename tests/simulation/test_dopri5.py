"""The compiled Dormand-Prince 5(4) pair (the default integrator of a smooth loop) against independent routes:
python-control on a linear loop, scipy's DOP853 at rtol 1e-12 on the nonlinear SIMNOG arm, the exact solution
of computed torque on an exact model; its error control; the step rule's tolerance to rounded poles."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from designkit.errors import SpecError
from designkit.families import synthesize
from designkit.models.codegen import find_compiler
from designkit.schema.loader import load_spec
from designkit.schema.spec import Spec
from designkit.simulation.linear import linear_response
from designkit.simulation.run import build, simulate
from designkit.simulation.timing import rates_of, resolve
from tests.simulation.helpers import design_of, make_spec, scaled_error

SPECS = Path(__file__).resolve().parents[2] / "specs"
needs_cc = pytest.mark.skipif(find_compiler() is None, reason="the Dormand-Prince pair runs compiled only")


def _with_numerics(spec: Spec, **numerics: object) -> Spec:
    return Spec.model_validate({**spec.model_dump(exclude={"numerics"}), "numerics": numerics})


# ----------------------------------------------------------------------------- the step rule


@pytest.mark.parametrize(("rate", "dt"), [(20.0000004, 1e-3), (19.9999996, 1e-3), (20.001, 5e-4)])
def test_the_step_rule_reads_a_rounded_double_pole_as_the_round_value(rate, dt):
    """A double pole at -20 computed as 20.0000004 (a double root carries ~sqrt(eps) relative error) gives the
    step of 20 (0.02 / 20 = 1 ms), not half of it; a rate that is really faster (20.001) still halves it."""
    spec = make_spec(duration=3.0)
    timing = resolve(spec, rates_of([complex(-rate), complex(-rate)]), 0.0)
    assert timing.dt == pytest.approx(dt, rel=1e-12)


# ----------------------------------------------------------------------------- against independent routes


@needs_cc
def test_the_pair_is_the_default_of_a_smooth_loop_and_matches_python_control():
    """POSSPEED link servo (linear): the default run is the pair, and equals python-control's exact response
    to the step within its error control; the settings state the tolerances and the work."""
    spec = make_spec(duration=3.0)
    design = design_of(spec)
    res = simulate(spec, design)
    assert res.settings["integrator"].startswith("dopri5") and "rtol 1e-10, atol 1e-12" in res.settings["integrator"]
    assert "evaluations" in res.settings["integrator_work"]
    x1, u = linear_response(design, res.time, res.reference)
    assert scaled_error(res.position, x1[:, 0]) < 1e-9
    assert scaled_error(res.u_command[:, 0], u[:, 0]) < 1e-7


@needs_cc
def test_the_error_shrinks_with_the_tolerance():
    """Error control: the error against the exact (python-control) response falls with rtol, staying within a
    small multiple of it, from 1e-5 to 1e-11."""
    base = make_spec(duration=3.0)
    design = design_of(base)
    errors = []
    for rtol in (1e-5, 1e-7, 1e-9, 1e-11):
        res = simulate(_with_numerics(base, rtol=rtol, atol=rtol * 1e-2), design)
        assert f"rtol {rtol:g}" in res.settings["integrator"]
        x1, _ = linear_response(design, res.time, res.reference)
        errors.append(scaled_error(res.position, x1[:, 0]))
    assert all(e < 50 * r for e, r in zip(errors, (1e-5, 1e-7, 1e-9, 1e-11), strict=True)), errors
    assert all(a > 10 * b for a, b in zip(errors[:-1], errors[1:], strict=True)), errors


@needs_cc
def test_simnog_pid_matches_scipy_dop853_at_tight_tolerance():
    """The nonlinear two-link arm under decentralized PID: the pair's grid agrees with scipy's DOP853 (rtol 1e-12)
    on the same right-hand side, integrated by scipy from the plant's ODE and the law's functions."""
    spec = load_spec(SPECS / "simnog-decentralized-pid.yaml").spec
    spec = Spec.model_validate({**spec.model_dump(exclude={"simulation", "numerics"}),
                                "simulation": {**spec.simulation.model_dump(exclude_unset=True), "duration": 2.0}})
    design = synthesize(spec)
    sim = build(spec, design)
    assert sim.dopri5 is not None
    res = sim.run()
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

    sol = solve_ivp(rhs, (0.0, float(res.time[-1])), sim.z0[:nx + nc], method="DOP853", t_eval=res.time,
                    rtol=1e-12, atol=1e-14)
    assert sol.success
    ours = np.hstack([res.state, res.controller_state])
    scale = 1.0 + np.abs(sol.y.T).max(axis=0)
    assert np.max(np.abs(ours[1:] - sol.y.T[1:]) / scale) < 1e-8  # t = 0: the step is applied from there on


@needs_cc
def test_computed_torque_on_an_exact_model_follows_the_reference_to_the_tolerance():
    """SIMNOG computed torque with the exact model: the exact solution is q(t) = qD(t) along the quintic."""
    spec = load_spec(SPECS / "simnog-computed-torque.yaml").spec
    res = simulate(spec, synthesize(spec))
    assert res.settings["integrator"].startswith("dopri5")
    assert np.abs(res.state[:, list(res.positions)] - res.reference[:, :, 0]).max() < 1e-8


# ----------------------------------------------------------------------------- what stays on RK4


def test_a_held_or_rough_loop_stays_on_rk4_and_an_explicit_pair_there_is_refused():
    relay = make_spec(duration=2.0, nonlinearity={"kind": "relay", "amplitude": 5.0, "hysteresis": 0.01})
    res = simulate(relay, design_of(relay))
    assert res.settings["integrator"].startswith("rk4") and "relay" in res.settings["integrator_choice"]
    with pytest.raises(SpecError) as info:
        simulate(_with_numerics(relay, integrator="dopri5"), design_of(relay))
    assert info.value.path == "numerics.integrator" and "relay" in info.value.message


@needs_cc
@pytest.mark.parametrize(("layer", "smooth"), [(0.0, True), (0.05, False)])
def test_coulomb_friction_is_smooth_only_when_the_law_cancels_it(layer, smooth):
    """The PUMA's Fc sign(q̇) is a jump at rest; computed torque on the exact model compensates it with the same
    sign (controller.friction_layer 0), so the loop is continuous there and runs the pair; a smoothed
    compensation (a 0.05 rad/s layer) leaves the jump in the loop (a stick at rest), which stays on RK4."""
    base = load_spec(SPECS / "puma560-computed-torque.yaml").spec
    data = base.model_dump(exclude={"numerics"}, exclude_unset=True)
    data["controller"] = {**data["controller"], "friction_layer": layer}
    data["simulation"] = {**data["simulation"], "duration": 0.5}
    spec = Spec.model_validate(data)
    sim = build(spec, synthesize(spec))
    assert (sim.dopri5 is not None) is smooth
    assert "Coulomb" in sim.settings["integrator_choice"]
    if smooth:
        res = sim.run()
        assert np.abs(res.state[:, list(res.positions)] - res.reference[:, :, 0]).max() < 1e-8  # q = qD exactly


@needs_cc
def test_explicit_rk4_stays_selectable():
    spec = _with_numerics(make_spec(duration=1.0), integrator="rk4")
    res = simulate(spec, design_of(spec))
    assert res.settings["integrator"].startswith("rk4") and "integrator_work" not in res.settings


@needs_cc
def test_the_interpreted_driver_gives_the_compiled_run():
    """numerics.compile: never runs the same algorithm in Python on CasADi's interpreted functions (the C driver
    and the Python one are two writings of one algorithm: they agree to rounding, amplified only by the error
    control's choice of steps)."""
    spec = load_spec(SPECS / "simnog-computed-torque.yaml").spec
    design = synthesize(spec)
    compiled = build(spec, design)
    interpreted = build(_with_numerics(spec, compile="never"), design)
    assert compiled.dopri5.library is not None and interpreted.dopri5.library is None
    a, b = compiled.run(), interpreted.run()
    assert "interpreted: numerics.compile: never" in b.settings["integrator"]
    np.testing.assert_allclose(b.state, a.state, rtol=0, atol=1e-8)


@needs_cc
def test_a_diverging_loop_is_integrated_again_by_rk4_and_says_so():
    """mrac-gamma-unstable diverges: the pair's step collapses; the run is repeated by RK4 on the grid, so every
    state is recorded as far as it stays finite (the reference model's stays finite throughout)."""
    from designkit.pipeline import run

    result = run(load_spec(SPECS / "mrac-gamma-unstable.yaml"))
    sim = result.simulation
    assert "the Dormand-Prince pair stopped at t =" in sim.settings["integrator"]
    assert sim.settings["integrator"].startswith("rk4")
    assert not np.all(np.isfinite(sim.state)) or "integrator_failure" in sim.settings or np.abs(sim.state).max() > 1e3


@needs_cc
def test_a_library_removed_from_the_cache_after_the_build_still_runs(tmp_path, monkeypatch):
    """The cache folder is shared with other processes, whose pruning removes the oldest libraries: a simulator
    built on a library keeps it loaded, so removing the file afterwards changes nothing."""
    monkeypatch.setenv("DESIGNKIT_CACHE_DIR", str(tmp_path))
    spec = make_spec(duration=1.0)
    sim = build(spec, design_of(spec))
    assert sim.dopri5 is not None and sim.dopri5.library is not None
    assert sim.dopri5.library.parent == tmp_path / "codegen"
    for so in (tmp_path / "codegen").glob("*.so"):
        so.unlink()
    assert not sim.dopri5.library.exists()
    ran = sim.run()
    assert np.all(np.isfinite(ran.position)) and ran.position[-1] != 0.0
