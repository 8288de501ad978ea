"""Figures of real pipeline runs: captions name exactly what is drawn, the drawn windows and levels are the
checks', requested vs derived poles, distinct line styles, a visible saturation next to a diverging command,
the sensitivity peaks (against python-control) and the evidence links."""

from __future__ import annotations

import math
import re
from pathlib import Path

import matplotlib
import numpy as np
import pytest

import designkit as dk
from designkit.display import svg
from designkit.report.figures import design_figures
from designkit.report.figures.pole_zero import pole_origin
from designkit.report.figures.simulation import _draw_simulation
from designkit.verification.figures.loop_margins import sensitivity_peaks
from designkit.verification.tolerances import STEADY_STATE_WINDOW

SPECS = Path(__file__).resolve().parents[2] / "specs"
NAMES = ("posspeed-link", "posspeed-saturation", "infeasible-requirements", "tracking-pid", "requirements-driven",
         "scara-decentralized-pid")

# What a caption says when a tagged artist is drawn, per figure (regular expressions written independently of the
# figure code's phrases).
PHRASES = {
    "fig-simulation.svg": {
        "overshoot-limit": r"overshoot limit \(dashed\)",
        "overshoot-limit-offscale": r"overshoot limit \(off scale",
        "settling-band": r"settling band",
        "rise-time": r"rise time is measured",
        "steady-state-band": r"steady-state band over the last 5 %",
        "control-limit": r"control limit \|u\| ≤ \S+ N·m \(dashed\)",
        "control-limit-offscale": r"control limit \|u\| ≤ \S+ N·m \(off scale",
        "element-levels": r"output levels \(dashed",
        "perturbation": r"perturbation torque",
        "perturbation-onset": r"onset at t =",
        "tracking-error": r"tracking error",
        "tracking-band": r"tracking-error requirement ±\S+ on the error panel",
        "error-steady-band": r"steady-state requirement ±\S+ on the error panel",
        "torque-limits": r"actuator torque limits of the plant",
        "u-applied": r"as commanded by the controller and as applied",
    },
    "fig-linear-response.svg": {
        "control-limit": r"limit \|u\| ≤ \S+ N·m \(dashed\)",
        "control-limit-offscale": r"limit \|u\| ≤ \S+ N·m is off scale",
        "reference": r"reference \(dash-dot\)",
    },
    "fig-pole-zero.svg": {
        "requested-poles": r"requested in the spec",
        "derived-poles": r"derived from the requirements",
        "requested-zero": r"requested zero",
        "derived-zero": r"zero the design chose",
        "achieved-zero": r"xD→x1",
        "coupled-poles": r"coupled arm",
    },
    "fig-loop-bode.svg": {"gain-crossover": r"gain crossovers", "margin-box": r"margins measured"},
    "fig-loop-sensitivity.svg": {"ms-peak": r"○ marks the peak", "mt-peak": r"Mt = "},
    "fig-robustness-robust_grid.svg": {"zero-contour": r"black line"},
}


@pytest.fixture(scope="module")
def runs():
    return {name: dk.run(dk.load_spec(SPECS / f"{name}.yaml")) for name in NAMES}


@pytest.fixture(scope="module")
def drawn_lists(runs):
    """Each run's figures in the order the report draws them (drawn once for the module)."""
    return {name: design_figures(r) for name, r in runs.items()}


@pytest.fixture(scope="module")
def figures(drawn_lists):
    return {name: {f.filename: f for f in figs} for name, figs in drawn_lists.items()}


def drawn(draw, *args):
    """The matplotlib figure (and info) a figure's draw function builds, under the report's rc settings."""
    with matplotlib.rc_context(svg.RC_PARAMS):
        out = draw(*args)
    return out if isinstance(out, tuple) else (out, {})


def by_key(fig, key):
    return [a for a in fig.findobj(lambda a: svg.tag_key(a.get_gid()) == key)]


@pytest.mark.parametrize("name", NAMES)
def test_every_caption_names_exactly_what_its_svg_draws(figures, name):
    for fig in figures[name].values():
        keys = set(svg.svg_keys(fig.svg))
        for key, phrase in PHRASES.get(fig.filename, {}).items():
            assert (key in keys) == bool(re.search(phrase, fig.caption)), (name, fig.filename, key, fig.caption)


