"""Lab experiment 3's comparison section (ROBEL): its numbers against independent computations -- closed-loop
simulations with scipy at the box's corners, Ackermann gains from python-control, closed-form static offsets,
a command whose chattering is known by hand."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from designkit.comparison import lab3
from designkit.comparison.answers import comparison_sections
from designkit.models.elastic import elastic_state_space
from designkit.models.robots.elastic_link import elastic_link

ROBEL = Path(__file__).resolve().parents[2] / "specs" / "robel.yaml"
T_END, W, T_W = 4.0, 0.2, 2.5


@pytest.fixture(scope="module")
def comparison():
    from designkit.pipeline import run
    from designkit.schema.loader import load_spec

    return run(load_spec(ROBEL))


@pytest.fixture(scope="module")
def lab_text(comparison):
    """Every sentence of the section, computed once."""
    return " ".join(" ".join(q.sentences) for q in lab3.section(comparison).questions)


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
    return over, float(t[outside[-1] + 1]) if outside.size else 0.0


def test_the_section_applies_and_answers_every_question(comparison):
    kinds = tuple(r.design.kind for r in comparison.results)
    assert lab3.applies(kinds) and not lab3.applies(("pid_servo", "vsc"))
    anchors = [s.anchor for s in comparison_sections(comparison)]
    assert anchors == ["comparison-answers", "lab-3-comparison"]
    sec = lab3.section(comparison)
    titles = " ".join(q.question for q in sec.questions).lower()
    for words in ("why, how and with what success", "importance", "structure", "compare with the pid",
                  "perturbation", "response time", "control level", "chatter", "robust"):
        assert words in titles, words


def test_chattering_of_a_known_command():
    t = np.linspace(0.0, 2.0, 2001)
    u = np.where(np.floor(t * 50) % 2 == 0, 1.0, -1.0)  # a +-1 square wave of 25 Hz: 100 jumps of 2 in 2 s
    ch = lab3.chattering(SimpleNamespace(time=t, u_command=u[:, None]))
    jumps = int(np.count_nonzero(np.diff(u)))
    assert ch.total_variation == pytest.approx(2.0 * jumps)
    assert ch.reversals == jumps - 1 and ch.rate == pytest.approx((jumps - 1) / 2.0)
    smooth = lab3.chattering(SimpleNamespace(time=t, u_command=np.sin(np.pi * t)[:, None]))  # one reversal at t = 0.5
    assert smooth.reversals == 2 and smooth.total_variation == pytest.approx(4.0, rel=1e-5)  # 1 up, 2 down, 1 up


def test_state_regulator_corners_against_scipy(comparison):
    run = comparison["state-regulator"]
    K, N = run.design.extra["state_regulator"]["K"], run.design.extra["state_regulator"]["N"]
    corners = lab3.corner_runs(run)
    assert len(corners) == 8 and all(c.bounded for c in corners)
    t = np.linspace(0.0, T_END, 40001)
    for c in corners:
        y = _closed_loop_response(elastic_link(**c.at), K, N, t)
        over, settle = _overshoot_settling(t, y)
        assert c.overshoot == pytest.approx(over, abs=0.02), c.at
        assert c.settling_time == pytest.approx(settle, abs=5e-3), c.at


def test_one_at_a_time_state_regulator_against_python_control(comparison):
    control = pytest.importorskip("control")
    run = comparison["state-regulator"]
    oat = lab3.oat_runs("state-regulator", run)
    assert [o.change for o in oat] == ["as specified", *(w for w, _ in lab3.VARIANTS["state_regulator"])]
    params = elastic_link()
    A, B = elastic_state_space(params)
    t = np.linspace(0.0, T_END, 40001)
    for o, factor in zip(oat, (1.0, 1.5, 0.75), strict=True):
        K = np.asarray(control.acker(A, B, [factor * p for p in (-8, -10, -12, -15)])).ravel()
        Acl = A - B @ K[None, :]
        N = -1.0 / np.linalg.solve(Acl, B[:, 0])[2]
        over, settle = _overshoot_settling(t, _closed_loop_response(params, K, N, t))
        assert o.overshoot == pytest.approx(over, abs=0.02) and o.settling_time == pytest.approx(settle, abs=5e-3)
        assert o.slowest_pole == pytest.approx(-8 * factor, rel=1e-6)


def test_fast_pid_variant_is_reported_unstable(comparison):
    oat = lab3.oat_runs("pid", comparison["pid"])
    fast = next(o for o in oat if o.change.startswith("poles and zero 1.5"))
    assert fast.slowest_pole is not None and fast.slowest_pole > 0


def test_load_effect_against_closed_form_offsets(comparison):
    p = elastic_link()
    effects = {label: lab3.perturbation_effect(comparison[label]) for label in comparison.labels}
    # state regulator: -C (A - BK)^-1 D w, computed here from the model's NumPy state space
    A, B = elastic_state_space(p)
    K = np.asarray(comparison["state-regulator"].design.extra["state_regulator"]["K"])
    D = np.array([0.0, 0.0, 0.0, p.R2 / p.J2])
    sr = -np.linalg.solve(A - B @ K[None, :], D)[2] * W
    assert effects["state-regulator"].predicted == pytest.approx(sr, rel=1e-9)
    assert effects["state-regulator"].final == pytest.approx(abs(sr), rel=2e-3)
    # sliding-mode regulator: the rest of the reduced system on sigma = 0 solved by numpy (x2 = x4 = 0, c x = 0,
    # the link's equation at rest with the load)
    c = np.asarray(comparison["sliding-regulator"].design.extra["vsc"]["c"])
    k2 = p.KR * p.R2**2 / p.J2
    M = np.array([[c[0], c[2]], [k2, -k2]])
    x1, x3 = np.linalg.solve(M, [0.0, -p.R2 / p.J2 * W])
    assert effects["sliding-regulator"].predicted == pytest.approx(x3, rel=1e-9)
    assert effects["sliding-regulator"].final == pytest.approx(abs(x3), rel=5e-3)
    # motor-side PID/sliding mode: the motor held at xD, the spring carries the load (w/KR); ringing lightly damped
    assert effects["pid-sliding-mode"].final == pytest.approx(W / p.KR, abs=2e-4)
    # the PID's integral removes the offset (still decaying at the end of the run)
    assert effects["pid"].final < 0.2 * effects["pid"].peak


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


def test_printed_c4_is_figure_5_3_as_printed(comparison, lab_text):
    run = comparison["sliding-regulator"]
    p = elastic_link()
    p1, p2, p3 = -8.0, -10.0, -12.0
    c1 = -(p1 + p2 + p3) - 1.0 / p.tau2
    c2 = 1.0
    # figure 5.3 as printed: c4 = (J2/(KR R2^2))(p3 p1 + p3 p2 + p1 p2) - 1 - c1 J2/(c2 KR R2^2)
    printed = (p.J2 / (p.KR * p.R2**2)) * (p3 * p1 + p3 * p2 + p1 * p2) - 1 - c1 * p.J2 / (c2 * p.KR * p.R2**2)
    c = run.design.extra["vsc"]["c"]
    assert lab3.printed_c4(c, p.tau2, p.KR * p.R2**2 / p.J2) == pytest.approx(printed, rel=1e-12)
    # ... and the designed c4 is the derivation's (tau2 in the last term), which places -8, -10, -12
    assert c[3] == pytest.approx(printed + c1 / (c2 * 400.0) - c1 / (p.tau2 * 400.0), rel=1e-12)
    assert "printed c4 = -0.33375" in lab_text


def test_sliding_poles_over_the_box_against_the_reduced_system(comparison, lab_text):
    import itertools

    from designkit.display.numbers import fmt_number

    c = np.asarray(comparison["sliding-regulator"].design.extra["vsc"]["c"])
    keep = [0, 2, 3]
    rates = []
    for J2, Km, KR in itertools.product((0.45, 0.55), (1.8, 2.2), (180.0, 220.0)):
        A, _ = elastic_state_space(elastic_link(J2=J2, Km=Km, KR=KR))
        # on sigma = 0, x2 = -(c1 x1 + c3 x3 + c4 x4) (c2 = 1): the reduced system of the other three states
        Ar = A[np.ix_(keep, keep)] + np.outer(A[keep, 1], -c[keep])
        rates.append(min(-np.linalg.eigvals(Ar).real))
    assert f"slowest decay rate is {fmt_number(min(rates), 3)} 1/s to {fmt_number(max(rates), 3)} 1/s" in lab_text
