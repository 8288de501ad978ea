"""The identification on simulated links: V non-increasing (property test), convergence to a = 1/tau and
b = Km/tau, re-convergence after a parameter step, and the determinant monitor against NumPy.

Expected values come from the plant's parameters (a = 1/tau, b = Km/tau computed here) and from the recorded
state and command (NumPy), never from the family's own helpers."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from designkit.cli import main
from designkit.pipeline import run
from designkit.schema.loader import load_spec
from tests.cli_input import assert_bad_input
from tests.families.sliding_mode_identification.conftest import SPECS

SPEC = """\
name: smid-property
plant: {{kind: link, Km: {Km}, tau: {tau}}}
controller:
  kind: sliding_mode_identification
  servo: {{K1: {K1}, K2: {K2}}}
  initial_estimates: [{a0}, {b0}]
  error_bounds: {{a: {ea}, b: {eb}}}
  window: {D}
  adaptation_gains: [{ga}, {gb}]
  sampling_period: 0.002
simulation:
  duration: {T}
  trajectory: {{kind: square, amplitude: 0.5, period: {P}}}
"""


def _V(sim, a, b, gamma):
    ah, bh = np.asarray(sim.signals["a_hat"]), np.asarray(sim.signals["b_hat"])
    return (a - ah) ** 2 / gamma[0] + (b - bh) ** 2 / gamma[1]


@settings(max_examples=6, deadline=None, suppress_health_check=list(HealthCheck), derandomize=True,
          phases=(Phase.explicit, Phase.generate))
@given(Km=st.floats(0.5, 5.0), tau=st.floats(0.2, 2.0), K1=st.floats(1.0, 8.0), K2=st.floats(0.1, 2.0),
       da=st.floats(-0.8, 0.8), db=st.floats(-0.8, 0.8), ga=st.floats(0.1, 2.0), gb=st.floats(0.1, 1.0),
       D=st.sampled_from([0.1, 0.25, 0.5]), P=st.sampled_from([1.0, 2.0, 3.0]))
def test_lyapunov_function_does_not_increase(tmp_path_factory, Km, tau, K1, K2, da, db, ga, gb, D, P):
    """Random links, servo gains, adaptation gains and initial errors; c, d from the stated bounds (the default:
    1.5 times sqrt(g V0max)), the bounds covering the initial errors, and gains whose sampled update's step
    Ts lambda_max(Gamma^1/2 Phi Gamma^1/2) stays below 2 (checked from the run, NumPy): V never rises and the
    observer's condition holds."""
    a, b = 1.0 / tau, Km / tau
    a0, b0 = a * (1 + da), b * (1 + db)
    ea, eb = 1.2 * abs(a - a0) + 1e-3, 1.2 * abs(b - b0) + 1e-3
    path = tmp_path_factory.mktemp("smid") / "spec.yaml"
    path.write_text(SPEC.format(Km=Km, tau=tau, K1=K1, K2=K2, a0=a0, b0=b0, ea=ea, eb=eb, D=D, ga=ga, gb=gb,
                                T=4.0, P=P))
    result = run(load_spec(path))
    sim = result.simulation
    x2 = np.asarray(sim.state)[:, sim.velocities[0]]
    u = np.asarray(sim.u_command)[:, 0]
    assert 0.002 * 2 * (ga * np.max(x2**2) + gb * np.max(u**2)) < 2  # trace bound of the step condition
    V = _V(sim, a, b, (ga, gb))
    assert np.all(np.isfinite(V))
    rise = V - np.minimum.accumulate(V)
    assert rise.max() <= 1e-6 * V[0] + 1e-9, (rise.max(), V[0])  # O(Ts^2) reconstruction: see checks.V_FLOOR
    # the observer's condition: c, d above the largest estimation errors along the run
    ah, bh = np.asarray(sim.signals["a_hat"]), np.asarray(sim.signals["b_hat"])
    x = result.design.data
    assert x.c > np.max(np.abs(a - ah)) and x.d > np.max(np.abs(b - bh))
    assert {c.name: c.passed for c in result.checks}["identification_lyapunov"] is True


def test_estimates_converge_on_an_exciting_input(link_result):
    sim = link_result.simulation
    a, b = 1.0 / 0.5, 2.0 / 0.5  # the spec's link
    assert sim.signals["a_hat"][-1] == pytest.approx(a, rel=1e-4)
    assert sim.signals["b_hat"][-1] == pytest.approx(b, rel=1e-4)
    assert link_result.verified is True
    checks = {c.name: c for c in link_result.checks}
    assert checks["identification_convergence"].required and checks["identification_convergence"].passed


