"""The ``ilc`` family end to end: the examples, the JSON contract, the law, the update, figures, diagnoses and bad
input.

* ``specs/ilc-simnog.yaml`` verifies: every learning check passes, the error norm falls every trial and the
  JSON's ``trials.error_norm`` is the norm of each trial's sampled error recomputed here from the raw state and
  reference; ``specs/ilc-simnog-diverging.yaml`` exits 1 through the CLI with ``rho`` above 1 by the amount the
  error grows per trial.
* The law's feedforward is ``M^(q) v`` with ``M^`` from the notes' SIMNOG closed forms (appendix B, fig. 2.2) at
  the model's masses; its command with ``v = 0`` is the computed-torque family's.
* The update is ``d + alpha H^T e`` with ``H`` the dense Toeplitz of the Markov parameters (the last sample held).
* Bad input through ``designkit synth`` (:func:`tests.cli_input.assert_bad_input`): exit 2, the key path, nothing
  written.
"""

from __future__ import annotations

import json
from types import SimpleNamespace

import numpy as np
import pytest
import scipy.linalg as sl

from designkit.cli import main
from designkit.display.svg import svg_keys
from designkit.families import FAMILIES
from designkit.families.ilc import FAMILY
from designkit.families.ilc.diagnoses import diagnose
from designkit.families.ilc.figures import error_norm_figure, learned_figure, tracking_error_figure
from designkit.families.ilc.learning import lifted_of, update_rule
from designkit.pipeline import run
from designkit.schema.loader import load_spec, parse_spec
from designkit.verification.check import Check
from tests.cli_input import assert_bad_input
from tests.families.ilc.common import DIVERGING, EXAMPLE, arm_spec


@pytest.fixture(scope="module")
def example():
    return run(load_spec(EXAMPLE))


@pytest.fixture(scope="module")
def diverging():
    return run(load_spec(DIVERGING))


def _check(result, name: str) -> Check:
    return next(c for c in result.checks if c.name == name)


def test_the_example_learns_every_trial_and_its_boundary_certificate_is_undecided(example):
    # rho = 1 - 4.5e-13: below 1, but within 1e-9 of the boundary -- no proof either way, and the verdict says so
    assert [c.name for c in example.failed] == ["ilc_convergence"]
    names = {c.name for c in example.checks}
    # the feedback part is computed torque: its linear checks apply; the learning part has its own
    assert {"pole_placement", "lyapunov", "error_poles", "designed_loop", "ilc_convergence", "ilc_error_decrease",
            "tracking_error"} <= names
    norms = example.trials.error_norms
    assert norms.size == 30 and np.all(np.diff(norms) < 0)
    assert norms[-1] < 0.01 * norms[0]
    rho = _check(example, "ilc_convergence")
    assert rho.passed is None and rho.status == "UNDECIDED" and rho.achieved < 1
    assert 0 < 1 - rho.certificate["rho_upper_bound"] < 1e-9 and rho.certificate["verdict_reason"] == "boundary"
    assert "within 1e-09 of the boundary" in rho.detail
    info = example.design.data  # the grid synthesis chose is the simulator's
    assert info.samples == example.simulation.time.size and info.dt == example.simulation.settings["dt"]


def test_json_contract(example):
    out = json.loads(json.dumps(example.to_json()))
    trials = example.trials.results
    recomputed = [float(np.linalg.norm(r.state[:, list(r.positions)] - r.reference[:, :, 0])) for r in trials]
    assert out["trials"]["error_norm"] == pytest.approx(recomputed, rel=1e-12)
    assert len(out["trials"]["error_norm"]) == example.loaded.spec.controller.trials
    assert out["rho"] == _check(example, "ilc_convergence").achieved
    lo, hi = out["rho_bounds"]
    assert lo <= out["rho"] <= hi < 1
    assert out["learning"]["kind"] == "adjoint" and out["learning"]["value"] == example.design.gains["alpha"]
    assert 0 < out["learning"]["value"] < out["learning"]["range"]["alpha_max"]


