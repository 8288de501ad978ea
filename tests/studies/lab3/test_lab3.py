"""Lab experiment 3 as a comparison study (ROBEL): its numbers against independent computations -- closed-loop
responses by scipy at the box's corners, Ackermann gains from python-control, closed-form static offsets, the
closed loop of a hand-written spec, a command whose chattering is known by hand."""

from __future__ import annotations

import itertools
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from designkit.comparison.answers import comparison_sections
from designkit.display.numbers import fmt_number
from designkit.families import family
from designkit.models.elastic import elastic_state_space
from designkit.models.robots.elastic_link import elastic_link
from designkit.studies import STUDIES
from designkit.studies.core.members import Plan, amount, members
from designkit.studies.core.study import StudyContext
from designkit.studies.lab3.measures import chattering
from designkit.studies.lab3.runs import corners, load_effect

ROBEL = Path(__file__).resolve().parents[3] / "specs" / "robel.yaml"
T_END, W, T_W = 4.0, 0.2, 2.5


@pytest.fixture(scope="module")
def comparison():
    from designkit.pipeline import run
    from designkit.schema.loader import load_spec

    return run(load_spec(ROBEL))


@pytest.fixture(scope="module")
def lab(comparison):
    return next(st for st in comparison.studies if st.name == "lab3")


@pytest.fixture(scope="module")
def lab_text(lab):
    """Every sentence of the section."""
    return " ".join(" ".join(q.sentences) for q in lab.section.questions)


def _entry(lab, parameter):
    return next(e for e in lab.entries if e.parameter == parameter)


def _closed_loop_response(params, K, N, t):
    """The state regulator's loop by scipy: x' = (A - BK) x + B N r + D w, step r = 1, load W from T_W."""
    from scipy.signal import lsim

    A, B = elastic_state_space(params)
    D = np.array([[0.0], [0.0], [0.0], [params.R2 / params.J2]])
    Acl = A - B @ np.asarray(K, float)[None, :]
    U = np.column_stack([np.ones_like(t), np.where(t >= T_W, W, 0.0)])
    _, y, _ = lsim((Acl, np.hstack([B * N, D]), np.eye(4)[[2]], np.zeros((1, 2))), U, t)
    return y


def _overshoot_settling(t, y, band=0.02):
    over = max(0.0, (np.max(y) - 1.0) * 100.0)
    outside = np.flatnonzero(np.abs(y - 1.0) > band)
    if outside.size and outside[-1] == t.size - 1:
        return over, float("inf")  # still outside the band at the end of the run: never settles
    return over, float(t[outside[-1] + 1]) if outside.size else 0.0


def test_the_section_carries_its_experiment_number_and_answers_every_question(comparison, lab):
    anchors = [s.anchor for s in comparison_sections(comparison)]
    assert anchors == ["comparison-answers", "lab-3-comparison"]
    assert lab.title.startswith("Lab experiment 3 (notes, appendix A): ") and lab.section.title == lab.title
    titles = " ".join(q.question for q in lab.section.questions).lower()
    for words in ("why, how and with what success", "importance", "structure", "compare with the pid",
                  "perturbation", "response time", "control level", "chatter", "robust"):
        assert words in titles, words
    assert lab.reduced == ""  # the spec's studies.budget fits every run


def test_it_applies_by_the_families_traits(comparison):
    assert STUDIES["lab3"].applies(comparison, None)
    assert {"switching", "state_feedback"} <= family("vsc").traits
    assert "state_feedback" in family("state_regulator").traits and "switching" not in family("state_regulator").traits


def test_chattering_of_a_known_command():
    t = np.linspace(0.0, 2.0, 2001)
    u = np.where(np.floor(t * 50) % 2 == 0, 1.0, -1.0)  # a +-1 square wave of 25 Hz: 100 jumps of 2 in 2 s
    ch = chattering(SimpleNamespace(time=t, u_command=u[:, None]))
    jumps = int(np.count_nonzero(np.diff(u)))
    assert ch.total_variation == pytest.approx(2.0 * jumps)
    assert ch.reversals == jumps - 1 and ch.rate == pytest.approx((jumps - 1) / 2.0)
    smooth = chattering(SimpleNamespace(time=t, u_command=np.sin(np.pi * t)[:, None]))  # one reversal at t = 0.5
    assert smooth.reversals == 2 and smooth.total_variation == pytest.approx(4.0, rel=1e-5)  # 1 up, 2 down, 1 up


