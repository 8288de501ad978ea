"""Stiff and extremely slow but stable designs are simulated and verified, not refused.

The integrator, the output step and the default duration are chosen from the poles
(:mod:`designkit.simulation.timing`): a loop whose RK4 grid would exceed the step bound because of
a pole far faster than the others runs on CVODES with an output step set by the other poles; a
default duration made astronomical by a pole near zero is cut and the settings say the run does
not reach steady state.  The step-count limit remains a resource bound naming the field to change.
"""

from __future__ import annotations

import json
from pathlib import Path

import casadi as ca
import numpy as np
import pytest
import scipy.signal

import designkit as dk
from designkit.cli import main
from designkit.errors import SpecError
from designkit.schema.spec import Spec
from designkit.simulation.integrate import run_steps
from designkit.simulation.run import simulate
from designkit.simulation.timing import CAPPED_STEPS, MAX_STEPS, rates_of, resolve
from tests.cli_input import assert_bad_input
from tests.simulation.helpers import design_of

LINK = "plant: {kind: link, Km: 2, tau: 0.5}\n"
STIFF = "controller: {kind: pid_servo, poles: [-1, -2, -1e6], zero: -3}\n"
REQUIREMENTS = "requirements: {overshoot: 1, settling_time: 5, steady_state_error: 0.001}\n"


def _write(tmp_path: Path, text: str, name: str = "spec") -> Path:
    path = tmp_path / f"{name}.yaml"
    path.write_text(f"name: {name}\n{LINK}{text}")
    return path


def _spec(controller: dict, **sections: dict) -> Spec:
    return Spec.model_validate({"name": "stiff", "plant": {"kind": "link", "Km": 2.0, "tau": 0.5},
                                "controller": controller, **sections})


def _closed_form_step(poles: list[float], zero: float, t: np.ndarray) -> np.ndarray:
    """Step response of ``k (s - z) / prod(s - p_i)`` with unit DC gain, by partial fractions (real, distinct
    poles): ``y = 1 + sum_i r_i exp(p_i t)``, ``r_i = k (p_i - z) / (p_i prod_{j != i} (p_i - p_j))``.

    For the servo ``x1/xD = (Km/tau) ((K1 + K3 K4) s + K3) / det(sI - A)``: the poles are the requested
    ones and the zero ``-K3/(K1 + K3 K4)`` the requested zero, whatever the gains.
    """
    p = np.asarray(poles, dtype=float)
    k = np.prod(-p) / -zero
    y = np.ones_like(t)
    for i, pi in enumerate(p):
        others = np.prod([pi - pj for j, pj in enumerate(p) if j != i])
        y = y + k * (pi - zero) / (pi * others) * np.exp(pi * t)
    return y


# ----------------------------------------------------------------------------- the choice of integrator


def test_stiff_rates_choose_cvodes_with_the_output_step_of_the_slow_poles():
    spec = _spec({"kind": "pid_servo", "poles": [-1, -2, -1e6], "zero": -3})
    rates = rates_of([-1, -2, -1e6], [-1, -2, -1e6])
    timing = resolve(spec, rates, 0.0)
    # RK4 would need dt = 0.02 / 1e6 = 2e-8 s over 10 / 1 = 10 s: 5e8 steps > MAX_STEPS
    assert timing.integrator == "cvodes"
    assert timing.dt == pytest.approx(0.02 / 2)  # the fastest non-stiff pole, -2 1/s
    assert timing.n_samples == 1001  # 10 s / 10 ms + 1
    assert timing.settings["stiff_rates"] == [1e6]
    assert "chosen: cvodes because the fastest pole |p| = 1e+06 1/s would need 500000000 RK4 steps" in \
        timing.settings["integrator_choice"]


