"""The root locus over the gain study: one panel per gain that moves a pole, the closed-loop poles as that gain
is scaled continuously from × 0.5 to × 2 (:func:`designkit.studies.gains.locus.root_locus`)."""

from __future__ import annotations

from typing import Any

import numpy as np

from designkit.display.figure import Figure
from designkit.display.svg import BLUE, GREEN, GREY, ORANGE, new_figure, render_tagged, tag

__all__ = ["TITLE", "WIDTH_IN", "root_locus_figure"]

WIDTH_IN = 4.6
"""Figure width (in): 8 pt text is 10 px when the figure is shown 420 px wide."""
PANEL_IN = 2.2
"""Height per panel (in)."""


def _moving(locus: Any) -> bool:
    span = float(np.max(np.abs(locus.poles[-1] - locus.poles[0])))
    return span > 1e-6 * max(1.0, float(np.max(np.abs(locus.poles))))


def _draw(loci: tuple[Any, ...], nominal: np.ndarray) -> Any:
    fig, axes = new_figure(WIDTH_IN, 0.4 + PANEL_IN * len(loci), rows=len(loci), sharex=False, layout="constrained")
    for k, (ax, locus) in enumerate(zip(axes, loci, strict=True)):
        p = locus.poles
        ax.axvline(0.0, color=GREY, lw=0.8)
        ax.axhline(0.0, color=GREY, lw=0.8)
        lines = ax.plot(p.real, p.imag, "-", color=BLUE, lw=1.2)
        tag(fig, "locus", *lines)
        (lo,) = ax.plot(p[0].real, p[0].imag, "o", ms=6, mfc="none", mec=ORANGE, mew=1.4, ls="none",
                        label="× 0.5")
        (hi,) = ax.plot(p[-1].real, p[-1].imag, "s", ms=6, mfc="none", mec=GREEN, mew=1.4, ls="none",
                        label="× 2")
        (mid,) = ax.plot(nominal.real, nominal.imag, "x", ms=7, color="black", mew=1.6, ls="none",
                         label="× 1 (design)")
        tag(fig, "half", lo)
        tag(fig, "double", hi)
        tag(fig, "nominal", mid)
        ax.set_ylabel("Im s (rad/s)")
        ax.set_title(f"{locus.name} scaled × 0.5 → × 2", fontsize=9)
        if k == 0:
            ax.legend(loc="upper left", ncols=3, framealpha=0.9, fontsize=8)
        ax.set_xlabel("Re s (1/s)")
        pts = p.ravel()
        im = max(float(np.max(np.abs(pts.imag))), 0.15 * float(np.ptp(pts.real)), 1e-3)
        ax.set_ylim(-1.5 * im, 1.5 * im)
    return fig


TITLE = "Root locus over the gain study"
"""The figure's title, which the gain study's answer names when it describes the locus."""


def root_locus_figure(result: Any, rl: Any) -> Figure | None:
    """The root-locus figure of the gain study from its locus ``rl``
    (:func:`designkit.studies.gains.locus.root_locus`): None when no gain moves a pole."""
    from designkit.studies.gains.locus import POINTS

    if rl is None:
        return None
    loci = tuple(locus for locus in rl.loci if _moving(locus))
    if not loci:
        return None
    still = [locus.name for locus in rl.loci if not _moving(locus)]
    svg, _, _ = render_tagged(_draw, loci, rl.nominal)
    caption = (f"Closed-loop poles of the true plant with the law linearized at the design's operating point, each "
               f"gain scaled on every joint over {POINTS} log-spaced factors from × 0.5 to × 2 (lines), the others as "
               "designed: × the design's poles, ○ at × 0.5, □ at × 2 (the gain study's runs). "
               + " ".join(rl.sentences[i] for i, locus in enumerate(rl.loci) if _moving(locus)))
    if still:
        caption += f" {', '.join(still)} moves no pole (not drawn)."
    return Figure(TITLE, caption, svg, "fig-root-locus.svg", ())