def test_state_regulator_corners_against_scipy(comparison, lab):
    run = comparison["state-regulator"]
    K, N = run.design.data.K, run.design.data.N
    at = corners(comparison)
    rows = _entry(lab, "state-regulator: corners of the box").rows
    assert len(at) == len(rows) == 8 and all(r.outcome == "verified" for r in rows)
    t = np.linspace(0.0, T_END, 40001)
    for values, row in zip(at, rows, strict=True):
        y = _closed_loop_response(elastic_link(**values), K, N, t)
        over, settle = _overshoot_settling(t, y)
        assert row.metrics["overshoot"] == pytest.approx(over, abs=0.02), values
        assert row.metrics["settling_time"] == pytest.approx(settle, abs=5e-3), values


def test_one_at_a_time_state_regulator_against_python_control(lab):
    control = pytest.importorskip("control")
    rows = {r.factor: r for r in _entry(lab, "state-regulator: poles").rows}
    assert sorted(rows) == [0.5, 2.0]  # the knob's own factors
    params = elastic_link()
    A, B = elastic_state_space(params)
    t = np.linspace(0.0, T_END, 40001)
    for factor, row in rows.items():
        K = np.asarray(control.acker(A, B, [factor * p for p in (-8, -10, -12, -15)])).ravel()
        Acl = A - B @ K[None, :]
        N = -1.0 / np.linalg.solve(Acl, B[:, 0])[2]
        over, settle = _overshoot_settling(t, _closed_loop_response(params, K, N, t))
        assert row.metrics["overshoot"] == pytest.approx(over, abs=0.02)
        assert row.metrics["settling_time"] == pytest.approx(settle, abs=5e-3)


def test_the_faster_pid_is_unstable_and_its_checks_say_so(comparison, lab):
    from designkit.pipeline import run
    from designkit.schema.loader import parse_spec

    row = next(r for r in _entry(lab, "pid: poles").rows if r.factor == 2.0)
    assert row.outcome == "failed" and "Lyapunov stability certificate" in row.detail
    text = ROBEL.read_text().replace("poles: [-4, -5, -6]\n    zero: -5.5", "poles: [-8, -10, -12]\n    zero: -5.5")
    fast = run(parse_spec(text))["pid"]
    assert max(np.linalg.eigvals(np.asarray(fast.design.closed_loop.A, float)).real) > 0  # the elastic mode


def test_load_effect_against_closed_form_offsets(comparison, lab):
    p = elastic_link()
    found = {m.label: m for m in members(comparison)}
    plan = Plan(StudyContext(comparison, None, budget=10.0).new_budget())
    effects = {label: load_effect(m, plan) for label, m in found.items()}
    # state regulator: -C (A - BK)^-1 D w, computed here from the model's NumPy state space
    A, B = elastic_state_space(p)
    K = np.asarray(comparison["state-regulator"].design.data.K)
    D = np.array([0.0, 0.0, 0.0, p.R2 / p.J2])
    sr = -np.linalg.solve(A - B @ K[None, :], D)[2] * W
    assert effects["state-regulator"].predicted == pytest.approx(abs(sr), rel=1e-9)
    assert effects["state-regulator"].final == pytest.approx(abs(sr), rel=2e-3)
    # sliding-mode regulator: the rest of the reduced system on sigma = 0 solved by numpy (x2 = x4 = 0, c x = 0,
    # the link's equation at rest with the load)
    c = np.asarray(comparison["sliding-regulator"].design.data.c)
    k2 = p.KR * p.R2**2 / p.J2
    x1, x3 = np.linalg.solve(np.array([[c[0], c[2]], [k2, -k2]]), [0.0, -p.R2 / p.J2 * W])
    assert effects["sliding-regulator"].predicted == pytest.approx(abs(x3), rel=1e-9)
    assert effects["sliding-regulator"].final == pytest.approx(abs(x3), rel=5e-3)
    # motor-side PID/sliding mode: the motor held at xD, the spring carries the load (w/KR); ringing lightly damped
    assert effects["pid-sliding-mode"].predicted == pytest.approx(W / p.KR, rel=1e-12)
    assert effects["pid-sliding-mode"].final == pytest.approx(W / p.KR, abs=2e-4)
    # the PID's integral removes the offset (still decaying at the end of the run)
    assert effects["pid"].predicted == 0.0 and effects["pid"].final < 0.2 * effects["pid"].peak
    table = next(q for q in lab.section.questions if "perturbation" in q.question).tables[0]
    for row in table.rows:  # the study's table is these runs'
        e = effects[row[0]]
        assert row[1:] == (amount(e.peak, "rad", 4), amount(e.final, "rad", 4), amount(e.predicted, "rad", 4))