def test_a_loop_within_the_bound_keeps_rk4_and_its_step():
    # 0.02/2000 = 1e-5 s over 10 s: 1e6 steps, within the bound although the pole is stiff by ratio
    timing = resolve(_spec({"kind": "pid_servo", "poles": [-1, -2, -2000]}), rates_of([-1, -2, -2000]), 0.0)
    assert timing.integrator == "rk4" and timing.dt == pytest.approx(1e-5)


def test_a_delay_holds_the_control_over_each_step_so_a_stiff_loop_stays_refused():
    spec = _spec({"kind": "pid_servo", "poles": [-1, -2, -1e6], "zero": -3}, simulation={"delay": 0.001})
    with pytest.raises(SpecError, match="held over each step") as err:
        resolve(spec, rates_of([-1, -2, -1e6]), 0.0, held_per_step=True)
    assert err.value.path == "simulation.duration"


def test_a_user_dt_too_coarse_for_rk4_on_a_stiff_loop_runs_on_cvodes():
    spec = _spec({"kind": "pid_servo", "poles": [-1, -2, -1e6], "zero": -3}, simulation={"dt": 0.05})
    timing = resolve(spec, rates_of([-1, -2, -1e6]), 0.0)
    assert timing.integrator == "cvodes" and timing.dt == 0.05 and timing.n_samples == 201
    assert "too coarse for RK4" in timing.settings["integrator_choice"]


# ----------------------------------------------------------------------------- the stiff example (poles -1, -2, -1e6)


def test_stiff_step_response_matches_the_closed_form_linear_response():
    spec = _spec({"kind": "pid_servo", "poles": [-1, -2, -1e6], "zero": -3})
    design = design_of(spec)
    res = simulate(spec, design)
    assert res.settings["integrator"].startswith("cvodes")
    t, x1 = res.time, res.position
    assert t[-1] == pytest.approx(10.0) and t[1] == pytest.approx(0.01)
    exact = _closed_form_step([-1.0, -2.0, -1e6], -3.0, t)
    # the same from the design's closed loop (scipy's lsim: matrix exponential, exact for a held input)
    loop = design.closed_loop
    u = np.zeros((t.size, loop.B.shape[1]))
    u[:, 0] = 1.0  # xD = 1 rad; xD' = xD'' = 0 and no perturbation
    lsim = scipy.signal.lsim((loop.A, loop.B, loop.C, loop.D), u, t)[1][:, 0]
    assert np.max(np.abs(lsim - exact)) < 1e-9
    # CVODES' local error test keeps a step's error to about rtol |x| + atol (rtol 1e-8, atol 1e-10 by default);
    # over the whole grid it takes fewer steps than the N = 1000 output steps, so the errors add to less than
    # N (rtol + atol) (1 + max|x|).
    tol = (t.size - 1) * (spec.numerics.rtol + spec.numerics.atol) * (1.0 + np.max(np.abs(exact)))
    error = np.max(np.abs(x1 - exact))
    assert error < tol, (error, tol)


