"""The tuning's files: the tuned spec (``<name>-tuned.yaml``) and its HTML report (``<name>-tuning.html``).

The report says, in this order: the verdict; the requirements' worst normalised margins over the box before and
after, and which one is active (limits the design); the tuned values beside the initial ones, with their ranges;
the method, iterations, candidates, simulations and time; the convergence history as a figure; the conflict and
the minimum-time bound when no tuning met every requirement; and the tuned spec's checks (its full verify).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["convergence_svg", "html_text", "write_files"]


def _value(v: Any) -> str:
    arr = np.asarray(v)
    if arr.ndim == 0:
        z = arr.item()
        if isinstance(z, complex):
            return f"{z.real:.4g}{z.imag:+.4g}j" if z.imag else f"{z.real:.4g}"
        return f"{float(z):.4g}"
    return "[" + ", ".join(_value(e) for e in arr) + "]"


def _achieved(check: Any) -> str:
    value = check.achieved
    if value is None:
        return ""
    text = f"{value:.4g}" if isinstance(value, float) else str(value)
    return f"{text} {check.unit}".strip()


def convergence_svg(result: Any) -> str:
    """The best score after each candidate, and each candidate's score (SVG)."""
    from designkit.display.svg import new_figure, tag, to_svg

    hist = result.search.history
    fig, (ax,) = new_figure(6.4, 3.0)
    k = np.arange(1, len(hist) + 1)
    shown = np.maximum(hist[:, 0], -1.5) if len(hist) else hist[:, 0]
    (dots,) = ax.plot(k, shown, ".", color="#9aa7b8", markersize=3, label="candidate (below −1.5 drawn at −1.5)")
    (line,) = ax.plot(k, hist[:, 1], "-", color="#1f4e8c", linewidth=1.6, label="best so far")
    zero = ax.axhline(0.0, color="#b3261e", linewidth=0.8, linestyle="--", label="every requirement met")
    tag(fig, "candidates", dots)
    tag(fig, "best", line)
    tag(fig, "met", zero)
    ax.set_xlabel("candidate")
    ax.set_ylabel("worst normalised margin")
    ax.legend(loc="lower right", fontsize=7)
    return to_svg(fig)


def html_text(result: Any) -> str:
    """The report as one HTML page."""
    from designkit.display.html import esc, heading, para, table

    name = result.loaded.spec.name
    best, initial, s = result.best, result.initial, result.search
    if result.verified:
        verdict = (f"TUNED AND VERIFIED: every requirement holds at the {1 + len(result.points)} plants run, with a "
                   f"worst normalised margin of {best.score:.3g}, and the tuned spec's full verify passes.")
    elif result.met:
        verdict = "TUNED, NOT VERIFIED: the tuned spec's full verify fails " + ", ".join(
            c.name for c in result.verify.failed) + "."
    else:
        verdict = f"NOT MET: no tuning found meets every requirement; the best compromise scores {best.score:.3g}."
    parts = [f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{esc(name)}: tuning</title></head>"
             "<body style='font-family:sans-serif;max-width:60em;margin:1em auto'>",
             f"<h2>{esc(name)}: tuning</h2>", para(verdict)]
    parts.append(heading("Requirements: worst normalised margin over the box"))
    rows = []
    for req in best.margins:
        where = best.worst_point.get(req) or {}
        rows.append((req, f"{initial.margins.get(req, float('nan')):.3g}", f"{best.margins[req]:.3g}",
                     ", ".join(f"{k} = {v:.4g}" for k, v in where.items()) or "nominal",
                     "active" if req == best.active else ""))
    parts.append(table(("requirement", "initial", "tuned", "worst at", ""), rows))
    parts.append(para("A normalised margin is the check's margin over the requirement's limit (1: the whole limit "
                      "to spare; negative: the requirement fails). The active requirement limits the design."))
    parts.append(heading("Tuned values"))
    parts.append(table(("knob", "initial", "tuned"), [(k, _value(initial.values[k]), _value(best.values[k]))
                                                     for k in best.values]))
    parts.append(table(("coordinate", "unit", "range", "initial", "tuned"), [
        (c.label, c.unit, f"[{c.low:.4g}, {c.high:.4g}]", f"{c.initial:.4g}",
         f"{float(np.exp(np.clip(x, np.log(c.low), np.log(c.high)))):.4g}")
        for c, x in zip(result.space.coordinates, best.x, strict=True)]))
    if result.at_bounds:
        parts.append(para("At an end of its range (the range, not a requirement, stops the design there; widen "
                          "tune.ranges to go further): " + ", ".join(result.at_bounds) + "."))
    for k in result.space.kept:
        parts.append(para("Not tuned: " + k))
    parts.append(heading("Search"))
    parts.append(para(f"{s.method}: {s.iterations} iterations, {s.restarts} restarts, {len(s.evaluations)} "
                      f"candidates, {s.simulations} simulations, {s.seconds:.1f} s ({s.stopped}). Every candidate's "
                      f"requirement checks were measured at the nominal plant and at {len(result.points)} other points "
                      "of the box; every candidate that could become the best also ran through the family's own run "
                      "with every check (its certificates)."))
    parts.append(convergence_svg(result))
    if result.conflict is not None:
        parts.append(heading("Why no tuning meets every requirement"))
        parts.append(para(result.conflict.sentence))
        parts.append(table(("requirement", "best alone", "at the compromise"), [
            (r, f"{result.conflict.alone[r]:.3g}", f"{result.conflict.compromise[r]:.3g}")
            for r in result.conflict.alone]))
    if result.bound is not None:
        parts.append(heading("Minimum-time bound of the actuator"))
        parts.append(para(result.bound.sentence))
    if not best.certified and best.failed:
        parts.append(para("The best candidate's certificates that fail: " + ", ".join(best.failed)))
    if result.verify is not None:
        parts.append(heading("The tuned spec's checks (designkit verify)"))
        parts.append(table(("check", "status", "achieved", "target", "margin"), [
            (c.name, c.status, _achieved(c), c.target,
             "" if c.margin is None else f"{c.margin:.4g}") for c in result.verify.checks], status_column=1))
    parts.append("</body></html>")
    return "\n".join(parts)


def write_files(result: Any, out: Path) -> Any:
    """Write the tuned spec and the report into ``out`` (created if needed); the result with ``files`` set.

    Raises
    ------
    OutputError
        ``out`` cannot be written.
    """
    from designkit.errors import OutputError

    name = result.loaded.spec.name
    try:
        out.mkdir(parents=True, exist_ok=True)
        spec_file = out / f"{name}-tuned.yaml"
        html_file = out / f"{name}-tuning.html"
        spec_file.write_text(result.tuned.text, encoding="utf-8")
        html_file.write_text(html_text(result), encoding="utf-8")
    except OSError as exc:
        raise OutputError("out", f"cannot write the tuning's files: {exc.strerror or exc}") from None
    return dataclasses.replace(result, files={"spec": spec_file, "html": html_file})