@pytest.mark.parametrize(("old", "new", "message"), [
    ("sliding_poles: [-8, -10, -12]", "sliding_poles: [-8, 1, -12]", "controllers[3].sliding_poles[1]"),
    ("sliding_poles: [-8, -10, -12]", "sliding_poles: [-8, 0, -12]", "controllers[3].sliding_poles[1]"),
    ("poles: [-8, -10, -12, -15]", "poles: [-8, -10, 2, -15]", "controllers[2].poles[2]"),
    ("poles: [-3, -4, -12]", "poles: [-3, 4, -12]", "controllers[1].poles[1]"),
    ("kind: elastic_joint\n", "kind: elastic_joint\n  KR: 1.0e-6\n", "plant.KR: makes the plant uncontrollable"),
])
def test_robel_bad_input_exits_2_with_the_key_path(old, new, message, tmp_path, capsys):
    from tests.cli_input import assert_bad_input

    text = ROBEL.read_text()
    assert old in text
    assert_bad_input(tmp_path, capsys, text.replace(old, new, 1), message)


def test_the_surface_words_come_from_the_family(comparison, lab_text):
    run = comparison["sliding-regulator"]
    for sentence in family("vsc").answer("strategy", run):
        assert sentence in lab_text
    assert "printed c4 = -0.33375" in lab_text


def test_sliding_poles_over_the_box_against_the_reduced_system(comparison, lab_text):
    c = np.asarray(comparison["sliding-regulator"].design.data.c)
    keep = [0, 2, 3]
    rates = []
    for J2, Km, KR in itertools.product((0.45, 0.55), (1.8, 2.2), (180.0, 220.0)):
        A, _ = elastic_state_space(elastic_link(J2=J2, Km=Km, KR=KR))
        # on sigma = 0, x2 = -(c1 x1 + c3 x3 + c4 x4) (c2 = 1): the reduced system of the other three states
        Ar = A[np.ix_(keep, keep)] + np.outer(A[keep, 1], -c[keep])
        rates.append(min(-np.linalg.eigvals(Ar).real))
    assert f"slowest decay rate is {fmt_number(min(rates), 3)} 1/s to {fmt_number(max(rates), 3)} 1/s" in lab_text


def test_every_member_sentence_says_what_its_checks_say(comparison, lab_text):
    from designkit.comparison.verdicts import check_lines
    from designkit.studies.core.members import status_words

    for m in members(comparison):
        if m.has("switching"):
            assert m.verdict in lab_text  # why, how and with what success
        assert f"{m.label}'s own run is {status_words(check_lines(m.run.checks))}" in lab_text  # robustness


def test_reliability_cites_each_switching_members_own_rate_study(comparison, lab):
    from designkit.studies import study_of

    q = next(q for q in lab.section.questions if "reliable" in q.question)
    table = q.tables[0]
    assert {line[0] for line in table.rows} == {"pid-sliding-mode", "sliding-regulator"}  # the switching members
    text = " ".join(q.sentences)
    for label in ("pid-sliding-mode", "sliding-regulator"):
        rate = study_of(comparison[label], "rate")  # the member's own study: the one cited, not run again
        assert rate is study_of(comparison[label], "rate")
        rows = sorted(rate.entries[0].rows, key=lambda r: -r.value)
        lines = [line for line in table.rows if line[0] == label]
        assert len(lines) == len(rows) == 6
        for line, row in zip(lines, rows, strict=True):
            assert line[2] == (row.outcome if not row.detail else f"{row.outcome}: {row.detail}")
            assert line[3] == amount(row.metrics["steady_error"], "rad", 3)
        lowest = None  # going down from the highest rate, the last before the first that does not pass
        for row in rows:
            if row.outcome != "verified":
                break
            lowest = row.value
        if lowest is None:
            assert f"{label} (" in text and "its verdict holds at none of the 6 rates run" in text
        elif lowest == rows[-1].value:
            assert "its verdict holds at every one of the 6 rates run, from 20 kHz down to 500 Hz" in text
        else:
            assert f"the lowest rate at which its verdict still holds is {fmt_number(lowest / 1000, 4)} kHz" in text \
                or f"the lowest rate at which its verdict still holds is {fmt_number(lowest, 4)} Hz" in text


def test_the_sliding_regulator_keeps_its_load_offset_at_20_khz(comparison):
    """At 20 kHz the sampled law is close to the continuous one: on its surface with the load, the steady error is the
    reduced system's static offset (solved here by numpy), up to the ripple of the switching."""
    from designkit.studies import study_of

    p = elastic_link()
    c = np.asarray(comparison["sliding-regulator"].design.data.c)
    k2 = p.KR * p.R2**2 / p.J2
    _, x3 = np.linalg.solve(np.array([[c[0], c[2]], [k2, -k2]]), [0.0, -p.R2 / p.J2 * W])
    row = next(r for r in study_of(comparison["sliding-regulator"], "rate").entries[0].rows if r.value == 20_000.0)
    assert row.outcome != "diverged"
    assert row.metrics["steady_error"] == pytest.approx(abs(x3), rel=0.05)