def test_no_requirement_no_envelope_no_limit_no_perturbation(figures):
    fig = figures["posspeed-link"]["fig-simulation.svg"]
    keys = set(svg.svg_keys(fig.svg))
    assert {"reference", "position", "u-command"} <= keys
    assert "u-applied" not in keys and "commanded and applied alike" in fig.caption  # one line: nothing between
    assert not keys & {"overshoot-limit", "settling-band", "steady-state-band", "rise-time", "control-limit",
                       "perturbation", "perturbation-onset", "element-levels", "tracking-band", "error-steady-band",
                       "torque-limits"}
    for word in ("limit", "band", "perturbation", "ξ", "xi", "saturation", "delay ", "noise (", "checks are"):
        assert word not in fig.caption.replace("no saturation, delay, sampling, noise or other", ""), word


def test_infeasible_spec_draws_its_envelope_limits_and_a_symlog_control_axis(runs, figures):
    res = runs["infeasible-requirements"]
    fig, info = drawn(_draw_simulation, res.design, res.simulation, res.loaded.spec.requirements)
    ax_u = fig.axes[-1]
    assert ax_u.get_yscale() == "symlog"
    peak = float(np.max(np.abs(res.simulation.u_command)))
    assert peak > 1e4  # the diverging command ...
    lo, hi = ax_u.get_ylim()
    assert lo <= -peak * 0.99 or hi >= peak * 0.99
    levels = sorted({abs(float(line.get_ydata()[0])) for key in ("control-limit", "element-levels")
                     for line in by_key(fig, key)})
    assert levels == [5.0]  # ... and the 5 N·m saturation and limit, both drawn
    assert ax_u.yaxis.get_transform().linthresh > 5.0  # inside the linear part of the axis: visible
    caption = figures["infeasible-requirements"]["fig-simulation.svg"].caption
    assert "symmetric-logarithmic" in caption and f"{info['linthresh']:g} N·m" in caption
    assert "symmetric" not in figures["posspeed-saturation"]["fig-simulation.svg"].caption


def test_requested_and_derived_poles_are_labelled_as_such(runs, figures):
    assert pole_origin(runs["infeasible-requirements"]) == ("derived", "derived")
    assert pole_origin(runs["posspeed-link"]) == ("requested", "requested")
    derived = figures["infeasible-requirements"]["fig-pole-zero.svg"]
    assert "derived-poles" in svg.svg_keys(derived.svg) and "poles derived from the requirements" in derived.svg
    assert "ζ = 0.703" in derived.caption  # the damping the design derived (design.extra)
    requested = figures["posspeed-link"]["fig-pole-zero.svg"]
    assert "requested-poles" in svg.svg_keys(requested.svg) and "derived" not in requested.caption


def test_drawn_steady_state_window_is_the_checks(runs):
    res = runs["posspeed-saturation"]
    sim = res.simulation
    fig, _ = drawn(_draw_simulation, res.design, sim, res.loaded.spec.requirements)
    (band,) = by_key(fig, "steady-state-band")
    x = np.concatenate([seg[:, 0] for seg in band.get_segments()])
    t0, t1 = float(x.min()), float(x.max())
    t = np.asarray(sim.time)
    assert t1 == t[-1] and t0 == pytest.approx(t[-1] - STEADY_STATE_WINDOW * (t[-1] - t[0]), abs=1e-12)
    window = t >= t0
    mean = float(np.mean(np.abs(sim.joint_positions[window, 0] - sim.desired[window, 0])))
    check = next(c for c in res.checks if c.name == "steady_state_error")
    assert mean == pytest.approx(check.achieved, rel=1e-9)  # the check averages over exactly this window
    assert window.sum() < 0.06 * t.size  # 5 %, not the 20 % the figure once drew


def test_rise_time_markers_are_the_checks_crossings(runs):
    res = runs["requirements-driven"]
    fig, _ = drawn(_draw_simulation, res.design, res.simulation, res.loaded.spec.requirements)
    (markers,) = by_key(fig, "rise-time")
    t10, t90 = markers.get_xdata()
    check = next(c for c in res.checks if c.name == "rise_time")
    assert t90 - t10 == pytest.approx(check.achieved, rel=1e-9)


def test_limits_references_and_events_have_distinct_line_styles(servo_result):
    fig, info = drawn(_draw_simulation, servo_result.design, servo_result.simulation,
                      servo_result.loaded.spec.requirements)
    styles = {key: {a.get_linestyle() for a in by_key(fig, key)} for key in
              ("reference", "overshoot-limit", "control-limit", "perturbation-onset", "position")}
    assert styles["reference"] == {"-."}
    assert styles["overshoot-limit"] == styles["control-limit"] == {"--"}
    assert styles["perturbation-onset"] == {":"} and styles["position"] == {"-"}
    onsets = by_key(fig, "perturbation-onset")
    assert len(onsets) == len(fig.axes) and all(a.get_xdata()[0] == pytest.approx(2.5, abs=0.01) for a in onsets)
    assert info["onset"] == pytest.approx(2.5, abs=0.01)


