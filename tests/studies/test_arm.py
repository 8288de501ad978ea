"""The arm's questions answered from a run (designkit.studies.arm).

Independent routes: the two-link arm's dynamics derived here by Lagrange with sympy (coupling and
Coriolis torques), the payload's weight written by hand (model error torque), and synthetic numbers
for the generated sentences.
"""

from __future__ import annotations

import dataclasses
import math
from functools import cache

import numpy as np
import pytest

from designkit.models.robot_plant import zoo_plant
from designkit.models.torques import coupling_torques, model_error_torque
from designkit.pipeline import run
from designkit.report.html import render_html
from designkit.report.model import build_report_model
from designkit.report.pdf import compile_pdf
from designkit.schema.loader import parse_spec
from designkit.studies.arm import lab_answers
from designkit.studies.arm.coupling import JointCoupling, coupling_level, coupling_sentences
from designkit.studies.arm.tracking import CoordinateError, tracking_sentences
from tests.problems import POSSPEED_YAML
from tests.tolerances import TOL

# computed torque on the SIMNOG arm with a model that believes m2 = 2.5 kg (the plant has 3 kg): a static
# error remains after the quintic, which the gain study must scale with 1/K1
CT_MISMATCH = """\
name: lab-ct-mismatch
plant: {kind: robot, robot: planar2r}
controller: {kind: computed_torque, poles: [-20, -20], model: {parameters: {m2: 2.5}}}
simulation: {duration: 3.0, trajectory: {kind: quintic, amplitude: [1.0, -0.5], duration: 1.0}}
"""
CT_EXACT = CT_MISMATCH.replace(", model: {parameters: {m2: 2.5}}", "").replace("lab-ct-mismatch", "lab-ct-exact")
# joint 2's loop on slow poles has K2 = -0.52 < 0: doubled, K2 < -1/Km2 and the Routh condition fails
PID_FRAGILE = """\
name: lab-pid-fragile
plant: {kind: robot, robot: planar2r}
controller: {kind: decentralized_pid, poles: [[-4, -5, -20], [-0.5, -1, -1.5]]}
simulation: {duration: 3.0, step: [0.2, 0.1], dt: 0.002}
"""


@pytest.fixture(scope="module")
def mismatch():
    result = run(parse_spec(CT_MISMATCH))
    return result, lab_answers(result)


@pytest.fixture(scope="module")
def exact():
    result = run(parse_spec(CT_EXACT))
    return result, lab_answers(result)


# ----------------------------------------------------------------------------- independent dynamics


@cache
def _lagrange_planar2r():
    """``M(q)`` and the Coriolis/centrifugal torque ``c(q, qd)`` of two uniform rods (relative second angle),
    from the kinetic energy by Lagrange's equations, as NumPy functions."""
    import sympy as sp

    q1, q2, qd1, qd2, qdd1, qdd2 = sp.symbols("q1 q2 qd1 qd2 qdd1 qdd2")
    m1, m2, d1, d2, I1, I2 = sp.symbols("m1 m2 d1 d2 I1 I2", positive=True)
    t = sp.symbols("t")
    Q1, Q2 = sp.Function("Q1")(t), sp.Function("Q2")(t)
    c1 = sp.Matrix([d1 / 2 * sp.cos(Q1), d1 / 2 * sp.sin(Q1)])
    c2 = sp.Matrix([d1 * sp.cos(Q1) + d2 / 2 * sp.cos(Q1 + Q2), d1 * sp.sin(Q1) + d2 / 2 * sp.sin(Q1 + Q2)])
    v1, v2 = c1.diff(t), c2.diff(t)
    T = (m1 * v1.dot(v1) + I1 * Q1.diff(t) ** 2 + m2 * v2.dot(v2) + I2 * (Q1.diff(t) + Q2.diff(t)) ** 2) / 2
    tau = [sp.diff(T.diff(Qi.diff(t)), t) - T.diff(Qi) for Qi in (Q1, Q2)]
    subs = {Q1.diff(t, 2): qdd1, Q2.diff(t, 2): qdd2, Q1.diff(t): qd1, Q2.diff(t): qd2}
    tau = [sp.expand(e.subs(subs).subs({Q1: q1, Q2: q2})) for e in tau]
    M = sp.Matrix(2, 2, lambda i, j: sp.diff(tau[i], (qdd1, qdd2)[j]))
    c = [e.subs({qdd1: 0, qdd2: 0}) for e in tau]
    args = (q1, q2, qd1, qd2, m1, m2, d1, d2, I1, I2)
    return sp.lambdify(args, M, "numpy"), sp.lambdify(args, c, "numpy")


