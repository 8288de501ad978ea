"""What the ``state_regulator`` family says of one of its runs when a study asks
(:attr:`designkit.synthesis.family.Family.answers`) and what it predicts in closed form
(:attr:`~designkit.synthesis.family.Family.predictions`): its strategy, and the static offset ``|x - xD| = |C (A -
B K)^-1 D w|`` (the controlled position's unit) a constant load ``w`` of the spec's ``simulation.perturbation``
leaves (no integral action)."""

from __future__ import annotations

import math
from typing import Any

from designkit.display.numbers import fmt_number, fmt_poles
from designkit.families.state_regulator.data import StateRegulatorData
from designkit.synthesis.knobs import Metric

__all__ = ["ANSWERS", "PREDICTIONS", "load_offset", "strategy"]


def strategy(result: Any) -> tuple[str, ...]:
    """The law and what its design needs, with the placed poles (1/s)."""
    info = result.design.data
    if not isinstance(info, StateRegulatorData):
        return ()
    poles = fmt_poles(result.design.poles)
    n_text = (fmt_number(info.N, 4) if not isinstance(info.N, tuple)
              else "(" + ", ".join(fmt_number(v, 4) for v in info.N) + ")")
    how = "Ackermann's formula" if not isinstance(info.N, tuple) else "robust placement (several inputs)"
    return (f"u = −K x + N xD: K places the closed-loop poles {poles} 1/s of x' = (A − B K) x by {how} "
            f"on the plant linearised at rest, N = {n_text} gives the controlled position "
            "a unit static gain; no integral action, so a constant load leaves an offset.",)


def load_offset(result: Any) -> float | None:
    """``|C (A - B K)^-1 D w|`` with ``w`` the spec's constant perturbation (module docstring); None without one."""
    info = result.design.data
    pert = result.loaded.spec.simulation.perturbation
    if not isinstance(info, StateRegulatorData) or pert is None:
        return None
    values = pert.value if isinstance(pert.value, list | tuple) else [pert.value]
    w = max((float(v) for v in values), key=abs)
    value = abs(w * float(info.load_offset_per_unit))
    return value if math.isfinite(value) else None


ANSWERS = (("strategy", strategy),)
"""The topics the family answers (:data:`designkit.synthesis.family.ANSWER_TOPICS`)."""

PREDICTIONS = (Metric("load_offset", "static offset a constant load leaves (closed form)", "rad", load_offset,
                      "|C (A − B K)⁻¹ D w| under the spec's constant perturbation w"),)
"""What the family predicts in closed form for a run."""
