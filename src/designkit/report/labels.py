"""The words of the report's tables that no check owns: the glossary of the compliance table and appendix A.

A check's own words are declared by its rule (:attr:`designkit.verification.suite.CheckRule.label`,
``labels`` and ``glossary``) and stamped on each :class:`~designkit.verification.check.Check` by the
runner; :func:`check_label` only reads them.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

__all__ = ["GLOSSARY", "check_label", "glossary"]

GLOSSARY: tuple[tuple[str, str], ...] = (
    ("limit", "the requirement as written in the spec, or the threshold a stability test must clear"),
    ("achieved", "the value measured on the design or the simulation, in the unit of the limit"),
    ("margin", "the signed distance from the achieved value to the limit: positive means the requirement holds "
               "with that much to spare, negative that it is missed by that much; % is relative to the limit"),
    ("shortfall", "how far a failed requirement is missed, in the unit of the limit and in % of the limit"),
    ("scaled", "a dimensionless value after the problem was rescaled (poles by their largest magnitude, "
               "matrices balanced) so that one tolerance applies whatever the units"),
    ("normalised", "a dimensionless value divided by a reference size (e.g. P scaled so that P ≤ I)"),
    ("informational", "a check reported with its status that does not decide the verdict (e.g. the common "
                      "Lyapunov function of a box, sufficient but not necessary for robust stability)"),
    ("UNDECIDED", "the check could not decide (solver not converged, undefined metric): never counted as a pass"),
    ("certificate", "the evidence a check leaves behind (matrices, tables) so that the result can be re-checked"),
)
"""The words every report uses."""


def check_label(check: Any) -> str:
    """A check in words: the label its rule stamped, else its name in words."""
    label = getattr(check, "label", "")
    if label:
        return label
    name = check if isinstance(check, str) else check.name
    return name.replace("_", " ").capitalize()


def glossary(rules: Iterable[Any]) -> tuple[tuple[str, str], ...]:
    """:data:`GLOSSARY` and the terms the run's check rules add, each term once."""
    out = list(GLOSSARY)
    seen = {term for term, _ in out}
    for rule in rules:
        for term, meaning in getattr(rule, "glossary", ()):
            if term not in seen:
                seen.add(term)
                out.append((term, meaning))
    return tuple(out)
