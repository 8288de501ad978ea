"""What the MRAC family says of one of its runs when a study asks (:attr:`designkit.synthesis.family.Family.answers`):
why and how it adapted (``how``), and its control strategy (``strategy``), with the run's and the design's numbers."""

from __future__ import annotations

from typing import Any

from designkit.display.numbers import fmt_number, fmt_poles
from designkit.families.mrac.checks import mismatch_reasons
from designkit.families.mrac.data import RegressorData
from designkit.families.mrac.model import ReferenceModel
from designkit.families.mrac.modification import describe

__all__ = ["ANSWERS", "how", "strategy"]


def _vector(values: Any) -> str:
    return "(" + ", ".join(fmt_number(v, 4) if v is not None else "diverged" for v in values) + ")"


def _gain(v: float) -> str:
    """An adaptation gain as the spec writes it: ``10000``, not ``1e+04``."""
    return f"{int(round(v))}" if 1.0 <= abs(v) < 1e9 and float(v) == round(v) else fmt_number(v, 4)


def _rule(design: Any) -> str:
    words = describe(design.data.modification)
    return "the gradient rule" + (f", modified ({words})," if words else "")


def how(result: Any) -> tuple[str, ...]:
    """Why the run adapted (what moves the link off the model), where the parameters went against the values that
    put the final link on the model, and the output error with and without adaptation (rad)."""
    from designkit.families.mrac.report import json

    if result.simulation is None:
        return ()
    d = result.design
    if isinstance(d.data, RegressorData):
        a = json(result)["adaptation"]
        return (f"The {a['rule']} rule moves θ = ({', '.join(a['parameters'])}) from {_vector(a['initial'])} to "
                f"{_vector(a['final'])}, against {_vector(a['matching'])} that make the nominal loop the reference "
                f"model; its output error is {fmt_number(a['error_rms']['adaptive'], 3)} RMS, against "
                f"{fmt_number(a['error_rms']['fixed'], 3)} with the parameters frozen at their initial values.",)
    plant = result.plant if result.plant is not None else d.plant
    reasons = mismatch_reasons(d, result.loaded.spec, plant)
    a = json(result)["adaptation"]
    err = a.get("error_rms") or {}
    why = ("It adapts because " + "; ".join(reasons)) if reasons else \
        "Nothing moves the link off the reference model (the fixed-gain loop is the model)"
    return (f"{why}: {_rule(d)} moves its PD coefficients a1, a2 from {_vector(a['initial'])} to "
            f"{_vector(a['final'])}, against {_vector(a['matching'])} that put the link at the end of the run on the "
            f"reference model; its output error against the reference model is "
            f"{fmt_number(err.get('adaptive'), 3)} rad RMS, against {fmt_number(err.get('fixed'), 3)} rad with the "
            "coefficients frozen at their initial values.",)


def strategy(result: Any) -> tuple[str, ...]:
    """The law, the adaptation and its gains, in continuous time; the reference model's poles (1/s)."""
    d = result.design
    x = d.data
    if isinstance(x, RegressorData):
        return (f"A model-reference controller u = θᵀω (feedforward of the command, feedback of the output) whose "
                f"{len(x.gamma)} parameters follow the {x.rule} rule in continuous time: a direct scheme, which "
                "adjusts the controller from the output error against a reference model without estimating the "
                "plant.",)
    gamma = x.gamma
    gammas = _gain(gamma[0]) if gamma[0] == gamma[1] else f"({_gain(gamma[0])}, {_gain(gamma[1])})"
    poles = fmt_poles(ReferenceModel(x.reference_model.a).poles)
    return (f"A PD position servo u = −K1(α) (x1 − xD) − K2(α) x2 whose closed-loop coefficients α1, α2 follow "
            f"{_rule(d)} α' = Γ Sᵀ Q e with γ = {gammas}, in continuous time: a direct scheme, which adjusts the "
            f"controller's gains from the output error against a reference model (poles {poles} 1/s) without "
            "estimating the link.",)


ANSWERS = (("how", how), ("strategy", strategy))
"""The topics the family answers (:data:`designkit.synthesis.family.ANSWER_TOPICS`)."""
