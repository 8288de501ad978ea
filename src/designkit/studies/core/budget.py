"""How much a study may run: the work of one variant estimated before it starts, then measured.

A variant is a whole run of the spec (design, simulation or trials, every check), so before any has run its cost is
the larger of the spec's own run as measured (``result.seconds``: the design, the run and the checks, proofs
included) and the spec's work estimate (:func:`designkit.schema.budget.estimate`: the simulations, the lattice and
the Lyapunov LMIs, without the imports a process pays once and the model a run builds once), and never less than
:data:`VARIANT_FLOOR`, the design and checks of a one-link variant measured on the development machine.  Once
variants have run, the mean of their measured wall times replaces it.  A study plans
its variants with :meth:`Budget.affords` before it runs them and says what it left out.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

__all__ = ["VARIANT_FLOOR", "Budget", "Meter", "variant_estimate"]

VARIANT_FLOOR = 0.25
"""Seconds one variant costs at least: the design and checks of a one-link spec (0.1 to 0.2 s measured warm on
the development machine for the MRAC, PID and sliding-mode links), rounded up."""

_ONCE = ("fixed work", "model build")


def variant_estimate(spec: Any, base_dir: Any = None, measured: float = 0.0) -> float:
    """Seconds one run of ``spec`` is expected to cost inside a process that has run it once (module docstring);
    ``measured``: the spec's own run (s)."""
    from designkit.schema.budget import estimate

    work = sum(t.seconds for t in estimate(spec, base_dir).terms if t.what not in _ONCE and t.what != "studies")
    return max(work, VARIANT_FLOOR, float(measured))


@dataclass
class Meter:
    """The wall times of every variant the studies of one run have run (s), shared by them: a later study plans
    with what the earlier ones measured."""

    times: list[float] = field(default_factory=list)

    @property
    def mean(self) -> float | None:
        """Mean wall time of a variant so far (s), None before any has run."""
        return sum(self.times) / len(self.times) if self.times else None


@dataclass
class Budget:
    """The seconds a study may spend, what it has spent, and what one more variant is expected to cost.

    Parameters
    ----------
    seconds : float
        The study's budget (s).
    estimate : float
        One variant's cost before any has run (s, :func:`variant_estimate`).
    """

    seconds: float
    estimate: float
    meter: Meter = field(default_factory=Meter)
    spent: float = 0.0
    runs: int = 0

    @property
    def per_run(self) -> float:
        """Expected seconds of the next variant: the estimate until one has run (in any study of the run), then the
        measured mean."""
        mean = self.meter.mean
        return self.estimate if mean is None else max(VARIANT_FLOOR / 2, mean)

    def capacity(self) -> int:
        """How many more variants fit (at :attr:`per_run` each)."""
        left = self.seconds - self.spent
        return max(0, int(left / self.per_run + 1e-9)) if self.per_run > 0 else 0

    def affords(self, n: int = 1) -> bool:
        """Whether ``n`` more variants fit."""
        return self.capacity() >= n

    def record(self, seconds: float) -> None:
        """A variant ran in ``seconds``."""
        self.spent += seconds
        self.runs += 1
        self.meter.times.append(float(seconds))
