"""Every fix the diagnosis numbers passes when applied to the spec and run through the CLI; every remedy it
tried and does not number fails there.

The fixes are applied here to the spec's own YAML dict (the YAML snippet the report shows, merged by this
test's code, a null leaving the key to its default), written to a file and run with
``designkit.cli.main(["synth", ...])``: exit 0 for every numbered fix, exit 1 for every "tried, and not a
fix".  The numbered fixes of the report's "why it failed" are exactly the passing re-runs.
"""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

import designkit as dk
from designkit.analysis.diagnosis import diagnose
from designkit.analysis.diagnosis.remedies import printed_bound, round_down, round_up, snippet
from designkit.analysis.diagnosis.resimulate import MAX_FIX_RUNS, rerun
from designkit.cli import main
from designkit.report.why import why_section

SPECS = Path(__file__).resolve().parents[2] / "specs"

CORE = ["infeasible-requirements", "posspeed-relay", "puma560-computed-torque-payload", "scara-decentralized-pid"]
FAMILY = ["puma560-resolved-acceleration", "sliding-mode-weak-switching", "ilc-simnog-diverging", "mrac-gamma-unstable",
          "selftune-no-forgetting", "vsc-elastic-joint-narrow-gains", "smid-link-single-step", "adaptive-ct-not-spr",
          "pid-sm-link-weak-relay", "hierarchy-simnog-small-M"]


@pytest.fixture(scope="module")
def diagnosed():
    cache: dict[str, tuple] = {}

    def get(name: str):
        if name not in cache:
            result = dk.run(dk.load_spec(SPECS / f"{name}.yaml"))
            cache[name] = (result, diagnose(result))
        return cache[name]

    return get


def _apply(text: str, changes) -> dict:
    """The spec's YAML with the fix's YAML snippet (what the report shows) merged in, as a user would."""
    data = yaml.safe_load(text)

    def merge(node: dict, patch: dict) -> None:
        for key, value in patch.items():
            if isinstance(value, dict) and isinstance(node.get(key), dict):
                merge(node[key], value)
            else:
                node[key] = value

    merge(data, yaml.safe_load(snippet(changes)))
    return data


def _synth(tmp_path: Path, data: dict, k: int) -> int:
    path = tmp_path / f"fix{k}.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False, allow_unicode=True), encoding="utf-8")
    return main(["synth", str(path), "--out", str(tmp_path / "out"), "--no-report", "--jobs", "1"])


@pytest.mark.parametrize("name", CORE + FAMILY)
def test_every_numbered_fix_passes_and_every_tried_one_fails(name, diagnosed, tmp_path):
    result, diag = diagnosed(name)
    trials = list({id(t): t for p in diag.proposed for t in p.trials}.values())  # a change proposed twice: one run
    assert len(trials) <= MAX_FIX_RUNS
    numbered = [t for t in trials if t.passed]
    tried = [t for t in trials if not t.passed and not t.error]
    for k, trial in enumerate(numbered):
        assert _synth(tmp_path, _apply(result.loaded.text, trial.remedy.changes), k) == 0, snippet(trial.remedy.changes)
    for k, trial in enumerate(tried):
        assert _synth(tmp_path, _apply(result.loaded.text, trial.remedy.changes), 100 + k) == 1, \
            snippet(trial.remedy.changes)
    # the report numbers exactly the passing re-runs, and says the others were tried
    rows, _, fixes = why_section(result, diag)
    assert [f.number for f in fixes] == list(range(1, len(numbered) + 1))
    text = " ".join(r.fix for r in rows)
    stated = text.count("Tried, and not a fix: ") - text.count("Tried, and not a fix: as under")
    assert stated == len(tried)
    # no fix text twice in the section: a sentence or a tried remedy stated by an earlier row is referred to
    tags = ("As under", "See fix", "Not re-simulated")
    sentences = [s for r in rows for s in r.fix.split(". ") if s and not s.startswith(tags)]
    assert len(sentences) == len(set(sentences)), sentences