def test_tracking_error_panel_for_trackers(runs, figures):
    res = runs["tracking-pid"]
    fig, _ = drawn(_draw_simulation, res.design, res.simulation, res.loaded.spec.requirements)
    (err,) = by_key(fig, "tracking-error")
    t, e = (np.asarray(v, float) for v in err.get_data())
    sim = res.simulation
    expected = np.interp(t, sim.time, sim.joint_positions[:, 0] - sim.desired[:, 0])
    assert np.allclose(e, expected, atol=1e-12) and np.max(np.abs(e)) > 0
    assert "tracking error" in figures["tracking-pid"]["fig-simulation.svg"].caption
    assert "tracking-error" not in svg.svg_keys(figures["posspeed-link"]["fig-simulation.svg"].svg)


def _python_control_sensitivity(design, channel, w):
    import control

    from designkit.verification.loop import loop_matrices

    A, b, c = loop_matrices(design, channel)
    L = control.ss(A, b, c, 0.0)
    S = control.feedback(control.ss([], [], [], 1.0), L)  # 1/(1 + L): negative feedback
    return np.abs(np.asarray(S(1j * np.asarray(w))).ravel())


@pytest.mark.parametrize("name", ["scara-decentralized-pid", "posspeed-link"])
def test_sensitivity_peak_matches_python_control_and_the_modulus_margin(runs, figures, name):
    res = runs[name]
    check = next(c for c in res.checks if c.name == "loop_margins")
    w = np.asarray(check.data["frequency"])
    peaks = sensitivity_peaks(check.data)
    for k, pk in enumerate(peaks):
        ms = max(float(np.max(_python_control_sensitivity(res.design, k, w))), 1.0)
        assert pk["Ms"] == pytest.approx(ms, rel=1e-6)
    assert 1.0 / max(p["Ms"] for p in peaks) == pytest.approx(check.achieved, rel=1e-9)
    fig = figures[name]["fig-loop-sensitivity.svg"]
    assert fig.evidence == ("loop_margins",)
    finite = [p for p in peaks if math.isfinite(p["w_Ms"])]
    assert ("ms-peak" in svg.svg_keys(fig.svg)) == bool(finite)
    for p in finite:
        assert f"Ms = {p['Ms']:.3g}" in fig.caption
    if name == "scara-decentralized-pid":
        assert finite and max(p["Ms"] for p in finite) > 4.0


def test_sensitivity_figure_wherever_loop_margins_exist(runs, figures):
    for name, res in runs.items():
        has_loop = any(c.name == "loop_margins" and c.data.get("channels") for c in res.checks)
        assert ("fig-loop-sensitivity.svg" in figures[name]) == has_loop, name


def test_evidence_links_name_present_checks_and_filenames_are_unique(runs, figures, drawn_lists):
    timed = {"overshoot", "settling_time", "rise_time", "steady_state_error", "tracking_error", "max_control"}
    for name, res in runs.items():
        present = {c.name for c in res.checks}
        figs = list(figures[name].values())
        assert len({f.filename for f in drawn_lists[name]}) == len(drawn_lists[name])
        for f in figs:
            assert set(f.evidence) <= present and f.anchor == f.filename[:-4] and f.anchor.startswith("fig-")
        assert set(figures[name]["fig-simulation.svg"].evidence) == timed & present
        assert figures[name]["fig-loop-bode.svg"].evidence == ("loop_margins",)
    grid = [f for f in figures["tracking-pid"].values() if f.filename.startswith("fig-robustness")]
    assert [f.evidence for f in grid] == [("robust_grid",)]


RAW = re.compile(r"N\*m|\bNone\b|\bTrue\b|\bFalse\b|\{\}|\[\]|\(\)|\[\[|\d\s*[+-]\s*\d+(?:\.\d+)?j\b|\{'\w+':")


def test_figure_text_and_captions_have_no_raw_representations(figures):
    for name, figs in figures.items():
        for fig in figs.values():
            texts = re.findall(r"<text\b[^>]*>([^<]*)</text>", fig.svg)
            assert texts, (name, fig.filename)  # text is text
            for piece in (*texts, fig.caption, fig.title):
                assert not RAW.search(piece), (name, fig.filename, piece)