def test_the_diverging_example_fails_by_how_much(diverging, capsys):
    code = main(["verify", str(DIVERGING), "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code == 1 and not out["verified"]
    check = next(c for c in out["checks"] if c["name"] == "ilc_convergence")
    rho = out["rho"]
    assert check["status"] == "FAIL" and rho > 1 and check["margin"] == pytest.approx(1 - rho, rel=1e-9)
    assert f"by {rho - 1:.3g}" in check["detail"] and "0 < α < 2/σ_max(H)²" in check["detail"]
    norms = np.array(out["trials"]["error_norm"])
    assert np.all(np.diff(norms) > 0)
    # the smoothest error direction dominates: it grows by rho per trial (measured 1.46 to 1.52 against 1.47)
    assert np.all(np.abs(norms[1:] / norms[:-1] - rho) < 0.1 * rho), (norms[1:] / norms[:-1], rho)
    assert _check(diverging, "ilc_error_decrease").passed is False


def test_the_feedforward_is_the_models_inertia_times_v(example):
    design, law = example.design, example.design.law
    p = {q.name: q.value for q in design.plant.parameters}
    assert p["m2"] == 2.0  # the controller's model
    rng = np.random.default_rng(5)
    for _ in range(5):
        q, qd, v = rng.uniform(-2, 2, 2), rng.uniform(-1, 1, 2), rng.uniform(-3, 3, 2)
        c2 = np.cos(q[1])
        D11 = p["m1"] * p["d1"] ** 2 / 4 + p["m2"] * (p["d1"] ** 2 + p["d2"] ** 2 / 4 + p["d1"] * p["d2"] * c2) \
            + p["I1"] + p["I2"]
        D12 = p["m2"] * (p["d2"] ** 2 / 4 + p["d1"] * p["d2"] * c2 / 2) + p["I2"]
        D22 = p["m2"] * p["d2"] ** 2 / 4 + p["I2"]
        r = rng.uniform(-1, 1, 6)
        y = np.zeros(len(design.plant.states))
        y[list(design.plant.positions)], y[list(design.plant.velocities)] = q, qd
        u = np.asarray(law.feedforward(y, [], [], r, v)).ravel()
        np.testing.assert_allclose(u, np.array([[D11, D12], [D12, D22]]) @ v, rtol=1e-12)
        ct = FAMILIES["computed_torque"].law(design, None)  # the feedback part is computed torque's
        np.testing.assert_allclose(np.asarray(law.command(y, [], [], r)).ravel(),
                                   np.asarray(ct.command(y, [], [], r)).ravel(), rtol=1e-12)


def test_the_update_is_the_adjoint_with_the_last_sample_held():
    loaded = parse_spec(arm_spec("{kind: ilc, poles: [-10, -10], learning: {alpha: 3000}}", duration=0.2))
    from designkit.pipeline import design as design_of

    design = design_of(loaded)
    lifted = lifted_of(design)
    N, L = lifted.samples, lifted.L
    rng = np.random.default_rng(6)
    t = design.data.dt * np.arange(N)
    desired, measured = rng.standard_normal((N, 2)), rng.standard_normal((N, 4))
    result = SimpleNamespace(time=t, desired=desired, measured=measured, positions=design.plant.positions)
    d = rng.standard_normal((N, 2))
    nxt = update_rule(tuple(design.gains["K1"]), tuple(design.gains["K2"]), design.data)(result, d)
    e = (desired - measured[:, list(design.plant.positions)])[1:]  # qD - q at samples 1 .. N-1
    for j in range(2):
        H = sl.toeplitz(lifted.markov[j], np.zeros(L))
        np.testing.assert_allclose(nxt[:L, j], d[:L, j] + 3000.0 * H.T @ e[:, j], rtol=1e-10, atol=1e-12)
        assert nxt[L, j] == nxt[L - 1, j]


def test_figures_stand_alone(example, diverging):
    for result in (example, diverging):
        figs = [f(result) for f in FAMILY.figures]
        assert [f.filename for f in figs] == ["fig-ilc-error-norm.svg", "fig-ilc-first-last.svg",
                                              "fig-ilc-learned.svg"]
        for fig in figs:
            assert fig.svg.lstrip().startswith("<?xml") and "<text" in fig.svg and fig.caption
    norms = error_norm_figure(example)
    assert set(svg_keys(norms.svg)) == {"measured", "rho-bound", "lifted-prediction"}
    assert "flat" in norms.caption and "ilc_error_decrease" in norms.evidence
    assert "above 1" in error_norm_figure(diverging).caption
    first_last = tracking_error_figure(example)
    assert set(svg_keys(first_last.svg)) == {"first-trial", "last-trial"}
    peak = float(np.max(np.abs(example.trials.results[0].tracking_errors)))
    assert f"{peak:.3g}" in first_last.caption
    assert "rad/s²" in learned_figure(example).caption
    empty = SimpleNamespace(trials=None, checks=())
    assert all(f(empty) is None for f in FAMILY.figures)


def test_diagnoses(example, diverging):
    cause, fix = diagnose(diverging, _check(diverging, "ilc_convergence"))
    alpha_max = diverging.to_json()["learning"]["range"]["alpha_max"]
    assert "exceeds 1 by" in cause and f"(0, {alpha_max:.4g})" in fix
    cause, fix = diagnose(example, _check(example, "ilc_convergence"))  # undecided at its boundary
    assert "within 1e-09 of 1" in cause and "1 − 4.5e-13" in cause and "cannot be decided" in fix
    slow = Check(name="tracking_error", passed=False, target="<= 0.002 rad", achieved=0.00325, unit="rad")
    cause, fix = diagnose(example, slow)
    peaks = example.trials.max_tracking_errors
    rate = (peaks[-1] / peaks[-5]) ** 0.25
    more = int(np.ceil(np.log(0.002 / 0.00325) / np.log(rate)))
    assert "slow" in cause and f"about {30 + more} trials" in fix, (cause, fix)


Q = "{kind: quintic, amplitude: [1.0, -0.5], duration: 0.4}"
BAD = [
    ("{kind: ilc, poles: [-10, -10], trials: 500}", "", "controller.trials: must be between 1 and 200"),
    ("{kind: ilc, poles: [-10, -10]}", ", dt: 0.0005, duration: 30.0",
     "simulation.duration: a learning trial of 30 s at dt = 0.0005 s has 60001 samples x 2 joints"),
    ("{kind: ilc, poles: [-10, -10], trials: 200}", ", dt: 0.001, duration: 10.0",
     "controller.trials: 200 trials of 10001 samples x 2 joints"),
    ("{kind: ilc, poles: [-10, -10], learning: {alpha: -1}}", "", "controller.learning.alpha: must be positive"),
    ("{kind: ilc, poles: [-10, -10], learning: {alpha: 0}}", "", "controller.learning.alpha: must be positive"),
    ("{kind: ilc, poles: [-10, -10], learning: {kind: p_type}}", "", "controller.learning.gain: the p_type update"),
    ("{kind: ilc, poles: [-10, -10]}", ", delay: 0.01", "simulation.delay: the learning's lifted model has no delay"),
]


@pytest.mark.parametrize(("controller", "extra", "message"), BAD, ids=[m.split(":")[0] + str(i)
                                                                      for i, (_, _, m) in enumerate(BAD)])
def test_bad_input(tmp_path, capsys, controller, extra, message):
    text = ("name: bad\nplant: {kind: robot, robot: planar2r}\n"
            f"controller: {controller}\nsimulation: {{trajectory: {Q}{extra}}}\n")
    assert_bad_input(tmp_path, capsys, text, message)


@pytest.mark.parametrize("trajectory", ["{kind: square, amplitude: 0.5, period: 1.0}",
                                        "{kind: line, displacement: [0.1, 0.0, 0.0]}"])
def test_a_reference_it_cannot_follow(tmp_path, capsys, trajectory):
    text = ("name: bad\nplant: {kind: robot, robot: planar2r}\ncontroller: {kind: ilc, poles: [-10, -10]}\n"
            f"simulation: {{trajectory: {trajectory}}}\n")
    assert_bad_input(tmp_path, capsys, text, "simulation.trajectory.kind:")