def _hand_coupling(plant, q, qd, qdd):
    M_fn, c_fn = _lagrange_planar2r()
    p = {s.name: s.value for s in plant.parameters}
    own, off, cor = np.empty_like(q), np.empty_like(q), np.empty_like(q)
    for k in range(q.shape[0]):
        args = (*q[k], *qd[k], p["m1"], p["m2"], p["d1"], p["d2"], p["I1"], p["I2"])
        M = np.asarray(M_fn(*args), dtype=float)
        own[k] = np.diag(M) * qdd[k]
        off[k] = M @ qdd[k] - own[k]
        cor[k] = np.asarray(c_fn(*args), dtype=float)
    return own, off, cor


def _scaled_error(x, ref):
    return float(np.max(np.abs(np.asarray(x) - np.asarray(ref)) / (1 + np.abs(np.asarray(ref)))))


def test_coupling_torques_match_the_lagrange_equations_of_two_rods():
    plant = zoo_plant("planar2r")
    rng = np.random.default_rng(7)
    q, qd, qdd = (rng.uniform(-3, 3, size=(25, 2)) for _ in range(3))
    got = coupling_torques(plant, q, qd, qdd)
    own, off, cor = _hand_coupling(plant, q, qd, qdd)
    assert _scaled_error(got["own"], own) <= TOL["algebra"]
    assert _scaled_error(got["off_diagonal"], off) <= TOL["algebra"]
    assert _scaled_error(got["coriolis"], cor) <= TOL["algebra"]
    assert _scaled_error(got["coupling"], off + cor) <= TOL["algebra"]


def test_coupling_answers_are_the_peaks_along_the_simulated_path(mismatch):
    result, answers = mismatch
    sim = result.simulation
    assert answers.coupling.stride == 1
    q = np.asarray(sim.joint_positions)
    qd = np.asarray(sim.state)[:, list(sim.velocities)]
    qdd = np.gradient(qd, np.asarray(sim.time), axis=0)
    own, off, cor = _hand_coupling(result.plant, q, qd, qdd)
    for i, j in enumerate(answers.coupling.joints):
        assert j.joint == i + 1 and j.unit == "N*m"
        assert j.coupling == pytest.approx(np.max(np.abs(off[:, i] + cor[:, i])), rel=1e-9)
        assert j.off_diagonal == pytest.approx(np.max(np.abs(off[:, i])), rel=1e-9)
        assert j.coriolis == pytest.approx(np.max(np.abs(cor[:, i])), rel=1e-9)
        assert j.own_inertial == pytest.approx(np.max(np.abs(own[:, i])), rel=1e-9)
        assert j.ratio == pytest.approx(j.coupling / j.own_inertial, rel=1e-12)


# ----------------------------------------------------------------------------- model error torque


def test_model_error_torque_is_exactly_zero_for_an_exact_model(exact):
    plant = zoo_plant("planar2r")
    rng = np.random.default_rng(1)
    q, qd, qdd = (rng.uniform(-2, 2, size=(10, 2)) for _ in range(3))
    assert np.all(model_error_torque(plant, plant.with_params(m2=3.0), q, qd, qdd) == 0.0)
    result, answers = exact
    assert answers.nature == "model-based"
    assert [j.model_error for j in answers.coupling.joints] == [0.0, 0.0]
    assert any("cancelled exactly" in s for s in answers.coupling.sentences)


def test_model_error_torque_at_rest_is_the_missing_payload_weight():
    model = zoo_plant("planar2r")
    payload = 0.7
    plant = model.with_payload(payload, 2)
    q = np.array([[0.0, 0.0], [0.4, -1.1], [2.0, 0.5], [-np.pi / 2, np.pi / 3]])
    zero = np.zeros_like(q)
    d1, d2, g = 0.5, 0.4, 9.81
    expected = np.column_stack([payload * g * (d1 * np.cos(q[:, 0]) + d2 / 2 * np.cos(q[:, 0] + q[:, 1])),
                                payload * g * d2 / 2 * np.cos(q[:, 0] + q[:, 1])])
    got = model_error_torque(plant, model, q, zero, zero)
    assert _scaled_error(got, expected) <= TOL["algebra"]


def test_mismatch_reports_the_model_error_and_the_differing_parameter(mismatch):
    result, answers = mismatch
    errs = [j.model_error for j in answers.coupling.joints]
    assert all(e is not None and e > 0 for e in errs)
    assert any("m2 2.5 against 3 kg" in s for s in answers.mass)


# ----------------------------------------------------------------------------- configuration


