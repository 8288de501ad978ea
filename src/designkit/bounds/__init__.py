"""Guaranteed bounds of CasADi expressions over boxes: ball arithmetic, the mean-value form, bisection.

``enclose(f, box)`` proves the range of one entry of a CasADi function over a box of its inputs
-- every value of the box lies in ``[lower, upper]`` -- and gives, for each end, a witness point
where the function comes within the requested tolerance of it.  The arithmetic is Arb's
midpoint-radius balls (python-flint), so rounding is accounted for; the expression graph is CasADi's
own (:mod:`designkit.bounds.tape`); the tightening is the mean-value form with CasADi's exact
gradient (:mod:`designkit.bounds.forms`); the search is branch and bound
(:mod:`designkit.bounds.search`).  ``designkit.models.bounds`` applies it to a robot's model
functions (``D(q)`` entries, ``g(q)``, Coriolis torques for bounded velocities).
"""

from __future__ import annotations

from designkit.bounds.box import Box
from designkit.bounds.enclosure import MAX_BOXES, Enclosure, enclose
from designkit.bounds.search import Side

__all__ = ["MAX_BOXES", "Box", "Enclosure", "Side", "enclose"]
