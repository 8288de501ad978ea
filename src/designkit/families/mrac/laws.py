"""The MRAC's control laws: the adaptive law (plant, model, sensitivities and gradient rule integrated together)
and the fixed-gain PD law it freezes to.

Adaptive law (:func:`adaptive_law`), controller states in this order::

    ym1, ym2                        reference model (rest-started: at the plant's position)
    dym1_da1, dym2_da1, dym1_da2,   sensitivity model S = dym/da (rest-started: zero at rest)
    dym2_da2
    a1, a2                          adapted closed-loop coefficients (start at the initial values)

    ym' = f_m(ym, a, xD),   S' = (df_m/dy) S + df_m/da      (mrac.model.sensitivity_function)
    e = (ym1 - x1, ym2 - x2),       alpha' = Gamma S' Q e    (or modified: mrac.modification)
    u = -K1(alpha) (x1 - xD) - K2(alpha) x2,   K1 = tau_n a1/Km_n,  K2 = (tau_n a2 - 1)/Km_n

``a`` in the model and its sensitivity is the model's own (fixed) coefficient vector: the gradient
uses the model's sensitivity, not the plant's (notes section 4.2).  Recorded signals: ``ym`` (model
position, rad), ``e`` (``ym1 - x1``, rad), ``ev`` (``ym2 - x2``, rad/s), ``a1``, ``a2`` and the gains
``K1``, ``K2`` they realise.

The integration step is bounded by the reference model's fastest pole (``max_step = MAX_STEP_FACTOR
/ |p|max``): the simulator chooses its step from the frozen loop's poles, which do not include the
model's when the spec gives its own.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from designkit.families.mrac.model import (
    MODEL_NAMES,
    PARAMETERS,
    SENSITIVITY_NAMES,
    ReferenceModel,
    gains_of,
    sensitivity_function,
)
from designkit.families.mrac.modification import modified_rate
from designkit.synthesis.law import Law, LawSymbols, State, dynamic_law

__all__ = ["Freezer", "MAX_STEP_FACTOR", "STATE_NAMES", "adaptive_law", "fixed_law"]

KIND = "mrac"
"""The controller kind of this family (the spec's ``controller.kind``)."""
STATE_NAMES = (*MODEL_NAMES, *SENSITIVITY_NAMES, *PARAMETERS)
"""The adaptive law's controller states, in order."""
MAX_STEP_FACTOR = 0.1
"""Largest integration step times the reference model's fastest ``|p|`` (RK4 local error ~ 1e-6 there)."""


def _link(plant: Any) -> tuple[float, float]:
    return float(plant.parameter("Km").value), float(plant.parameter("tau").value)


def adaptive_law(nominal: Any, model: ReferenceModel, gamma: Sequence[float], Q: Sequence[Sequence[float]],
                 initial: Sequence[float], modification: Mapping[str, Any] | None = None) -> Law:
    """The adaptive law (module docstring) on the nominal link ``nominal``.

    Parameters
    ----------
    nominal : LinkPlant
        The link the gains are realised on.
    model : ReferenceModel
        The model to follow.
    gamma : sequence of 2 float
        Adaptation gains of ``a1`` and ``a2``.
    Q : 2 x 2
        Error weighting (symmetric positive definite).
    initial : sequence of 2 float
        ``a1, a2`` at ``t = 0``.
    modification : mapping or None
        An ad hoc modification of the gradient rule (:func:`designkit.families.mrac.modification.resolved`), None
        for the plain rule.
    """
    Km, tau = _link(nominal)
    sens = sensitivity_function()
    a = ca.DM(list(model.a))
    G = ca.DM(np.diag(np.asarray(gamma, dtype=float)))
    Qm = ca.DM(np.asarray(Q, dtype=float))
    memo: dict[int, dict[str, ca.SX]] = {}

    def parts(s: LawSymbols) -> dict[str, ca.SX]:
        key = id(s)
        if key not in memo:
            ym = ca.vertcat(*[s.state(n) for n in MODEL_NAMES])
            S = ca.vertcat(*[s.state(n) for n in SENSITIVITY_NAMES])
            alpha = ca.vertcat(*[s.state(n) for n in PARAMETERS])
            y_dot, S_dot = sens(ym, S, a, s.qD[0])
            e = ym - ca.vertcat(s.q[0], s.qd[0])
            Sm = ca.reshape(S, 2, 2)
            alpha_dot = modified_rate(modification, G @ Sm.T @ Qm @ e, alpha, e, Sm, G, Qm)
            K1, K2 = gains_of((alpha[0], alpha[1]), Km, tau)
            memo[key] = {"y_dot": y_dot, "S_dot": S_dot, "alpha_dot": alpha_dot, "e": e, "K1": K1, "K2": K2,
                         "ym": ym, "alpha": alpha}
        return memo[key]

    def pick(name: str, k: int):
        return lambda s: parts(s)[name][k]

    states = [State(n, pick("y_dot", k)) for k, n in enumerate(MODEL_NAMES)]
    states += [State(n, pick("S_dot", k)) for k, n in enumerate(SENSITIVITY_NAMES)]
    states += [State(n, pick("alpha_dot", k), float(initial[k])) for k, n in enumerate(PARAMETERS)]
    fastest = max(abs(p) for p in model.poles)
    return dynamic_law(
        KIND, nominal, states=states,
        command=lambda s: -parts(s)["K1"] * (s.q[0] - s.qD[0]) - parts(s)["K2"] * s.qd[0],
        settings={"reference_model": {"a1": model.a[0], "a2": model.a[1]}, "gamma": [float(g) for g in gamma],
                  "Q": [[float(x) for x in row] for row in Q], "initial": [float(v) for v in initial],
                  "nominal": {"Km": Km, "tau": tau}, "adaptation": "gradient rule, alpha' = Gamma S' Q e",
                  "modification": dict(modification) if modification is not None else None},
        signals={"ym": lambda s: parts(s)["ym"][0], "e": lambda s: parts(s)["e"][0],
                 "ev": lambda s: parts(s)["e"][1], "a1": lambda s: parts(s)["alpha"][0],
                 "a2": lambda s: parts(s)["alpha"][1], "K1": lambda s: parts(s)["K1"],
                 "K2": lambda s: parts(s)["K2"]},
        signal_units=("rad", "rad", "rad/s", "1/s^2", "1/s", "N*m/rad", "N*m*s/rad"),
        max_step=MAX_STEP_FACTOR / fastest,
        max_step_reason=f"the reference model's fastest pole ({fastest:.4g} 1/s) is integrated with the loop",
    )


def fixed_law(nominal: Any, values: Sequence[float]) -> Law:
    """The PD servo with the coefficients held at ``values`` (``(a1, a2)``, realised on ``nominal``): no
    adaptation, no model or sensitivity state."""
    Km, tau = _link(nominal)
    K1, K2 = gains_of([float(v) for v in values], Km, tau)
    return dynamic_law(KIND, nominal, command=lambda s: -K1 * (s.q[0] - s.qD[0]) - K2 * s.qd[0],
                       settings={"gains": {"K1": K1, "K2": K2},
                                 "frozen": {n: float(v) for n, v in zip(PARAMETERS, values, strict=True)}})


@dataclass(frozen=True)
class Freezer:
    """``values -> fixed_law(nominal, values)``: the ``freeze`` of the frozen linearization contract."""

    nominal: Any

    def __call__(self, values: Sequence[float]) -> Law:
        return fixed_law(self.nominal, values)
