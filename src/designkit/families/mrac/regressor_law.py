"""The feedforward/feedback MRAC's laws: the adaptive law and the fixed law it freezes to
(:mod:`designkit.families.mrac.structure`).

Controller states, in this order (all but the parameters start at the loop's rest)::

    ym1 .. ym<nm>          the reference model Gm in controllable canonical form, driven by uc
    wy1 .. wy<n-1>         1/Lambda filter of y  (n > 1)
    wu1 .. wu<n-1>         1/Lambda filter of u  (n > 1)
    phi<i>_<k>             the sensitivity filter Gm/Gm(0) of regressor entry i (rules mit and normalized)
    theta1 .. theta<2n>    the adapted parameters (start at ``initial``)

    u = theta' omega,   omega = (uc, -y, -(alpha/Lambda) y, -(alpha/Lambda) u)
    e = y - ym          (Astrom and Wittenmark's sign)
    mit:         theta' = -gamma s e phi,                 phi = Gm(p)/Gm(0) omega   (the filtered-signal form)
    lyapunov:    theta' = -gamma s e omega
    normalized:  theta' = -gamma s e phi / (alpha0 + phi' phi)

``s = sign(kp/km)``.  The MIT rule's ``phi`` is the sensitivity derivative ``de/dtheta`` with the loop's closed-loop
polynomial replaced by the model's and the constant ``kp/km`` folded into ``gamma`` (their section 5.2); for Example
5.2, ``Gm/Gm(0) = am/(p + am)``, the book's filter.  Recorded signals: ``ym``, ``e`` (``ym - y``, the family's sign
on every plant), and each parameter.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from designkit.families.mrac.laws import KIND, MAX_STEP_FACTOR
from designkit.families.mrac.structure import Structure
from designkit.synthesis.law import Law, LawSymbols, State, dynamic_law

__all__ = ["RULES", "RegressorFreezer", "fixed_regressor_law", "regressor_law", "state_names"]

RULES = ("mit", "lyapunov", "normalized")
"""The adaptation rules of the feedforward/feedback structure."""


def _companion(den: Sequence[float]) -> tuple[np.ndarray, int]:
    """``(ascending coefficients a_0 .. a_(k-1) of the monic den, k)``: ``x_(k-1)' = in - sum a_j x_j``."""
    d = np.asarray(den, dtype=float)
    return d[::-1][:-1], len(d) - 1


def _filter_derivatives(x: Sequence[ca.SX], den: Sequence[float], inp: ca.SX) -> list[ca.SX]:
    """Controllable canonical form of ``1/den``: ``x_j = p^j/den inp``."""
    a, k = _companion(den)
    out = [x[j + 1] for j in range(k - 1)]
    out.append(inp - sum(float(a[j]) * x[j] for j in range(k)))
    return out


def _model_output(x: Sequence[ca.SX], num: Sequence[float], nm: int, scale: float = 1.0) -> ca.SX:
    b = np.zeros(nm + 1)
    nn = np.asarray(num, dtype=float)
    b[nm + 1 - len(nn):] = nn
    asc = b[::-1]
    return sum(float(asc[j]) / scale * x[j] for j in range(nm))


def state_names(s: Structure, rule: str) -> tuple[str, ...]:
    """The adaptive law's controller states (module docstring)."""
    n, nm = s.order, len(s.model_den) - 1
    p = 2 * n
    names = [f"ym{k + 1}" for k in range(nm)]
    names += [f"wy{k + 1}" for k in range(n - 1)] + [f"wu{k + 1}" for k in range(n - 1)]
    if rule != "lyapunov":
        names += [f"phi{i + 1}_{k + 1}" for i in range(p) for k in range(nm)]
    return (*names, *s.names)


def _omega(s: Structure, sym: LawSymbols, uc: ca.SX, y: ca.SX) -> ca.SX:
    n = s.order
    wy = [sym.state(f"wy{k + 1}") for k in range(n - 1)]
    wu = [sym.state(f"wu{k + 1}") for k in range(n - 1)]
    # alpha/Lambda x = (p^(n-2), ..., 1)/Lambda x: the filter states in reverse
    return ca.vertcat(uc, -y, *[-w for w in reversed(wy)], *[-w for w in reversed(wu)])