def test_stiff_example_through_the_cli_is_designed_and_verified(tmp_path, capsys):
    """Exit 0: every check passes on the CVODES run.  The Lyapunov LMI alone cannot certify this loop at
    its relative margin -- its balanced and scaled matrix ``Ah`` has spectral radius 1 and the slow
    eigenvalue ``-1/s``, ``s >= 1e6``, so along that eigenvector ``v'(Ah'Pb + Pb Ah)v = 2 Re(lambda)
    v'Pb v >= -2e-6`` for ``Pb <= I`` and the best margin ``t* <= 2e-6`` sits at eps = 1e-6 -- and the
    check falls back on the Lyapunov equation, whose certificate is judged by rounding bounds."""
    path = _write(tmp_path, STIFF + REQUIREMENTS)
    out = tmp_path / "out"
    code = main(["synth", str(path), "--out", str(out), "--json", "--no-studies"])
    result = json.loads(capsys.readouterr().out)
    assert code == 0, [c for c in result["checks"] if c["status"] != "PASS"]
    status = {c["name"]: c["status"] for c in result["checks"]}
    lyap = next(c for c in result["checks"] if c["name"] == "lyapunov")
    assert status["lyapunov"] == "PASS" and "equation_route" in lyap["certificate"]
    assert lyap["certificate"]["t"] <= 2 * 1.0 / 1e6
    for name in ("overshoot", "settling_time", "steady_state_error", "routh_hurwitz", "pole_placement"):
        assert status[name] == "PASS", name
    settling = next(c for c in result["checks"] if c["name"] == "settling_time")
    # closed form: y = 1 - (4/3) e^-t + (1/3) e^-2t (+ a 1e-6 fast term); enters the 2 % band at
    # t = -ln(x) with (4/3) x - (1/3) x^2 = 0.02, x = 0.015085...
    x = (4 / 3 - np.sqrt((4 / 3) ** 2 - 4 / 3 * 0.02)) / (2 / 3)
    assert settling["achieved"] == pytest.approx(-np.log(x), abs=2e-3)
    html = (out / "spec" / "report.html").read_text()
    assert "Integrator choice" in html and "chosen: cvodes because the fastest pole" in html


def test_a_design_with_one_fast_pole_that_meets_its_requirements_is_verified(tmp_path, capsys):
    path = _write(tmp_path, "controller: {kind: pid_servo, poles: [-1, -2, -1e4], zero: -3}\n" + REQUIREMENTS)
    code = main(["verify", str(path), "--json"])
    result = json.loads(capsys.readouterr().out)
    assert code == 0 and result["verified"] is True
    assert {c["name"] for c in result["checks"]} >= {"overshoot", "settling_time", "steady_state_error", "lyapunov"}
    run = dk.run(dk.load_spec(path))
    assert run.simulation.settings["integrator"].startswith("cvodes")
    assert run.simulation.settings["dt"] == pytest.approx(0.01)  # 0.02 / 2, not 0.02 / 1e4


# ----------------------------------------------------------------------------- a pole near -1e-9


def test_a_pole_near_zero_gives_a_capped_run_that_says_it_does_not_reach_steady_state(tmp_path, capsys):
    path = _write(tmp_path, "controller: {kind: pid_servo, poles: [-1e-9, -2, -20], zero: -3}\n"
                            "requirements: {steady_state_error: 0.01}\n")
    code = main(["verify", str(path), "--json"])
    captured = capsys.readouterr()
    assert code == 1, captured.err
    checks = {c["name"]: c for c in json.loads(captured.out)["checks"]}
    # y = 1 + r e^{-1e-9 t} + (decayed fast terms), r = k (p - z) / (p (p + 2)(p + 20)) ~ -1: the position has
    # barely moved at the end of the cut run, so the error is the whole step
    sse = checks["steady_state_error"]
    assert sse["status"] == "FAIL" and sse["achieved"] == pytest.approx(1.0, abs=1e-6)
    settings = dk.run(dk.load_spec(path)).simulation.settings
    assert settings["integrator"].startswith("dopri5")  # a smooth loop: no stiff pole sends it to cvodes
    # dt = 0.02 / 20 = 1 ms; the default 10 / 1e-9 s is cut to max(20,000 steps, 10 / |Re p|med = 10 / 2 s)
    assert settings["dt"] == pytest.approx(1e-3)
    assert settings["duration"] == pytest.approx(CAPPED_STEPS * 1e-3)
    assert settings["duration_requested"] == pytest.approx(1e10)
    assert settings["steady_state"].startswith("not reached")


# ----------------------------------------------------------------------------- refusals: the resource bound


def test_explicit_rk4_on_a_stiff_loop_is_refused_with_the_cvodes_hint(tmp_path, capsys):
    assert_bad_input(tmp_path, capsys, f"name: x\n{LINK}{STIFF}numerics: {{integrator: rk4}}\n",
                     "numerics.integrator: rk4: 10 s at dt = 2e-08 s needs 500000000 steps")
    capsys.readouterr()
    assert_bad_input(tmp_path, capsys, f"name: x\n{LINK}{STIFF}numerics: {{integrator: rk4}}\n",
                     "use numerics.integrator: cvodes")


