"""The "why it failed" section: shared fixes shown once, and the robot failures diagnosed.

- :func:`designkit.report.why.share_fixes` on hand-made rows: a fix found under several rows is
  numbered once, those rows refer to it and keep their own fixes; the HTML, Typst and notebook
  views show it once;
- end to end on ``infeasible-requirements`` (no fix text twice in the section) and on the two PUMA
  specs (no "not diagnosed" left in the section).  Each spec is run once per module.
"""

from __future__ import annotations

import dataclasses
import html
import re

import pytest

import designkit as dk
from designkit.report.html import render_html
from designkit.report.model import build_report_model
from designkit.report.notebook import result_html
from designkit.report.pdf import render_typst
from designkit.report.rows import WhyFix, WhyRow
from designkit.report.why import share_fixes

SPECS = "specs"
SHARED = "An anti-windup stops the divergence."
DEMAND = "The ideal linear loop itself commands 122.4 N·m for this step."
OWN = "The ±5 N·m limit allows a settling time of at least 0.3974 s."


def _row(check: str, fix: str) -> WhyRow:
    return WhyRow(check, check.title(), "FAIL", "<= 1", "2", "1", "100 %", "The loop diverges.", fix)


def test_a_shared_fix_is_numbered_once_and_referred_to():
    rows = [_row("overshoot", f"{SHARED} {DEMAND}"), _row("settling_time", f"{SHARED} {OWN} {DEMAND}"),
            _row("max_control", DEMAND), _row("rise_time", "Slow down.")]
    parts = [(SHARED, DEMAND), (SHARED, OWN, DEMAND), (DEMAND,), ("Slow down.",)]
    shared, fixes = share_fixes(rows, parts)
    assert fixes == (WhyFix(1, SHARED, ("Overshoot", "Settling_Time")),
                     WhyFix(2, DEMAND, ("Overshoot", "Settling_Time", "Max_Control")))
    assert [r.fix for r in shared] == ["See fixes 1 and 2 below.", f"{OWN} See fixes 1 and 2 below.",
                                       "See fix 2 below.", "Slow down."]
    assert [r.fix_refs for r in shared] == [(1, 2), (1, 2), (2,), ()]
    assert shared[3] is rows[3]  # a row with no shared fix is left as it was
    assert share_fixes(rows[3:], parts[3:]) == (tuple(rows[3:]), ())


@pytest.fixture(scope="module")
def infeasible_model():
    return build_report_model(dk.run(dk.load_spec(f"{SPECS}/infeasible-requirements.yaml")))


def _why_html(page: str) -> str:
    start = page.index('<section class="why')
    return page[start:page.index("</section>", start)]


def _fix_texts(section: str) -> list[str]:
    """Every fix text of the rendered section: the rows' and the numbered ones, markup removed."""
    rows = re.findall(r"<b>Fix:</b>(.*?)</td>", section, re.S)
    shared = re.findall(r'<li id="fix-\d+"><b>Fix \d+</b> \(.*?\): (.*?)</li>', section, re.S)
    return [html.unescape(re.sub(r"<[^>]+>", "", t)).strip() for t in (*rows, *shared)]


def _sentences(texts: list[str]) -> list[str]:
    out = []
    for text in texts:
        out += [s.strip() for s in re.split(r"(?<=[.)])\s+(?=[A-Z])", text) if s.strip()]
    return out


def test_no_fix_text_twice_in_the_why_section_of_infeasible_requirements(infeasible_model):
    model = infeasible_model
    assert len(model.why) == 3 and len(model.why_fixes) == 2
    section = _why_html(render_html(model))
    sentences = [s for s in _sentences(_fix_texts(section)) if not s.startswith(("See fix", "As under"))]
    assert sentences and len(sentences) == len(set(sentences)), sentences
    assert section.count("ideal linear loop itself commands 122.4") == 1
    # the anti-windup, whose re-simulation stalls short of the command, is said once as tried and is no numbered fix
    assert section.count("Tried, and not a fix: an anti-windup") == 1
    assert all("anti-windup" not in f.text for f in model.why_fixes)
    # the root cause leads the section, before the divergence it explains
    assert model.divergence.startswith("Root cause:") and model.divergence.index("cannot be met") < \
        model.divergence.index("diverges")
    # every row points at the shared fixes; the settling-time row keeps its own bound
    assert all(r.fix_refs == (1, 2) for r in model.why)
    settling = next(r for r in model.why if r.check == "settling_time")
    assert "0.3974 s" in settling.fix
    assert settling.fix.endswith("See fixes 1 and 2 below (re-simulated, passing every required check).")
    # the PDF (Typst source) and the notebook view show each shared fix once too
    typ = render_typst(model)
    notebook = result_html(model)
    for fix in model.why_fixes:
        assert typ.count(f"*Fix {fix.number}*") == 1
        assert html.unescape(notebook).count(fix.text) == 1
    assert typ.count("ideal linear loop itself commands") == 1


@pytest.mark.parametrize("name", ["puma560-computed-torque-payload", "puma560-resolved-acceleration"])
def test_robot_failures_are_diagnosed(name):
    model = build_report_model(dk.run(dk.load_spec(f"{SPECS}/{name}.yaml")))
    assert model.why
    for row in model.why:
        assert row.cause and row.fix, row
    section = _why_html(render_html(model))
    assert "not diagnosed" not in section
    assert "not diagnosed" not in render_typst(model).split("== Requirement compliance")[0]
    text = html.unescape(section)
    if "payload" in name:
        assert "m6 = 2.84" in text and "controller.model.payload: {mass: 2.5, link: 6}" in text
        assert len({r.fix for r in model.why}) == len(model.why)  # distinct fixes stay in their rows
    else:
        assert "controller.damped_least_squares: {damping: 0.00826}" in text and "joint 5" in text


def test_a_model_without_shared_fixes_renders_as_before(infeasible_model):
    plain = dataclasses.replace(infeasible_model, why_fixes=(),
                                why=tuple(dataclasses.replace(r, fix="Do this.", fix_refs=())
                                          for r in infeasible_model.why))
    section = _why_html(render_html(plain))
    assert 'class="fixes"' not in section and section.count("Do this.") == 3
    assert "*Fix 1*" not in render_typst(plain)


def test_a_long_cause_stated_by_an_earlier_row_is_referred_to():
    from designkit.report.why import REPEATED_CAUSE_MIN, share_causes

    long_cause = "The controller's model differs from the true plant" + " (details)" * 12
    assert len(long_cause) >= REPEATED_CAUSE_MIN

    def row(label, cause):
        return WhyRow("c", label, "FAIL", "r", "a", "s", "p", cause, "f")

    rows = share_causes([row("First", long_cause + "; and the worst corner."), row("Second", long_cause + "."),
                          row("Third", "Short cause."), row("Fourth", "Short cause.")])
    assert [r.cause for r in rows[1:]] == ["Same cause as First (above).", "Short cause.", "Short cause."]
    assert rows[0].cause.startswith(long_cause)


def test_no_committed_report_leaves_a_failing_row_undiagnosed():
    """Every committed example report (``designkit synth specs/<name>.yaml --out reports``) gives a cause and a fix
    in each row of "why it failed"."""
    from pathlib import Path

    reports = sorted((Path(__file__).resolve().parents[2] / "reports").glob("*/report.html"))
    assert len(reports) >= 50
    undiagnosed = [p.parent.name for p in reports if "not diagnosed" in p.read_text(encoding="utf-8")]
    assert undiagnosed == []