def regressor_law(plant: Any, s: Structure, rule: str, gamma: Sequence[float], initial: Sequence[float],
                  normalization: float = 1.0) -> Law:
    """The adaptive law (module docstring) on ``plant`` (its first position is ``y``).

    Parameters
    ----------
    plant : Plant
        The plant (the layout; ``y`` is its first position).
    s : Structure
        The structure: nominal plant, model, ``Lambda``.
    rule : {"mit", "lyapunov", "normalized"}
        The adaptation rule.
    gamma : sequence of float
        One adaptation gain per parameter (units: 1/(s * unit(e) * unit(phi_i))).
    initial : sequence of float
        The parameters at ``t = 0``.
    normalization : float
        ``alpha0 > 0`` of the normalized rule (in the unit of ``phi' phi``).
    """
    n, nm = s.order, len(s.model_den) - 1
    p = 2 * n
    sign = s.high_frequency_sign
    G = np.asarray(gamma, dtype=float)
    gain = s.static_gain
    memo: dict[int, dict[str, Any]] = {}

    def parts(sym: LawSymbols) -> dict[str, Any]:
        key = id(sym)
        if key not in memo:
            uc, y = sym.qD[0], sym.q[0]
            theta = ca.vertcat(*[sym.state(name) for name in s.names])
            omega = _omega(s, sym, uc, y)
            u = ca.dot(theta, omega)
            xm = [sym.state(f"ym{k + 1}") for k in range(nm)]
            ym = _model_output(xm, s.model_num, nm)
            e = y - ym
            deriv = _filter_derivatives(xm, s.model_den, uc)
            if n > 1:
                deriv += _filter_derivatives([sym.state(f"wy{k + 1}") for k in range(n - 1)], s.lam, y)
                deriv += _filter_derivatives([sym.state(f"wu{k + 1}") for k in range(n - 1)], s.lam, u)
            if rule == "lyapunov":
                phi = omega
            else:
                rows = []
                for i in range(p):
                    xi = [sym.state(f"phi{i + 1}_{k + 1}") for k in range(nm)]
                    deriv += _filter_derivatives(xi, s.model_den, omega[i])
                    rows.append(_model_output(xi, s.model_num, nm, gain))
                phi = ca.vertcat(*rows)
            rate = -sign * e * phi
            if rule == "normalized":
                rate = rate / (normalization + ca.dot(phi, phi))
            deriv += [float(G[i]) * rate[i] for i in range(p)]
            memo[key] = {"u": u, "ym": ym, "e": e, "deriv": deriv, "theta": theta}
        return memo[key]

    names = state_names(s, rule)
    n_fixed = len(names) - p
    def deriv(k: int):
        return lambda sym: parts(sym)["deriv"][k]

    def param(i: int):
        return lambda sym: parts(sym)["theta"][i]

    states = [State(name, deriv(k)) for k, name in enumerate(names[:n_fixed])]
    states += [State(name, deriv(n_fixed + i), float(initial[i])) for i, name in enumerate(s.names)]
    signals = {"ym": lambda sym: parts(sym)["ym"], "e": lambda sym: -parts(sym)["e"]}
    signals.update({name: param(i) for i, name in enumerate(s.names)})
    fastest = max([abs(r) for r in np.roots(s.model_den)] + [abs(r) for r in np.roots(s.lam)] + [1e-9])
    return dynamic_law(
        KIND, plant, states=states, command=lambda sym: parts(sym)["u"],
        settings={"structure": "feedforward_feedback", "rule": rule, "gamma": [float(g) for g in G],
                  "initial": [float(v) for v in initial], "reference_model": {"num": list(s.model_num),
                                                                               "den": list(s.model_den)},
                  "filter": list(s.lam), "normalization": float(normalization) if rule == "normalized" else None},
        signals=signals, signal_units=("", "", *([""] * p)),
        max_step=MAX_STEP_FACTOR / fastest,
        max_step_reason=f"the reference model's and the filters' fastest pole ({fastest:.4g} 1/s) are integrated "
                        "with the loop")


def fixed_regressor_law(plant: Any, s: Structure, theta: Sequence[float]) -> Law:
    """``u = theta' omega`` with ``theta`` held: no model, no sensitivity filter, no adaptation (the regressor's
    ``1/Lambda`` filters remain: they are part of the controller)."""
    n = s.order
    th = [float(v) for v in theta]

    def command(sym: LawSymbols) -> ca.SX:
        return ca.dot(ca.DM(th), _omega(s, sym, sym.qD[0], sym.q[0]))

    states: list[State] = []
    if n > 1:
        def filt(prefix: str, k: int):
            def f(sym: LawSymbols) -> ca.SX:
                x = [sym.state(f"{prefix}{j + 1}") for j in range(n - 1)]
                inp = sym.q[0] if prefix == "wy" else command(sym)
                return _filter_derivatives(x, s.lam, inp)[k]
            return f
        states = [State(f"wy{k + 1}", filt("wy", k)) for k in range(n - 1)]
        states += [State(f"wu{k + 1}", filt("wu", k)) for k in range(n - 1)]
    return dynamic_law(KIND, plant, command=command, states=states,
                       settings={"frozen": dict(zip(s.names, th, strict=True)), "filter": list(s.lam)})


@dataclass(frozen=True)
class RegressorFreezer:
    """``values -> fixed_regressor_law(plant, structure, values)``: the frozen contract's ``freeze``."""

    plant: Any
    structure: Structure

    def __call__(self, values: Sequence[float]) -> Law:
        return fixed_regressor_law(self.plant, self.structure, values)