def test_explicit_rk4_with_a_coarse_dt_on_a_stiff_loop_names_dt_and_hints_cvodes(tmp_path, capsys):
    assert_bad_input(tmp_path, capsys,
                     f"name: x\n{LINK}{STIFF}simulation: {{dt: 0.01}}\nnumerics: {{integrator: rk4}}\n",
                     "simulation.dt: 0.01 s is too coarse")
    capsys.readouterr()
    assert_bad_input(tmp_path, capsys,
                     f"name: x\n{LINK}{STIFF}simulation: {{dt: 0.01}}\nnumerics: {{integrator: rk4}}\n",
                     "numerics.integrator: cvodes takes this step")


@pytest.mark.parametrize(
    ("simulation", "message"),
    [
        ("{duration: 1e6, dt: 0.001}", f"simulation.dt: 1e+06 s at dt = 0.001 s needs 1e+09 steps, more than "
                                       f"{MAX_STEPS}"),
        ("{duration: 1e7}", f"simulation.duration: 1e+07 s at dt = 0.001 s needs 1e+10 steps, more than {MAX_STEPS}"),
    ],
    ids=["duration-and-dt", "duration"],
)
def test_an_absurd_explicit_duration_is_refused_by_the_step_bound(tmp_path, capsys, simulation, message):
    poles = "controller: {kind: pid_servo, poles: [-4, -5, -20], zero: -3}\n"
    assert_bad_input(tmp_path, capsys, f"name: x\n{LINK}{poles}simulation: {simulation}\n",
                     message)


# ----------------------------------------------------------------------------- a diverging variable-step run


def test_a_sampled_stiff_loop_runs_on_cvodes_and_its_divergence_fails_the_checks_not_the_program(tmp_path, capsys):
    # K1 = 7.5e5 N*m/rad held over 1 ms samples: the sampled loop is unstable (x2 gains ~ 4 u Ts ~ 3000 e per
    # sample); the cvodes steps past the overflow return NaN and the time-domain check fails on it
    path = _write(tmp_path, STIFF + "requirements: {overshoot: 5}\nsimulation: {sampling_period: 0.001}\n")
    code = main(["verify", str(path), "--json"])
    captured = capsys.readouterr()
    assert code == 1 and captured.err == ""
    overshoot = next(c for c in json.loads(captured.out)["checks"] if c["name"] == "overshoot")
    assert overshoot["status"] == "FAIL" and "not finite" in overshoot["detail"]


def test_a_failing_step_ends_the_run_with_nan_records_from_that_step():
    # x' = w x^2 from x = 0.5: constant while w = 0, escapes to infinity at t = 1/(w x) = 0.2 s < 1 s once w = 10
    x, w_sym = ca.SX.sym("x"), ca.SX.sym("w")
    blow = ca.integrator("blow", "cvodes", {"x": x, "p": w_sym, "ode": w_sym * x * x}, 0.0, 1.0,
                         {"show_eval_warnings": False, "disable_internal_warnings": True})
    z, w = ca.MX.sym("z"), ca.MX.sym("w")
    step = ca.Function("step", [z, w], [blow(x0=z, p=w)["xf"], z])
    inputs = np.zeros((1, 500))
    inputs[0, 237:] = 10.0
    failure: dict = {}
    records = run_steps(step, np.array([0.5]), inputs, chunk=200, failure=failure)
    assert failure["step"] == 237 and "CVode" in failure["error"]
    np.testing.assert_array_equal(records[0, :237], 0.5)
    assert np.isnan(records[0, 237:]).all()
    with pytest.raises(RuntimeError):
        run_steps(step, np.array([0.5]), inputs, chunk=200)
