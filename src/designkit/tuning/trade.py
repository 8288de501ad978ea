"""The trade-off along the tuning's final direction: the straight line, in the tuner's log coordinates, from the
spec's own values (step 0) to the tuned ones (step 1), extended a quarter beyond each end; at each of a handful of
steps the family's own runs measure every requirement's worst normalised margin over the box's points, as the
search measured its candidates (:func:`designkit.tuning.evaluate.evaluate`, without the certificates)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["FLOOR", "STEPS", "Trade", "trade_off", "trade_svg"]

STEPS = (-0.25, 0.0, 0.25, 0.5, 0.75, 1.0, 1.25)
"""Steps along the direction (0: the spec's values, 1: the tuned values)."""
FLOOR = -3.0
"""Margins below it are drawn at it (already compressed below -1 by the cost, ``-1 - ln(-m)``)."""


@dataclass(frozen=True, eq=False)
class Trade:
    """Requirement margins along the final direction.

    Parameters
    ----------
    steps : ndarray
        The steps run (0 the initial point, 1 the tuned point).
    clipped : ndarray of bool
        The step's point left the coordinates' ranges and was clipped to them (what the search would run there).
    margins : dict
        Requirement -> its worst normalised margin over the box's points at each step (NaN: not measured, the
        candidate being refused or diverged before it).
    scores : ndarray
        The smallest of them at each step (the search's score without the certificates).
    failed : tuple of str
        Per step, why it was not measured ("" when it was).
    """

    steps: np.ndarray
    clipped: np.ndarray
    margins: dict[str, np.ndarray]
    scores: np.ndarray
    failed: tuple[str, ...]

    def to_json(self) -> dict[str, Any]:
        """As JSON values (NaN as None)."""
        def plain(a: np.ndarray) -> list[float | None]:
            return [float(v) if np.isfinite(v) else None for v in np.asarray(a, dtype=float)]

        return {"steps": [float(s) for s in self.steps], "clipped": [bool(c) for c in self.clipped],
                "margins": {k: plain(v) for k, v in self.margins.items()}, "scores": plain(self.scores),
                "failed": list(self.failed)}


def trade_off(problem: Any, space: Any, x0: np.ndarray, x1: np.ndarray, steps: tuple[float, ...] = STEPS) -> Any:
    """The margins along ``x0 + s (x1 - x0)`` for each step ``s`` (:class:`Trade`), or None when the tuned point is
    the initial one (no direction)."""
    from designkit.tuning.evaluate import evaluate

    x0, x1 = np.asarray(x0, dtype=float), np.asarray(x1, dtype=float)
    if not np.any(np.abs(x1 - x0) > 1e-12):
        return None
    lo, hi = space.bounds
    names = problem.requirements
    margins = {k: np.full(len(steps), np.nan) for k in names}
    scores = np.full(len(steps), np.nan)
    clipped = np.zeros(len(steps), dtype=bool)
    failed = []
    for i, s in enumerate(steps):
        x = x0 + float(s) * (x1 - x0)
        xc = np.clip(x, lo, hi)
        clipped[i] = bool(np.any(np.abs(xc - x) > 1e-12))
        ev = evaluate(problem, space, xc, above=np.inf)
        stopped = any(f.startswith(("refused", "diverged", "not run")) for f in ev.failed)
        measured = not stopped and bool(np.isfinite(ev.score))
        reason = "" if measured else "; ".join(ev.failed) or "not measured"
        failed.append(reason)
        if measured:
            for k in names:
                margins[k][i] = ev.margins[k]
            scores[i] = ev.score
    return Trade(np.asarray(steps, dtype=float), clipped, margins, scores, tuple(failed))


def trade_svg(trade: Any) -> str:
    """Each requirement's worst normalised margin against the step along the final direction (SVG)."""
    from designkit.display.svg import new_figure, tag, to_svg

    fig, (ax,) = new_figure(6.4, 3.0)
    for k, m in trade.margins.items():
        (line,) = ax.plot(trade.steps, np.maximum(m, FLOOR), "o-", markersize=3, linewidth=1.2, label=k)
        tag(fig, f"margin-{k}", line)
    lost = np.array([bool(f) for f in trade.failed])
    if lost.any():
        (gone,) = ax.plot(trade.steps[lost], np.full(int(lost.sum()), FLOOR), "x", color="#b3261e", markersize=7,
                          label="not measured (refused or diverged)")
        tag(fig, "not-measured", gone)
    pad = 0.05 * float(trade.steps[-1] - trade.steps[0])
    ax.set_xlim(float(trade.steps[0]) - pad, float(trade.steps[-1]) + pad)
    zero = ax.axhline(0.0, color="#b3261e", linewidth=0.8, linestyle="--", label="requirement's limit")
    tag(fig, "limit", zero)
    for s, text in ((0.0, "initial"), (1.0, "tuned")):
        ax.axvline(s, color="#9aa7b8", linewidth=0.8, linestyle=":")
        ax.annotate(text, (s, 1.0), fontsize=7, ha="center", va="bottom", xycoords=("data", "axes fraction"))
    ax.set_xlabel("step along the line from the initial to the tuned values (log coordinates)")
    ax.set_ylabel("worst normalised margin")
    ax.legend(loc="best", fontsize=7)
    return to_svg(fig)
