"""Presentation primitives every layer may use to contribute figures and sentences of its own.

This package sits at the bottom of the layer order: it imports the standard library, NumPy,
matplotlib (lazily, inside functions) and :mod:`designkit.errors` only, never another designkit
package, so verification checks, simulation elements and controller families can draw and write
with it without importing the report.

* :mod:`~designkit.display.numbers` -- numbers, complex numbers, units and quantities as text;
* :mod:`~designkit.display.typeset` -- formulas typeset from plain text (:func:`~designkit.display.typeset.equation`);
* :mod:`~designkit.display.svg` -- deterministic SVG rendering (rc settings, palette, tags, decimation);
* :mod:`~designkit.display.figure` -- the :class:`~designkit.display.figure.Figure` value and the drawing
  conventions (line styles, off-scale levels, ticks);
* :mod:`~designkit.display.heatmap` -- a margin over a parameter lattice, from a certificate's ``grid``.
"""