def test_configuration_is_the_diagonal_inertia_along_the_path(mismatch):
    result, answers = mismatch
    q = np.asarray(result.simulation.joint_positions)
    p = {s.name: s.value for s in result.plant.parameters}
    m1, m2, d1, d2 = p["m1"], p["m2"], p["d1"], p["d2"]
    D11 = m1 * d1**2 / 4 + m2 * (d1**2 + d2**2 / 4 + d1 * d2 * np.cos(q[:, 1])) + p["I1"] + p["I2"]  # appendix B
    j1, j2 = answers.configuration.joints
    assert j1.low == pytest.approx(D11.min(), rel=1e-12) and j1.high == pytest.approx(D11.max(), rel=1e-12)
    assert j1.ratio == pytest.approx(D11.max() / D11.min(), rel=1e-12)
    assert j2.ratio == pytest.approx(1.0, abs=1e-12)  # D22 = m2 d2^2/4 + I2 does not depend on q
    assert f"varies by a factor {j1.ratio:.3g}" in answers.configuration.sentences[0]
    assert any("error_poles" in s for s in answers.configuration.sentences)


# ----------------------------------------------------------------------------- sentences follow the numbers


def _joint(ratio: float, model_error: float | None = None) -> JointCoupling:
    return JointCoupling(1, "N*m", ratio, 0.1, ratio, 0.5, 1.0, ratio, model_error)


def test_coupling_wording_is_monotone_in_the_ratio():
    ratios = [0.0, 0.01, 0.049, 0.05, 0.2, 0.31, 0.9, 1.0, 1.01, 5.0, math.inf]
    order = ["negligible", "moderate", "significant", "dominant"]
    levels = [order.index(coupling_level(r)) for r in ratios]
    assert levels == sorted(levels) and levels[0] == 0 and levels[-1] == 3
    low, high = (coupling_sentences([_joint(r)], "other")[0] for r in (0.01, 2.0))
    assert low.endswith("negligible.") and high.endswith("dominant.") and "1 %" in low and "200 %" in high


def test_model_error_wording_follows_its_size():
    words = [coupling_sentences([_joint(1.0, e)], "model-based", "Computed torque")[-1] for e in (0.0, 0.01, 0.5, 3.0)]
    assert "cancelled exactly" in words[0]
    assert "almost exactly" in words[1]
    assert "disturbance on the error dynamics" in words[2]
    assert "the model mismatch, not the coupling" in words[3]


def test_tracking_sentence_tells_a_static_error_from_a_decaying_one():
    def coords(final: float):
        return [CoordinateError("q1", "rad", 1.0, 0.01, 0.5, 0.005, final)]

    static = tracking_sentences("trajectory", coords(0.009), [])
    decays = tracking_sentences("trajectory", coords(1e-5), [])
    assert "a static error remains" in static[1] and "decays" in decays[1]
    assert "0.01 rad on q1" in static[0] and "1 % of its move" in static[0]


# ----------------------------------------------------------------------------- report


def test_none_for_a_link_plant_or_without_simulation(exact):
    link = run(parse_spec(POSSPEED_YAML), simulate=False)
    assert lab_answers(link) is None
    result, _ = exact
    assert lab_answers(dataclasses.replace(result, simulation=None)) is None
    assert build_report_model(link).sections == ()


def test_report_of_a_robot_spec_has_the_arm_section_without_an_experiment_number(exact):
    result, answers = exact
    model = build_report_model(result)
    arm = next(s for s in model.sections if s.anchor == "arm")
    questions = [s.question for s in arm.questions]
    assert len(questions) == 4 and questions[0].startswith("How well does the controller perform")
    html = render_html(model)
    assert '<h2 id="arm">The arm: tracking, configuration, mass parameters and coupling</h2>' in html
    assert "experiment 1" not in arm.title + arm.intro  # computed torque is not the notes' PID experiment
    assert answers.tracking.sentences[0] in html.replace("&#39;", "'")
    assert any(s.anchor == "study-gains" for s in model.sections)
    assert compile_pdf(model).startswith(b"%PDF")


def test_coupling_the_law_cancels_is_not_called_dominant():
    """Resolved acceleration with the exact model: the coupling torques are in the arm, not in the loop."""
    from designkit.studies.arm.coupling import JointCoupling, coupling_sentences

    strong = JointCoupling(1, "N*m", 3.0, 0.1, 3.1, 0.5, 1.0, 3.1, 0.0)  # coupling 3.1x the own torque, cancelled
    text = " ".join(coupling_sentences([strong], "model-based"))
    assert "dominant in the arm's dynamics, but cancelled by the controller's model" in text
    assert ": dominant." not in text
    felt = JointCoupling(1, "N*m", 3.0, 0.1, 3.1, 0.5, 1.0, 3.1, 1.0)  # a model error of 1 N*m: felt by the loop
    assert ": dominant." in " ".join(coupling_sentences([felt], "model-based"))
