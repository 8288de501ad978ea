"""Judging a statement ``value < bound`` on a proved bracket ``lower <= value <= upper``: the rule every bracketed
certificate shares.

A certificate of this shape has a **proof route** -- a lower bound and an upper bound, each a true bound of the
value whatever the estimate -- and, often, **secondary routes** (an iterative estimate and its independent re-check)
that say where inside the bracket the value lies.  The rule:

* **FAIL** when the lower bound exceeds the bound by more than the boundary tolerance: the statement is proved
  false, whatever a secondary route says (an unconverged iteration that disagrees with another is no evidence
  against a proof);
* **PASS** when the upper bound lies below the bound by more than the boundary tolerance *and* the secondary routes
  agree (a disagreement there leaves a passing bracket unconfirmed, since a missed top of a spectrum would also be
  missed by a bound built from the same computation);
* **UNDECIDED** otherwise, saying why: the bracket contains the bound; or an end of it lies within
  :data:`~designkit.verification.tolerances.BOUNDARY_REL` of the bound -- a margin below the precision of the
  bounds proves nothing, however it is computed; or the routes disagree on a passing bracket.

``margin = bound - upper`` and ``excess = lower - bound`` are taken as the caller computed them, without
cancellation where it matters (``1 - rho`` from ``alpha sigma^2`` directly).
"""

from __future__ import annotations

from dataclasses import dataclass

from designkit.verification.tolerances import BOUNDARY_REL

__all__ = ["BracketVerdict", "bracket_verdict"]


@dataclass(frozen=True)
class BracketVerdict:
    """The verdict on ``value < bound`` and why.

    Attributes
    ----------
    passed : bool or None
        True proved, False proved false, None undecided.
    reason : str
        ``"proved"``, ``"proved_false"``, ``"boundary"`` (an end of the bracket within the tolerance of the bound),
        ``"routes"`` (a passing bracket the secondary routes do not confirm) or ``"bracket"`` (it contains the
        bound).
    tolerance : float
        The boundary tolerance applied, in the unit of the bound.
    """

    passed: bool | None
    reason: str
    tolerance: float

    @property
    def explanation(self) -> str:
        """The reason in words (empty for a decided verdict)."""
        tol = f"{self.tolerance:.2g}"
        return {
            "boundary": f"an end of the proved bracket lies within {tol} of the boundary, below the precision of the "
                        "bounds: not a proof either way",
            "routes": "the proved bracket passes but the secondary routes to the value disagree",
            "bracket": "the proved bracket contains the boundary",
        }.get(self.reason, "")


def bracket_verdict(margin: float, excess: float, *, bound: float = 1.0, routes_agree: bool = True) -> BracketVerdict:
    """The verdict on ``value < bound`` from ``margin = bound - upper`` and ``excess = lower - bound`` (module
    docstring).

    Parameters
    ----------
    margin : float
        ``bound - upper`` (positive: the upper bound is below the bound).
    excess : float
        ``lower - bound`` (positive: the lower bound is above it).
    bound : float
        The bound, which scales the tolerance (``BOUNDARY_REL |bound|``, at least ``BOUNDARY_REL``).
    routes_agree : bool
        Whether the secondary routes confirm the estimate (only a pass needs it).

    Examples
    --------
    >>> bracket_verdict(4.5e-13, -4.6e-13).reason
    'boundary'
    >>> bracket_verdict(-0.03, 0.0317, routes_agree=False).passed
    False
    """
    tol = BOUNDARY_REL * max(abs(float(bound)), 1.0)
    if excess > tol:
        return BracketVerdict(False, "proved_false", tol)
    if margin > tol:
        return BracketVerdict(True, "proved", tol) if routes_agree else BracketVerdict(None, "routes", tol)
    if margin > 0 or excess > 0 or abs(margin) <= tol or abs(excess) <= tol:
        return BracketVerdict(None, "boundary", tol)
    return BracketVerdict(None, "bracket", tol)
