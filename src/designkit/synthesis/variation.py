"""A design with other gains: its law, and the linear loop the law gives, rebuilt.

A study varies a design's gains everything else equal (:mod:`designkit.studies`); the design it runs must then be
the one those gains make: the law built from them by the family's ``law``, the closed loop linearized again at the
design's operating point.  The requested poles and zeros no longer apply and are dropped (the achieved ones are the
closed loop's), so no check compares the variant with a request it was not designed for.  A family whose design has
more structure (per-joint loops) rebuilds it itself (``Family.regain``), with this function per loop.
"""

from __future__ import annotations

import dataclasses
from typing import Any

__all__ = ["with_gains"]


def with_gains(design: Any, gains: Any, law_of: Any, anti_windup: Any = None) -> Any:
    """``design`` with ``gains`` (a :class:`~designkit.synthesis.design.Gains`) and its law and linear loop
    rebuilt (module docstring).

    Raises
    ------
    ValueError
        The design has per-joint loops or a frozen (adaptive) linearization: its family must rebuild it
        (``Family.regain``).
    """
    from designkit.synthesis.closed_loop import with_closed_loop, with_law

    lin = design.linearization
    if design.loops:
        raise ValueError("a design with per-joint loops is rebuilt by its family (Family.regain)")
    if lin.kind == "frozen":
        raise ValueError("an adaptive design's frozen loop is rebuilt by its family (Family.regain)")
    changed = dataclasses.replace(design, gains=gains)
    law = law_of(changed, anti_windup)
    if lin.kind == "exact" and design.closed_loop is not None:
        op = design.operating_point
        changed = dataclasses.replace(changed, poles=(), zeros=())
        return with_closed_loop(changed, law, op["r"], z0=[*op["x"], *op["xc"]], linearization=lin)
    return with_law(changed, law, lin)
