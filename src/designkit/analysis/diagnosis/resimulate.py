"""A proposed fix run again through the whole pipeline: design, checks, simulation on the true plant.

:func:`try_remedy` applies a :class:`~designkit.analysis.diagnosis.remedies.Remedy` to the spec's own YAML
(:func:`designkit.runner.variants.changed_spec`: the key paths set, validated by the same loader), runs it as
the pipeline does (:func:`designkit.runner.run.run_spec`: the true plant, the family's design, the simulation
with its duration and settings, the trials of a learning law, every check the family offers) and returns a
:class:`FixTrial`: whether every required check passes, the checks that failed before with their measured value
against the requirement now, any required check the fix breaks, and the loop margins of the fixed design (the
``loop_margins`` check's certificate: gain, phase and modulus margin per plant input).  At most
:data:`MAX_FIX_RUNS` fixes are re-run per diagnosis, each with the spec's own duration.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from designkit.analysis.diagnosis.remedies import Remedy
from designkit.display.numbers import fmt_number, plain_complex, quantity, unit

__all__ = ["MAX_FIX_RUNS", "CheckOutcome", "FixTrial", "LoopMargin", "rerun", "try_remedy"]

MAX_FIX_RUNS = 6
"""At most this many proposed fixes are re-run per diagnosis (each a whole pipeline run of the spec's duration);
the others are said to be not re-simulated."""


@dataclass(frozen=True)
class CheckOutcome:
    """A required check of the fixed spec.

    Parameters
    ----------
    name, label : str
    requirement : str
        The check's target, typeset (``"≤ 5 %"``).
    measured : str
        Its achieved value with its unit (``"4.5 %"``), ``"undefined"`` when it has none.
    status : str
        ``PASS``, ``FAIL`` or ``UNDECIDED``.
    failed_before : bool
        The check failed (or was undecided) on the original spec.
    """

    name: str
    label: str
    requirement: str
    measured: str
    status: str
    failed_before: bool
    value: float | None = None


@dataclass(frozen=True)
class LoopMargin:
    """The margins of one loop of the fixed design, broken at plant input ``input`` (formatted, ``"∞"`` when the
    loop has no crossover; ``gain_margin`` names itself: a *lower* gain margin, below 1, is the factor below
    which a conditionally stable loop goes unstable)."""

    input: str
    gain_margin: str
    phase_margin: str
    modulus_margin: str


@dataclass(frozen=True)
class FixTrial:
    """A remedy re-run.

    Parameters
    ----------
    remedy : Remedy
    passed : bool
        Every required check of the fixed spec passes (the CLI would exit 0).
    outcomes : tuple of CheckOutcome
        The checks that failed before, then any other required check that fails now.
    margins : tuple of LoopMargin
        Empty when the family offers no loop-margin check (the reason is in ``margins_note``).
    margins_note : str
    error : str
        Why the fixed spec could not be run (``""`` when it ran).
    seconds : float
        Wall time of the re-run (s).
    """

    remedy: Remedy
    passed: bool
    outcomes: tuple[CheckOutcome, ...]
    margins: tuple[LoopMargin, ...]
    margins_note: str
    error: str
    seconds: float

    @property
    def verdict(self) -> str:
        """The re-run's outcome in words: what passes, or what still fails, measured against its requirement."""
        if self.error:
            return f"could not be re-run: {self.error}"
        failing = [o for o in self.outcomes if o.status != "PASS"]
        if not failing:
            shown = "; ".join(f"{o.label.lower()} {o.measured} ({o.requirement})" for o in self.outcomes)
            return "every required check passes" + (f": {shown}" if shown else "")
        return "still fails: " + "; ".join(f"{o.label.lower()} {o.measured} against {o.requirement}"
                                           + ("" if o.failed_before else " (passed before)") for o in failing)



def rerun(loaded: Any) -> Any:
    """Run a spec as :func:`designkit.pipeline.run` does (:func:`designkit.runner.run.run_spec`), with every check but
    those of the code the spec's own design ships (``generated_code``: a fix's design is not the one ``designkit
    codegen`` writes until the spec is changed; :attr:`designkit.verification.suite.Context.verdict_run`)."""
    from designkit.runner.run import run_spec

    return run_spec(loaded)


def _measured(check: Any) -> str:
    value = check.achieved
    if isinstance(value, int | float) and not isinstance(value, bool):
        return quantity(float(value), check.unit)
    if isinstance(value, str) and value:
        return plain_complex(value)
    return "undefined"


def _outcome(check: Any, failed_before: bool) -> CheckOutcome:
    label = getattr(check, "label", "") or check.name.replace("_", " ")
    value = float(check.achieved) if isinstance(check.achieved, int | float) and not isinstance(check.achieved, bool) \
        else None
    target = unit(check.target or "").replace("<=", "≤").replace(">=", "≥")
    return CheckOutcome(check.name, label, target, _measured(check), check.status, failed_before,
                        value)


def _margin(value: Any, fmt: str) -> str:
    return "∞" if value is None else fmt.format(fmt_number(float(value), 3))


def margins_of(checks: Sequence[Any]) -> tuple[tuple[LoopMargin, ...], str]:
    """The loop margins per plant input from the ``loop_margins`` check, or why there are none."""
    check = next((c for c in checks if c.name == "loop_margins"), None)
    if check is None:
        return (), "no loop margins: the family offers no loop-margin check"
    cert = check.certificate if hasattr(check.certificate, "get") else {}
    loops = cert.get("loops") or ()
    out = []
    for loop in loops:
        gm, db = loop.get("gain_margin"), loop.get("gain_margin_db")
        gain = "gain margin ∞" if gm is None else (
            f"{'lower ' if gm < 1 else ''}gain margin ×{fmt_number(float(gm), 3)} ({fmt_number(float(db), 3)} dB)")
        out.append(LoopMargin(str(loop.get("input", "")), gain, _margin(loop.get("phase_margin_deg"), "{}°"),
                              _margin(loop.get("modulus_margin"), "{}")))
    return tuple(out), "" if out else f"the loop-margin check gives no margins ({check.detail})"


def try_remedy(result: Any, remedy: Remedy) -> FixTrial:
    """Re-run ``result``'s spec changed by ``remedy`` and compare its required checks with the original run's."""
    from designkit.errors import DesignkitError

    failed_before = {c.name for c in result.checks if c.required and c.passed is not True}
    start = time.perf_counter()
    try:
        from designkit.runner.variants import changed_spec

        fixed = rerun(changed_spec(result.loaded, remedy.changes))
    except (DesignkitError, ValueError, RuntimeError, ArithmeticError) as exc:
        message = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        return FixTrial(remedy, False, (), (), "", message, time.perf_counter() - start)
    seconds = time.perf_counter() - start
    required = [c for c in fixed.checks if c.required]
    before = [c for c in required if c.name in failed_before]
    broken = [c for c in required if c.name not in failed_before and c.passed is not True]
    outcomes = tuple(_outcome(c, True) for c in before) + tuple(_outcome(c, False) for c in broken)
    passed = all(c.passed is True for c in required)
    margins, note = margins_of(fixed.checks)
    return FixTrial(remedy, passed, outcomes, margins, note, "", seconds)
