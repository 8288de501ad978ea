"""Why it failed: one row per required check that failed or is undecided, with the diagnosed cause and fix.

The causes and fixes come from :func:`designkit.analysis.diagnosis.diagnose`; a fix found under several
rows is numbered once below the table (:func:`share_fixes`) and a long cause already stated by an earlier
row is referred to (:func:`share_causes`).  The metrics of the linear model against the nonlinear
simulation (:func:`metric_rows`) come from the same diagnosis.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import Any

from designkit.display.numbers import fmt_number, is_real, unit
from designkit.report.compliance import achieved_text, limit_of, percent_of, unit_suffix
from designkit.report.labels import check_label
from designkit.report.rows import MetricRow, WhyFix, WhyRow

__all__ = ["REPEATED_CAUSE_MIN", "diagnose_run", "metric_rows", "resimulated_fixes", "share_causes", "share_fixes",
           "why_section"]


def _why_from_check(check: Any) -> WhyRow:
    """Requirement, achieved value and shortfall of a failing check, from the check alone."""
    limit, number = limit_of(check)
    margin = check.margin if is_real(check.margin) else None
    if margin is not None and margin < 0:
        shortfall, percent = fmt_number(-margin, 4) + unit_suffix(check.unit), percent_of(-margin, number)
    elif check.passed is None:
        shortfall, percent = "not decided", ""
    else:
        shortfall, percent = "not measurable", ""
    return WhyRow(check.name, check_label(check), check.status, limit, achieved_text(check), shortfall,
                  percent.lstrip("+"), "", "")


def diagnose_run(result: Any) -> Any:
    """``designkit.analysis.diagnosis.diagnose(result)``; None when that module is not installed,
    the exception itself when the diagnosis failed (the report then says so instead of failing).  A pipeline
    result computes its diagnosis once (``result.diagnosis``, shared with ``synth --json``'s fixes)."""
    if "diagnosis" in getattr(result, "__dict__", {}) or type(result).__dict__.get("diagnosis") is not None:
        return result.diagnosis
    try:
        from designkit.analysis.diagnosis import diagnose
    except ImportError:
        return None
    try:
        return diagnose(result)
    except Exception as exc:  # noqa: BLE001 - a failed diagnosis must not cost the user the report
        return exc


def why_section(result: Any, diagnosis: Any) -> tuple[tuple[WhyRow, ...], str, tuple[WhyFix, ...]]:
    """The rows of "why it failed", where their causes come from, and the fixes shared by several rows."""
    failing = [c for c in result.checks if getattr(c, "required", True) and c.passed is not True]
    if not failing:
        return (), "", ()
    if isinstance(diagnosis, Exception):
        rows = tuple(_why_from_check(c) for c in failing)
        return rows, (f"The diagnosis of this run failed ({type(diagnosis).__name__}: {diagnosis}); the rows give "
                      "the requirement, the achieved value and the shortfall only."), ()
    by_name = {f.check: f for f in (diagnosis.findings if diagnosis is not None else ())}
    rows, parts = [], []
    for check in failing:
        row = _why_from_check(check)
        found = by_name.get(check.name)
        parts.append(_fix_parts(found) if found is not None else ())
        if found is not None:
            cause = unit(found.cause)
            lead = unit(diagnosis.divergence).strip().rstrip(".") if diagnosis.diverged and diagnosis.divergence else ""
            if lead and cause.strip().startswith(lead):
                rest = cause.strip()[len(lead):].lstrip(".;, ")
                cause = "The nonlinear loop diverges (see above)." + (" " + rest[0].upper() + rest[1:] if rest else "")
            row = dataclasses.replace(
                row, cause=cause, fix=unit(found.fix),
                # the check's own numbers first (same format as the compliance table); the diagnosis' when it has none
                achieved=row.achieved if row.achieved != "undefined" else (unit(found.achieved) or row.achieved),
                shortfall=row.shortfall if row.shortfall_percent or row.shortfall.endswith(unit(check.unit))
                and row.shortfall[:1].isdigit() else (unit(found.shortfall) or row.shortfall),
                shortfall_percent=row.shortfall_percent or found.shortfall_percent)
        rows.append(row)
    if diagnosis is None:
        note = ("No diagnosis was available (designkit.analysis.diagnosis is not installed): the rows give the "
                "requirement, the achieved value and the shortfall only.")
    elif not any(r.cause for r in rows):
        note = "The run shows no specific cause for these shortfalls beyond the values themselves."
    else:
        note = ("Causes are diagnosed from this run (the simulation, the linear analysis of the design and the "
                "checks' certificates); the fixes are computed from the same run.")
    rows = share_causes(rows)
    proposed = tuple(getattr(diagnosis, "proposed", ()) or ())
    if proposed:
        shared_rows, fixes = resimulated_fixes(rows, parts, proposed)
        note += (" Every fix the diagnosis can write as a change of the spec was re-run through the same pipeline "
                 "(design, checks, simulation on the true plant); only those whose re-run passes every required "
                 "check are numbered below the table, each with the change as YAML to merge into the spec.")
        return shared_rows, note, fixes
    shared_rows, fixes = share_fixes(rows, parts)
    if fixes:
        note += " A fix that applies to several rows is given once, numbered, below the table."
    return shared_rows, note, fixes


def _trial_words(trial: Any) -> str:
    """A re-run in one sentence: the change (YAML), the verdict, the margins."""
    from designkit.analysis.diagnosis.remedies import snippet

    text = f"{trial.remedy.title} ({snippet(trial.remedy.changes)}): re-run, {trial.verdict}"
    if trial.margins:
        text += "; loop margins " + "; ".join(
            f"{m.input}: {m.gain_margin}, phase margin {m.phase_margin}, modulus margin {m.modulus_margin}"
            for m in trial.margins)
    elif trial.margins_note:
        text += f"; {trial.margins_note}"
    text = unit(text)
    return text[0].upper() + text[1:] + "."


def resimulated_fixes(rows: Sequence[WhyRow], parts: Sequence[tuple[str, ...]], proposed: Sequence[Any]
                      ) -> tuple[tuple[WhyRow, ...], tuple[WhyFix, ...]]:
    """Rows whose fixes are re-run: a sentence stated once (later rows refer to the first row that states it),
    followed by what its re-runs showed; the numbered fixes are the re-runs that pass every required check, so
    every row refers to every one of them.

    Parameters
    ----------
    rows : sequence of WhyRow
    parts : sequence of tuple of str
        Each row's distinct fix sentences (typeset).
    proposed : sequence of ProposedFix
        The diagnosis' sentences with their re-runs (:func:`designkit.analysis.diagnosis.fixes.check_fixes`).
    """
    by_sentence = {unit(p.sentence): p for p in proposed}
    numbers: dict[int, int] = {}  # id(trial) -> fix number
    fixes: list[WhyFix] = []
    first: dict[str, str] = {}
    tried: dict[int, str] = {}  # id(trial) -> the row that states it
    out = []
    for row, row_parts in zip(rows, parts, strict=True):
        texts: list[str] = []
        for part in row_parts:
            if part in first:
                texts.append(f"As under {first[part]} (above).")
                continue
            first[part] = row.label
            texts.append(part)
            found = by_sentence.get(part)
            if found is None:
                continue
            for trial in found.trials:
                if trial.passed:
                    if id(trial) not in numbers:  # the same change proposed under several sentences is one fix
                        numbers[id(trial)] = len(numbers) + 1
                        fixes.append(WhyFix(numbers[id(trial)], _trial_words(trial), ()))
                elif id(trial) in tried:
                    texts.append(f"Tried, and not a fix: as under {tried[id(trial)]} (above).")
                else:
                    tried[id(trial)] = row.label
                    words = _trial_words(trial)
                    texts.append("Tried, and not a fix: " + words[0].lower() + words[1:])
            if found.note:
                texts.append(found.note[0].upper() + found.note[1:] + ".")
        out.append((row, texts))
    # a numbered fix passes every required check on its re-run, so it fixes every row
    refs = list(range(1, len(fixes) + 1))
    ending = [_refs_text(refs).replace("below.", "below (re-simulated, passing every required check).")] \
        if refs else []
    rows_out = tuple(dataclasses.replace(row, fix=" ".join([*texts, *ending]), fix_refs=tuple(refs))
                     for row, texts in out)
    labels = tuple(r.label for r in rows_out)
    return rows_out, tuple(dataclasses.replace(f, checks=labels) for f in fixes)


REPEATED_CAUSE_MIN = 120
"""A cause at least this long (characters) that an earlier row's cause already states in full is
replaced by a reference to that row; a shorter one is clearer repeated."""


def share_causes(rows: Sequence[WhyRow]) -> list[WhyRow]:
    """Rows whose long cause is contained in an earlier row's cause say "Same cause as <row> (above)." instead."""
    out: list[WhyRow] = []
    for row in rows:
        text = row.cause.strip().rstrip(".")
        earlier = next((r for r in out if len(text) >= REPEATED_CAUSE_MIN and text in r.cause), None)
        same = f"Same cause as {earlier.label} (above)." if earlier is not None else ""
        out.append(dataclasses.replace(row, cause=same) if same else row)
    return out


def _fix_parts(finding: Any) -> tuple[str, ...]:
    """The distinct fixes of a finding (``fixes``; its whole ``fix`` when it does not list them)."""
    parts = tuple(getattr(finding, "fixes", ()) or ())
    if not parts and getattr(finding, "fix", ""):
        parts = (finding.fix,)
    return tuple(dict.fromkeys(unit(p) for p in parts if p.strip()))


def _refs_text(numbers: Sequence[int]) -> str:
    """``"See fix 1 below."``, ``"See fixes 1 and 2 below."``."""
    if len(numbers) == 1:
        return f"See fix {numbers[0]} below."
    return "See fixes " + ", ".join(map(str, numbers[:-1])) + f" and {numbers[-1]} below."


def share_fixes(rows: Sequence[WhyRow], parts: Sequence[tuple[str, ...]]
                 ) -> tuple[tuple[WhyRow, ...], tuple[WhyFix, ...]]:
    """Fixes found under several rows numbered once; those rows keep their own fixes and refer to the shared ones.

    Parameters
    ----------
    rows : sequence of WhyRow
        The rows, their ``fix`` the finding's whole fix.
    parts : sequence of tuple of str
        Each row's distinct fixes.

    Returns
    -------
    rows, fixes : tuple of WhyRow, tuple of WhyFix
        A row with no shared fix is returned as is.
    """
    count: dict[str, int] = {}
    for row_parts in parts:
        for part in row_parts:
            count[part] = count.get(part, 0) + 1
    numbers: dict[str, int] = {}
    for row_parts in parts:
        for part in row_parts:
            if count[part] > 1 and part not in numbers:
                numbers[part] = len(numbers) + 1
    if not numbers:
        return tuple(rows), ()
    out = []
    for row, row_parts in zip(rows, parts, strict=True):
        refs = tuple(dict.fromkeys(numbers[p] for p in row_parts if p in numbers))
        if not refs:
            out.append(row)
            continue
        own = " ".join(p for p in row_parts if p not in numbers)
        out.append(dataclasses.replace(row, fix=(own + " " if own else "") + _refs_text(refs), fix_refs=refs))
    fixes = tuple(WhyFix(k, text, tuple(r.label for r, rp in zip(rows, parts, strict=True) if text in rp))
                  for text, k in numbers.items())
    return tuple(out), fixes


def metric_rows(diagnosis: Any) -> tuple[MetricRow, ...]:
    if diagnosis is None:
        return ()
    return tuple(MetricRow(m.metric, unit(m.unit), m.linear or "undefined", m.nonlinear or "undefined")
                 for m in getattr(diagnosis, "linear_vs_nonlinear", ()))
