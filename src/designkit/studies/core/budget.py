"""How much a study may run: the work of one variant estimated before it starts, deterministically.

A variant is a whole run of the spec (design, simulation or trials, every check) with a new law, so its cost is
estimated from the spec itself (:func:`variant_estimate`): the spec's work estimate
(:func:`designkit.schema.budget.estimate`: the simulations, the lattice and the Lyapunov LMIs, without the imports a
process pays once and the model it builds once), plus the new law's compiled functions (:data:`COMPILE` times the
model's size), and never less than :data:`VARIANT_FLOOR`.  A study plans its variants with :meth:`Budget.affords`
on that estimate, so the same spec gets the same study on any machine, and says what it left out.

The measured processor time (:func:`cpu_seconds`: this process's and its compilers', not the wall clock, so that
other work on a loaded machine does not shorten a study) is kept as a safety net only: when the variants run have
taken more than :data:`SAFETY` times the budget (a family's proof the estimate does not see, a machine far slower
than the development one), the study stops where it is and says so (:attr:`Budget.overrun`).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any

__all__ = ["COMPILE", "SAFETY", "VARIANT_FLOOR", "Budget", "cpu_seconds", "variant_estimate"]

VARIANT_FLOOR = 0.25
"""Seconds one variant costs at least: the design and checks of a one-link spec (0.1 to 0.2 s measured warm on
the development machine for the MRAC, PID and sliding-mode links), rounded up."""
COMPILE = 0.2
"""Seconds a new law's compiled step costs per unit of model size (the one-link Dormand--Prince library: 0.2 s
measured); a variant's gains are new constants, so its functions are new."""
SAFETY = 4.0
"""A study stops when its variants' measured processor time exceeds this many times its budget (a variant's linear
algebra may run on two threads: its processor time can be up to twice its wall time on an idle machine)."""

_ONCE = ("fixed work", "model build")


def cpu_seconds() -> float:
    """Processor seconds (user and system) of this process and of the children it has waited for (the C compiler
    building a law's library), since the process started."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def variant_estimate(spec: Any, base_dir: Any = None) -> float:
    """Seconds one variant of ``spec`` is estimated to cost inside a process that has run the spec once (module
    docstring)."""
    from designkit.schema.budget import estimate, size

    est = estimate(spec, base_dir)
    work = sum(t.seconds for t in est.terms if t.what not in _ONCE)
    return max(work + COMPILE * size(est.joints), VARIANT_FLOOR)


@dataclass
class Budget:
    """The seconds a study may spend, the variants it has planned and run, and what they measured.

    Parameters
    ----------
    seconds : float
        The study's budget (s).
    estimate : float
        One variant's estimated cost (s, :func:`variant_estimate`).
    """

    seconds: float
    estimate: float
    runs: int = 0
    spent: float = 0.0

    @property
    def per_run(self) -> float:
        """Estimated seconds of one variant."""
        return self.estimate

    def capacity(self) -> int:
        """How many more variants the budget fits, on the estimate (deterministic)."""
        left = self.seconds - self.runs * self.estimate
        return max(0, int(left / self.estimate + 1e-9))

    def affords(self, n: int = 1) -> bool:
        """Whether ``n`` more variants fit on the estimate and the safety net has not tripped."""
        return not self.overrun and self.capacity() >= n

    @property
    def overrun(self) -> bool:
        """The variants have taken more than :data:`SAFETY` times the budget (measured): stop."""
        return self.spent > SAFETY * self.seconds

    def overrun_words(self) -> str:
        """Why a study stopped early, in words."""
        return (f"the {self.runs} variants run took {self.spent:.3g} s of processor time, more than {SAFETY:g} "
                f"times the budget of {self.seconds:.3g} s (estimated at {self.estimate:.2g} s each): "
                "the study stopped there")

    def record(self, seconds: float) -> None:
        """A variant ran in ``seconds`` (processor time, :func:`cpu_seconds`)."""
        self.spent += seconds
        self.runs += 1