def test_infeasible_requirements_fixes_say_what_they_change(diagnosed):
    result, diag = diagnosed("infeasible-requirements")
    trials = {t.remedy.title: t for p in diag.proposed for t in p.trials}
    # the actuator sized for the design: 1.1 x the 122.4 N*m the ideal linear loop commands, up to two digits
    sized = next(t for title, t in trials.items() if title.startswith("an actuator limit of 140"))
    assert sized.passed and dict(sized.remedy.changes)["simulation.nonlinearity.limit"] == 140.0
    # slower poles alone keep overshoot and effort but cannot reach 0.3 s (the root cause): not a fix ...
    slow = next(t for title, t in trials.items()
                if title.startswith("every closed-loop pole") and "relaxed" not in title)
    assert not slow.passed and [o.name for o in slow.outcomes if o.status != "PASS"] == ["settling_time"]
    # ... and with the settling requirement relaxed to what they reach, a fix that says so
    relaxed = next(t for title, t in trials.items() if "relaxed" in title)
    assert relaxed.passed and relaxed.remedy.requirement
    reached = next(o.value for o in slow.outcomes if o.name == "settling_time")
    assert dict(relaxed.remedy.changes)["requirements.settling_time"] >= reached
    # the bound's own numbers (8.619 N*m, 0.3974 s) re-run with the design unchanged: not fixes of this design
    changes = [dict(t.remedy.changes) for t in trials.values()]
    bound = [t for t, c in zip(trials.values(), changes, strict=True)
             if 8.619 <= c.get("simulation.nonlinearity.limit", 0) < 8.62
             or 0.3974 <= c.get("requirements.settling_time", 0) < 0.3975]
    assert len(bound) == 2 and not any(t.passed for t in bound)
    # every re-run reports the margins of its loop
    assert all(t.margins and t.margins[0].phase_margin.endswith("°") for t in trials.values())


def test_the_relay_hysteresis_fix_is_tried_and_not_numbered(diagnosed):
    _, diag = diagnosed("posspeed-relay")
    trials = [t for p in diag.proposed for t in p.trials]
    hysteresis = next(t for t in trials if "hysteresis" in t.remedy.title)
    # the describing-function-free exact cycle puts the mean error at the limit, the run lands just above it
    assert not hysteresis.passed and "steady-state error" in hysteresis.verdict
    proportional = next(t for t in trials if "proportional" in t.remedy.title)
    assert proportional.passed and dict(proportional.remedy.changes) == {"simulation.nonlinearity": None}


def test_rerun_gives_the_pipeline_s_checks():
    loaded = dk.load_spec(SPECS / "infeasible-requirements.yaml")
    mine, run = rerun(loaded), dk.run(loaded)
    theirs = [c for c in run.checks if c.name != "generated_code"]  # the shipped code's check: the verdict's run only
    assert len(theirs) == len(run.checks) - 1
    assert [(c.name, c.status) for c in mine.checks] == [(c.name, c.status) for c in theirs]
    for a, b in zip(mine.checks, theirs, strict=True):
        if isinstance(a.achieved, float):
            assert a.achieved == pytest.approx(b.achieved, rel=1e-12, abs=1e-15)


def test_rounding_keeps_the_side_the_sentence_asks_for():
    assert round_up(8.61871) == 8.619 and round_up(8.619) == 8.619 and round_up(134.64, 2) == 140.0
    assert round_down(4.39487) == 4.394 and round_down(4.394) == 4.394
    # a printed "at least 5.21" covers every true value that prints so, up to 5.215; "4.394 or less" down to 4.3935
    for true in (5.205, 5.2101, 5.21499):
        assert f"{true:.3g}" == "5.21" and printed_bound(f"{true:.3g}", True) >= true
    for true in (4.3935, 4.39449):
        assert f"{true:.4g}" == "4.394" and printed_bound(f"{true:.4g}", False) <= true


def test_without_resimulation_nothing_is_re_run(diagnosed):
    result, _ = diagnosed("infeasible-requirements")
    assert diagnose(result, resimulate=False).proposed == ()