def test_estimates_reconverge_after_a_parameter_step(step_result):
    sim = step_result.simulation
    t = np.asarray(sim.time)
    before = np.searchsorted(t, 10.0) - 1
    assert sim.signals["a_hat"][before] == pytest.approx(1 / 0.5, rel=1e-3)
    assert sim.signals["b_hat"][before] == pytest.approx(2 / 0.5, rel=1e-3)
    assert sim.signals["a_hat"][-1] == pytest.approx(1 / 1.0, rel=1e-4)  # Km 1, tau 1 after the change
    assert sim.signals["b_hat"][-1] == pytest.approx(1 / 1.0, rel=1e-4)
    assert step_result.verified is True


def test_determinant_monitor_against_numpy(step_result):
    """det = x2m(t) u(t-D) - u(t) x2m(t-D) with x2m the mean speed over the last sample and u the command held over
    it, from the recorded state and command."""
    sim = step_result.simulation
    N = int(round(0.25 / 0.002))
    x2 = np.asarray(sim.state)[:, sim.velocities[0]]
    u = np.asarray(sim.u_command)[:, 0]
    xm = np.r_[0.0, (x2[1:] + x2[:-1]) / 2]
    pu = np.r_[0.0, u[:-1]]
    xD, uD = np.r_[np.zeros(N), xm[:-N]], np.r_[np.zeros(N), pu[:-N]]
    det = xm * uD - pu * xD
    rec = np.asarray(sim.signals["det"])
    assert np.max(np.abs(rec - det)) <= 1e-9 * max(1.0, np.max(np.abs(det)))
    assert np.mean(np.abs(det[N:]) > 1e-3 * np.max(np.abs(det))) > 0.5


def test_a_single_step_does_not_excite(single_step_result):
    checks = {c.name: c for c in single_step_result.checks}
    assert checks["determinant_condition"].passed is False
    assert checks["identification_convergence"].required is False
    assert single_step_result.verified is False


def test_json_gives_the_final_estimates(tmp_path, capsys):
    code = main(["synth", str(SPECS / "smid-link.yaml"), "--json", "--no-studies", "--out", str(tmp_path)])
    out = json.loads(capsys.readouterr().out)
    assert code == 0
    assert out["a_hat"] == pytest.approx(2.0, rel=1e-4) and out["b_hat"] == pytest.approx(4.0, rel=1e-4)


HEAD = ("name: bad\nplant: {kind: link, Km: 2.0, tau: 0.5}\n"
        "simulation: {duration: 4, trajectory: {kind: square, amplitude: 0.5, period: 2}}\n"
        "controller: {kind: sliding_mode_identification, initial_estimates: [1, 1], error_bounds: {a: 3, b: 5}, ")


@pytest.mark.parametrize("extra, message", [
    ("c: 0}", "controller.c: "), ("c: -1}", "controller.c: "), ("d: 0}", "controller.d: "),
    ("d: -2.5}", "controller.d: "), ("window: 0}", "controller.window: "), ("window: -0.1}", "controller.window: "),
    ("window: 0.0001}", "controller.window: must be between one and"),
])
def test_bad_input(extra, message, tmp_path, capsys):
    assert_bad_input(tmp_path, capsys, HEAD + extra + "\n", message)


def test_a_prbs_reference_identifies_the_link(tmp_path):
    """A seeded PRBS (the other exciting reference the family follows) on another link: Km = 1.5, tau = 0.8 s."""
    path = tmp_path / "spec.yaml"
    path.write_text(SPEC.format(Km=1.5, tau=0.8, K1=4.0, K2=0.4, a0=2.0, b0=1.0, ea=2.0, eb=2.0, D=0.25, ga=1.0,
                                gb=1.0, T=15.0, P=2.0).replace("{kind: square, amplitude: 0.5, period: 2.0}",
                                                               "{kind: prbs, amplitude: 0.5, bit: 0.5, order: 7}"))
    result = run(load_spec(path))
    sim = result.simulation
    assert "prbs" in path.read_text()
    assert sim.signals["a_hat"][-1] == pytest.approx(1 / 0.8, rel=1e-3)
    assert sim.signals["b_hat"][-1] == pytest.approx(1.5 / 0.8, rel=1e-3)


def test_report_section_and_figures(step_result):
    from designkit.families.sliding_mode_identification.report import FIGURES, section

    sec = section(step_result)
    assert sec is not None and len(sec.questions) == 2
    rows = sec.questions[0].tables[0].rows
    assert len(rows) == 2  # the segments before and after the change
    figures = [f(step_result) for f in FIGURES]
    assert [f.title for f in figures] == ["Estimates against the true values", "The observer's sliding variable",
                                          "Determinant monitor"]
    assert all("t = 10 s" in f.caption for f in figures)
    text = " ".join([sec.intro, *[s for q in sec.questions for s in q.sentences], *[f.caption for f in figures]])
    assert "_" not in text and "np." not in text
