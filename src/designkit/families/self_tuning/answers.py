"""What the self-tuning family says of one of its runs when a study asks
(:attr:`designkit.synthesis.family.Family.answers`): why and how it adapted (``how``), its control strategy
(``strategy``); and the variant a study may run (:data:`VARIANTS`): the estimator and design with their safeguards
turned off (or on)."""

from __future__ import annotations

from typing import Any

from designkit.display.numbers import fmt_number, fmt_poles
from designkit.synthesis.knobs import Variant

__all__ = ["ANSWERS", "VARIANTS", "how", "strategy"]


def _vector(values: Any) -> str:
    return "(" + ", ".join(fmt_number(v, 4) if v is not None else "diverged" for v in values) + ")"


def how(result: Any) -> tuple[str, ...]:
    """The estimates at the end of the run against the exactly sampled true link's parameters, and how often the
    safeguards acted."""
    from designkit.families.self_tuning.report import json

    if result.simulation is None:
        return ()
    x = result.design.data
    own = json(result)
    info = own[result.design.kind]
    form = _form_words(x.settings)
    acted = (f"; the covariance bound fired on {info['bounded']} of its {info['samples']} samples and the controller "
             f"was held on {info['held']}" if x.settings.safeguards else "; its safeguards are off")
    return (f"It adapts because its estimates of the sampled {form} ({', '.join(x.parameters)}) must fit the "
            f"measurements of the plant it drives: recursive least squares ends at {_vector(own['theta_hat'])} against "
            f"the true plant's {_vector(own['theta_true'])} at the end of the run, and the "
            f"{x.settings.design.replace('_', ' ')} redesigned from the estimates at every sample places the requested "
            f"poles on the estimated model{acted}.",)


def strategy(result: Any) -> tuple[str, ...]:
    """The estimator, its sampling and forgetting, and the redesign with its poles (1/s)."""
    st = result.design.data.settings
    poles = fmt_poles(st.poles)
    if st.form == "arx":
        ao = " ".join(fmt_number(v, 4) for v in st.ao)
        return (f"Recursive least squares with forgetting factor {fmt_number(st.forgetting, 4)} on the "
                f"{_form_words(st)}, sampled every {fmt_number(st.Ts, 3)} s, and a pole placement redesign "
                f"(Diophantine equation, the zeros {'cancelled' if st.cancel else 'kept'}) at every sample for the "
                f"poles {poles} 1/s with the observer polynomial Ao = [{ao}] in z: an indirect scheme, which "
                "estimates the plant's sampled model and recomputes the controller from it.",)
    observer = f" (observer pole {fmt_number(st.observer, 3)} 1/s)" if st.design == "pole_placement" else ""
    design = ("a pole placement redesign (Diophantine equation)" if st.design == "pole_placement" else
              "a PID redesign on the estimated Km and τ")
    return (f"Recursive least squares with forgetting factor {fmt_number(st.forgetting, 4)} on the "
            f"{'speed equation' if st.form == 'speed' else 'position differences'}, sampled every "
            f"{fmt_number(st.Ts, 3)} s, and {design} at every sample for the poles {poles} 1/s{observer}: an "
            "indirect scheme, which estimates the link's parameters and recomputes the controller from them.",)


def _form_words(st: Any) -> str:
    if st.form == "arx":
        na, nb, d = st.orders
        return f"ARX model (na = {na}, nb = {nb}, d = {d})"
    return "speed equation" if st.form == "speed" else "position differences"


def _safeguards(on: bool) -> Any:
    def changes(run: Any) -> tuple[tuple[str, Any], ...]:
        return (("controller.safeguards", on),) if bool(run.loaded.spec.controller.safeguards) != on else ()

    return changes


ANSWERS = (("how", how), ("strategy", strategy))
"""The topics the family answers (:data:`designkit.synthesis.family.ANSWER_TOPICS`)."""

VARIANTS = (
    Variant("no_safeguards", "safeguards turned off",
            "the textbook estimator and design: no covariance bound on tr P, no controller hold on a degenerate "
            "estimate", _safeguards(False)),
    Variant("safeguards", "safeguards turned on",
            "the covariance bound on tr P and the controller hold on a degenerate estimate", _safeguards(True)),
)
"""The ad hoc modifications of the textbook self-tuner a study may turn off (or on)."""
