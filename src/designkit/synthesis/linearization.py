"""What a design's linearization means: the contract every linear check and analysis honours.

A smooth fixed-gain law composed with the plant has an equilibrium and a Jacobian that *are* the
small-signal loop: its poles, Lyapunov function, margins and robustness lattice describe the run.
Two kinds of law break that:

* an **adaptive** law integrates its own gains: at any rest point the output error is zero, so
  every value of the adapted parameters is an equilibrium and the Jacobian has one zero
  eigenvalue per parameter -- "marginally stable" whatever the design.  What a linear check can
  honestly say is how the loop behaves with the adaptation **frozen** at stated parameter values:
  the initial ones (the loop the run starts with) and the final ones (the loop it ends with);
* a **switching** law (a sliding-mode ``sign``) has no derivative on its switching surface, where
  it spends its life: its Jacobian there describes neither structure (it can show, e.g., a
  saddle for a loop that converges), so **no** linear check is offered at all.

:class:`Linearization` states which of the three holds.  ``exact``: ``design.closed_loop`` is the
loop.  ``frozen``: ``design.closed_loop`` is the loop of ``freeze(initial)`` -- the law with its
adapted parameters held at their initial values -- and the checks say so; ``freeze(values)`` gives
the fixed-gain law at any other values (the final ones, read from the run's controller states named
``parameters``).  ``none``: the design has no closed loop, input loop or characteristic, and the
checks that need one are not offered (:attr:`designkit.verification.registry.CheckRule.linear`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

__all__ = ["EXACT", "Linearization"]

KINDS = ("exact", "frozen", "none")


@dataclass(frozen=True)
class Linearization:
    """The linearization contract of a design (module docstring).

    Parameters
    ----------
    kind : {"exact", "frozen", "none"}
    reason : str
        In words: why there is none (``"the law switches on s = 0 ..."``), or what is frozen.
    parameters : tuple of str
        ``frozen``: the adapted parameters, named as the law's controller states.
    initial : tuple of float
        ``frozen``: their initial values (and the values ``design.closed_loop`` is computed at).
    units : tuple of str
        ``frozen``: their units.
    freeze : callable or None
        ``frozen``: ``values -> Law``, the fixed-gain law with the adaptation held at ``values``.
    """

    kind: str = "exact"
    reason: str = ""
    parameters: tuple[str, ...] = ()
    initial: tuple[float, ...] = ()
    units: tuple[str, ...] = ()
    freeze: Callable[[Sequence[float]], Any] | None = None

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"linearization kind must be one of {KINDS}, got {self.kind!r}")
        object.__setattr__(self, "parameters", tuple(self.parameters))
        object.__setattr__(self, "initial", tuple(float(v) for v in self.initial))
        object.__setattr__(self, "units", tuple(self.units) or ("",) * len(self.parameters))
        if self.kind == "frozen" and (self.freeze is None or not self.parameters
                                      or len(self.initial) != len(self.parameters)):
            raise ValueError("a frozen linearization needs its parameters, their initial values and freeze()")
        if self.kind == "none" and not self.reason:
            raise ValueError("a design without a linearization must say why (reason)")

    @property
    def linear(self) -> bool:
        """True when the design has a linear loop to check (``exact`` or ``frozen``)."""
        return self.kind != "none"

    def describe(self, values: Sequence[float] | None = None) -> str:
        """``"with the adaptation frozen at a1 = 2, a2 = 3"`` (``frozen``), ``""`` (``exact``), the reason
        (``none``)."""
        if self.kind == "exact":
            return ""
        if self.kind == "none":
            return self.reason
        vals = self.initial if values is None else tuple(values)
        parts = ", ".join(f"{n} = {v:.6g}{(' ' + u) if u else ''}"
                          for n, v, u in zip(self.parameters, vals, self.units, strict=True))
        return f"with the adaptation frozen at {parts}"


EXACT = Linearization()
"""The contract of a smooth fixed-gain law."""
