"""The rate study in words and a table, written from its rows only."""

from __future__ import annotations

import math

from designkit.display.numbers import fmt_number
from designkit.display.section import Table
from designkit.studies.core.members import amount
from designkit.studies.core.study import Recommended, Row
from designkit.studies.core.words import outcome_words

__all__ = ["count_rate", "holding", "rate_text", "row_sentences", "summary", "table"]


def rate_text(rate: float) -> str:
    """A rate in Hz or kHz: ``"20 kHz"``, ``"500 Hz"``."""
    return f"{fmt_number(rate / 1000.0, 4)} kHz" if rate >= 1000.0 else f"{fmt_number(rate, 4)} Hz"


def count_rate(value: float | None) -> str:
    """A count per second, whole from 10 on (``"5566"``), else to three digits; ``—`` when undefined."""
    if value is None or not math.isfinite(value):
        return "—"
    return f"{value:.0f}" if value >= 10 else fmt_number(value, 3)


def holding(rows: list[Row]) -> Recommended | None:
    """The lowest rate at which the verdict still holds: going down the ladder from its highest rate, the last one
    before the first run whose required checks do not all pass, with every rate down to it (``checked``); None when
    the highest rate's run does not pass."""
    down = sorted(rows, key=lambda r: -float(r.value))
    kept = []
    for r in down:
        if not r.passed:
            break
        kept.append(float(r.value))
    if not kept:
        return None
    return Recommended(kept[-1], kept[-1], kept[0], tuple(sorted(kept)))


def _span(rows: list[Row], key: str, unit_text: str) -> str:
    """``"a at R1 to b at R2"`` from the highest to the lowest rate with a finite value (``"a at R1"`` for one)."""
    pts = [(float(r.value), r.metrics.get(key)) for r in sorted(rows, key=lambda r: -float(r.value))]
    pts = [(f, v) for f, v in pts if v is not None and math.isfinite(v)]
    if not pts:
        return "undefined"

    def text(v: float) -> str:
        return count_rate(v) if unit_text == "1/s" else amount(v, unit_text)

    if len(pts) == 1:
        return f"{text(pts[0][1])} at {rate_text(pts[0][0])}"
    return f"{text(pts[0][1])} at {rate_text(pts[0][0])} to {text(pts[-1][1])} at {rate_text(pts[-1][0])}"


def summary(rows: list[Row], eu: str, cu: str) -> tuple[str, ...]:
    """The verdict across the ladder (the lowest rate at which it still holds), then how the numbers moved."""
    out = []
    if not rows:
        return ("No rate was run.",)
    ordered = sorted(rows, key=lambda r: -float(r.value))
    hold = holding(rows)
    if hold is None:
        first = ordered[0]
        out.append(f"The verdict does not hold even at the highest rate run, {rate_text(first.value)}: "
                   f"{outcome_words(first.outcome, first.detail)}.")
    elif hold.value == float(ordered[-1].value):
        out.append(f"The verdict holds at every rate run, down to the lowest, {rate_text(hold.value)} (every required "
                   "check passes there): the ladder does not reach a rate where it fails.")
    else:
        below = next(r for r in ordered if float(r.value) < hold.value)
        out.append(f"The lowest rate at which the verdict still holds is {rate_text(hold.value)}: every required check "
                   f"passes at each of the {len(hold.checked)} rates from {rate_text(hold.high)} down to it; at "
                   f"{rate_text(below.value)} {outcome_words(below.outcome, below.detail)}.")
        again = [r for r in ordered if float(r.value) < float(below.value) and r.passed]
        if again:
            out.append("Lower still, the verdict holds again at " + ", ".join(rate_text(r.value) for r in again)
                       + ": the outcome is not monotone in the rate.")
    diverged = [r for r in ordered if r.outcome == "diverged"]
    if diverged:
        out.append("Diverged: " + "; ".join(f"{rate_text(r.value)} ({r.detail})" for r in diverged) + ".")
    else:
        out.append("No run diverged.")
    out.append(f"From the highest rate run to the lowest: the steady error (the largest |x − xD| over the last tenth "
               f"of the reference's last plateau) {_span(rows, 'steady_error', eu)}; the RMS of the command's "
               f"switching component {_span(rows, 'chatter_rms', cu)} (its peak {_span(rows, 'chatter_peak', cu)}); "
               f"the reversals per second {_span(rows, 'reversal_rate', '1/s')}; the control effort (RMS of u over "
               f"the run) {_span(rows, 'command_rms', cu)}.")
    return tuple(out)


def row_sentences(rows: list[Row]) -> tuple[str, ...]:
    """How often each run reversed its command against how often it could (once a sample at most)."""
    out = []
    for r in sorted(rows, key=lambda r: -float(r.value)):
        rev = r.metrics.get("reversal_rate")
        if rev is None or not math.isfinite(rev) or r.outcome in ("refused", "not run"):
            continue
        out.append(f"{rate_text(r.value)}: {count_rate(rev)} reversals a second, {fmt_number(rev / r.value, 3)} of "
                   "its samples.")
    if out:
        out.insert(0, "A command held over each period can reverse at most once a sample:")
    return tuple(out)


def table(rows: list[Row], eu: str, cu: str) -> Table:
    """One line per rate, in decreasing rate."""
    from designkit.display.numbers import unit

    def u(text: str) -> str:
        return f" ({unit(text)})" if text else ""

    lines = []
    for r in sorted(rows, key=lambda r: -float(r.value)):
        m = r.metrics
        verdict = r.outcome if not r.detail else f"{r.outcome}: {r.detail}"
        lines.append((rate_text(r.value), amount(m.get("dt"), "s"), verdict, amount(m.get("steady_error"), eu),
                      amount(m.get("chatter_rms"), cu), amount(m.get("chatter_peak"), cu),
                      count_rate(m.get("reversal_rate")), amount(m.get("command_rms"), cu),
                      "yes" if r.outcome == "diverged" else "no"))
    return Table("One run per sampling rate (the command computed once a period and held); the numbers are the "
                 "largest over the tracked coordinates and the inputs",
                 ("rate", "integration step", "verdict", f"steady error{u(eu)}", f"switching RMS{u(cu)}",
                  f"switching peak{u(cu)}", "reversals (1/s)", f"RMS command{u(cu)}", "diverged"), tuple(lines))
