"""What a diagnosis says: one :class:`Finding` per failing or undecided required check, the run's
:class:`LimitCycle`, the whole :class:`Diagnosis`, and :func:`shortfall` (by how much a limit is missed)."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Any

from designkit.analysis.diagnosis.comparison import MetricPair
from designkit.display.numbers import TARGET, fmt_number, quantity

__all__ = ["Diagnosis", "Finding", "LimitCycle", "shortfall"]

_LIMIT = re.compile(r"(?:^|\s)(<=|>=|≤|≥)\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)(?=\s|$)")


@dataclass(frozen=True)
class Finding:
    """Why one required check failed or is undecided.

    Parameters
    ----------
    check : str
        The check's name, e.g. ``"overshoot"``.
    status : str
        ``"FAIL"`` or ``"UNDECIDED"``.
    requirement : str
        Human text, e.g. ``"overshoot <= 5 %"``.
    achieved : str
        Formatted with its unit, e.g. ``"168.6 %"``; ``""`` when the check has no value.
    shortfall : str
        Absolute, with unit, e.g. ``"163.6 % over the limit"``; ``""`` when not meaningful.
    shortfall_percent : str
        Relative to the limit, e.g. ``"3272 % of the limit"``; ``""`` when not meaningful.
    cause : str
        Diagnosed cause (one or two sentences), ``""`` when the run shows none.
    fix : str
        What would fix it, with numbers where computable, or ``""``: the sentences of ``fixes`` joined.
    fixes : tuple of str
        The distinct fixes ``fix`` is made of, each a sentence of its own (capitalized, ending with a
        period), in order; a report shows a fix shared by several findings once.
    changes : tuple of (str, tuple of SpecChange)
        The fix sentence of the check's owner (as in ``fixes``) with the changes of the spec its owner declared
        for it (:class:`~designkit.synthesis.spec_change.SpecChange`); empty when the owner declared none (the
        sentence is then read by :data:`~designkit.analysis.diagnosis.remedies.RECOGNIZERS`).
    """

    check: str
    status: str
    requirement: str
    achieved: str
    shortfall: str
    shortfall_percent: str
    cause: str
    fix: str
    fixes: tuple[str, ...] = ()
    changes: tuple[tuple[str, tuple[Any, ...]], ...] = ()


@dataclass(frozen=True)
class LimitCycle:
    """A sustained oscillation of the position at the end of the run.

    Parameters
    ----------
    amplitude : float
        Measured half peak-to-peak of the position over the analysed window (rad).
    frequency : float
        Measured angular frequency (rad/s).
    predicted_amplitude : float or None
        Describing-function prediction of the position's first-harmonic amplitude (rad); None when
        the element has no describing function here or harmonic balance has no solution.
    predicted_frequency : float or None
        Describing-function prediction (rad/s).
    sentence : str
        Measured and predicted values in words.
    """

    amplitude: float
    frequency: float
    predicted_amplitude: float | None
    predicted_frequency: float | None
    sentence: str


@dataclass(frozen=True)
class Diagnosis:
    """What :func:`diagnose` found.

    Parameters
    ----------
    findings : tuple of Finding
        One per failing or undecided required check, in check order.
    diverged : bool
        The nonlinear run diverged.
    divergence : str
        When and how it diverged (``""`` otherwise).
    limit_cycle : LimitCycle or None
    linear_vs_nonlinear : tuple of MetricPair
        Overshoot, settling time, rise time, steady-state error, peak |u| (step runs); max tracking error,
        settling time, final error, peak |u| (trajectory runs).
    root_cause : str
        A cause no controller could remove, stated before everything it explains (``""`` when there is none):
        requirements the actuator cannot meet (the time-optimal settling bound).
    proposed : tuple of ProposedFix
        Every distinct fix sentence of the findings with its remedies re-run through the pipeline
        (:func:`~designkit.analysis.diagnosis.fixes.check_fixes`); empty when not re-simulated.
    """

    findings: tuple[Finding, ...]
    diverged: bool
    divergence: str
    limit_cycle: LimitCycle | None
    linear_vs_nonlinear: tuple[MetricPair, ...]
    root_cause: str = ""
    proposed: tuple[Any, ...] = ()


def shortfall(target: str, margin: float | None, unit: str) -> tuple[str, str]:
    """The absolute and relative shortfall of a violated ``target`` (``""`` when not meaningful).

    Parameters
    ----------
    target : str
        ``"<= limit unit"`` or ``">= limit unit"``.
    margin : float or None
        Signed margin in ``unit``, negative when violated by ``|margin|``.
    unit : str
        Unit of the margin.

    Returns
    -------
    absolute, relative : str
        E.g. ``("163.6 % over the limit", "3272 % of the limit")``.

    Examples
    --------
    >>> shortfall("<= 5 %", -163.59085, "%")
    ('163.6 % over the limit', '3272 % of the limit')
    >>> shortfall("all first-column entries > 0", -1.0, "1 (scaled)")
    ('', '')
    """
    m = TARGET.match(target or "") or _LIMIT.search(target or "")
    if m is None or margin is None or not math.isfinite(margin) or margin >= 0:
        return "", ""
    op, limit = m.group(1), float(m.group(2))
    side = "over" if op in ("<=", "<", "≤") else "under"
    absolute = f"{quantity(-margin, unit)} {side} the limit"
    relative = f"{fmt_number(100.0 * -margin / abs(limit))} % of the limit" if limit != 0 else ""
    return absolute, relative
