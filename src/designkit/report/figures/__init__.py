"""Report figures as deterministic SVG text (matplotlib, imported lazily).

The report draws the design's own figures (:data:`DESIGN_FIGURES`: the pole-zero map and the ideal
linear response, when the design's linearization contract gives a loop, and the nonlinear simulation
per joint), and lays out the figures others contribute (:mod:`~designkit.report.figures.tables`): the
family's (``Family.figures``: a phase portrait, adaptation traces, the error per trial) and each check
rule's (``CheckRule.figures``: the loop margins' Bode and sensitivity plots, the robustness lattice, the
intercoupling, the conditioning along a path, the workspace), drawn by the modules that own them.

One module per kind of figure: :mod:`~designkit.report.figures.pole_zero`,
:mod:`~designkit.report.figures.linear` and :mod:`~designkit.report.figures.simulation`.

Captions are written from what is drawn: every artist a caption may name is tagged with a key
(:func:`~designkit.display.svg.tag`, written as the SVG id ``dk-<key>``), and the caption is built from
the keys of the artists actually drawn (plus what the drawing measured, e.g. a symmetric-log control
axis), so no envelope, limit or marker is named when it is absent.  Line styles are distinct:
references dash-dot, limits dashed, events (a perturbation's onset, crossovers) dotted verticals.
Every :class:`~designkit.display.figure.Figure` names the checks it is evidence for (``evidence``), and
the windows and levels drawn are the checks' own (the steady-state window is the last
:data:`~designkit.verification.tolerances.STEADY_STATE_WINDOW` of the run, the rise-time markers the
:data:`~designkit.verification.tolerances.RISE_LIMITS` crossings).

Analysis is never done here: margins, frequency responses, stability over the lattice and the
decoupled predictions are computed by the checks (:mod:`designkit.verification`); figures only
draw them, and every caption is written from what is drawn.  Rendering (rc settings, palette,
byte-for-byte reproducible SVG, decimation) lives in :mod:`designkit.display.svg`, the line styles
and the off-scale rule in :mod:`designkit.display.figure`.

Any finite value a spec accepts can be drawn: a requirement or element level far from the signals
(more than :data:`~designkit.display.figure.OFF_SCALE` times their extent, e.g. a 1e6 N*m saturation
on a 30 N*m command) is named in the legend as "off scale" instead of squashing the signals or
overflowing matplotlib's axis arithmetic, and signal samples beyond
:data:`~designkit.display.svg.MAX_DRAWN` are left out.
"""

from designkit.report.figures.tables import DESIGN_FIGURES, design_figures

__all__ = ["DESIGN_FIGURES", "design_figures"]
