"""How a study writes its rows: a factor, a value with its unit, an outcome, a metric's change."""

from __future__ import annotations

import math
from typing import Any

from designkit.display.numbers import fmt_number, quantity, unit

__all__ = ["change", "factor_verb", "outcome_words", "value_text"]

_VERBS = {0.5: "halving", 2.0: "doubling", 0.1: "dividing by ten", 10.0: "multiplying by ten"}


def factor_verb(factor: float) -> str:
    """``"halving"``, ``"doubling"``, or ``"scaling by 0.8"``."""
    return _VERBS.get(float(factor), f"scaling by {fmt_number(factor, 3)}")


def value_text(value: Any, unit_text: str = "", digits: int = 4) -> str:
    """A knob's value with its unit (per joint: in parentheses)."""
    if isinstance(value, tuple | list):
        inner = ", ".join(fmt_number(v, digits) for v in value)
        return f"({inner}) {unit(unit_text)}".strip()
    return quantity(float(value), unit_text, digits)


def outcome_words(outcome: str, detail: str) -> str:
    """A row's outcome as a clause (``"every required check passes"``, ``"the run fails (overshoot)"``)."""
    if outcome == "verified":
        return "every required check passes"
    if outcome == "failed":
        return f"the run fails ({detail})"
    if outcome == "undecided":
        return f"a required check is undecided ({detail})"
    if outcome == "diverged":
        return f"the run diverges ({detail})"
    if outcome == "refused":
        return f"the family cannot design it ({detail})"
    return f"the run could not be made ({detail})"


def change(before: float | None, after: float | None, unit_text: str) -> str:
    """How a metric moved: ``"×1.8 (0.0113 → 0.0203 rad)"``, ``"unchanged (0.0113 rad)"``."""
    if before is None or after is None:
        return "undefined"
    if math.isinf(after) and not math.isinf(before):
        return f"unbounded (from {quantity(before, unit_text, 3)})"
    if before == 0 or math.isinf(before):
        return f"{quantity(before, unit_text, 3)} → {quantity(after, unit_text, 3)}"
    ratio = after / before
    if abs(ratio - 1) < 0.005:
        return f"unchanged ({quantity(after, unit_text, 3)})"
    return f"×{fmt_number(ratio, 3)} ({quantity(before, unit_text, 3)} → {quantity(after, unit_text, 3)})"
