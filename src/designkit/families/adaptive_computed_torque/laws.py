"""The adaptive computed-torque law (notes section 4.4, Craig 1988) and the fixed computed torque it freezes to.

Parameters.  The arm's dynamics are linear in the model layer's parameter vector ``P``
(:mod:`designkit.models.regressor`: ``m_i, mcx_i, ..., Izz_i`` per link, then ``fv_i, fc_i``,
then ``Ia_i``): ``D(q) a + h(q, qd) = W(q, qd, a) P`` for every acceleration ``a``.  The law adapts
the entries the spec names (``controller.adapt``, e.g. ``[m1, m2]``: the ``a`` entries of ``P``,
``P_a``) and takes the others as known, at the arm's true values.  With the estimate ``P^``::

    v       = qD'' + K1 e + K2 e',          e = qD - q                       (rad/s^2)
    Gamma   = D^(q) v + h^(q, qd) = W(q, qd, v) P^                           (N*m)
    D^(q)   = dW(q, 0, a)/da P^  (the estimated inertia matrix; W is affine in a)
    e1      = e + psi e'                                                      (rad)
    P^_a'   = K W_a(q, qd, qdd)' D^(q)^-1 e1                                  (notes, update law)

The error equation on the true arm is ``e'' + K2 e' + K1 e = D^^-1 W(q, qd, qdd) (P - P^)``
(docs/families/adaptive_computed_torque.md), so the update needs the arm's acceleration ``qdd``:
``acceleration: ideal`` reads it from an ideal accelerometer -- in the simulation the true arm's
forward dynamics at the command, which the law can evaluate because the command does not depend
on ``qdd`` (no algebraic loop) -- and ``acceleration: filtered`` differentiates the measured
velocity through a first-order filter ``vf' = wf (qd - vf)``, ``qdd^ = wf (qd - vf)`` (``n``
more controller states, a lag of ``1/wf``).

Controller states in order: ``<name> estimate`` (the adapted parameters, starting at the spec's initial
estimates), then ``vf<j>`` (filtered velocities, ``filtered`` only, starting at rest).  Recorded
signals: ``V`` (the Lyapunov function of the adaptive loop, computed with the true parameters --
a verification signal, not used by the law), ``Vdot_bound`` (its derivative on the exact error
equation, ``-sum_j 2 K1_j e_j^2 + 2 (psi_j K2_j - 1) e'_j^2``) and ``e1_<j>``.

Projection (optional): after every integration step ``p_i`` is reset to ``l_i`` when
``p_i <= l_i - delta`` and to ``h_i`` when ``p_i >= h_i + delta`` (notes section 4.4).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from designkit.families.adaptive_computed_torque import slotine_li
from designkit.models import regressor
from designkit.synthesis.design import FamilyData
from designkit.synthesis.law import Law, LawSymbols, State, dynamic_law

__all__ = ["KIND", "Adaptation", "AdaptiveData", "Freezer", "adaptive_law", "estimated_dynamics", "estimates",
           "fixed_law", "parameter_units", "state_name", "true_parameters"]

KIND = "adaptive_computed_torque"
"""The controller kind of this family (the spec's ``controller.kind``)."""

_UNIT_OF = {"m": "kg", "mcx": "kg*m", "mcy": "kg*m", "mcz": "kg*m", "fv": "N*m*s/rad", "fc": "N*m", "Ia": "kg*m^2"}


def parameter_units(names: Sequence[str]) -> tuple[str, ...]:
    """The unit of each regressor parameter name (``m2`` kg, ``mcx2`` kg*m, ``Izz2`` kg*m^2, ``fv1`` N*m*s/rad)."""
    out = []
    for name in names:
        stem = name.rstrip("0123456789")
        out.append(_UNIT_OF.get(stem, "kg*m^2" if stem.startswith("I") else ""))
    return tuple(out)


def true_parameters(plant: Any) -> np.ndarray:
    """The arm's true regressor parameter vector ``P`` (model layer's layout)."""
    return np.asarray(plant.robot.parameter_values(plant.model_parameters()), dtype=float).reshape(-1)


@dataclass(frozen=True)
class Adaptation:
    """What the law adapts and how (SI units; ``n`` joints, ``m`` adapted parameters).

    Parameters
    ----------
    names : tuple of str
        Adapted entries of ``P`` (``controller.adapt``).
    initial : tuple of float
        Their estimates at ``t = 0``.
    gain : tuple of float
        The diagonal of ``K``, one per adapted parameter (unit of the parameter squared times s/rad^2).
    K1, K2, psi : tuple of float
        Error gains (1/s^2, 1/s) and the filter's ``psi`` (s), per joint.
    acceleration : str
        ``"ideal"`` or ``"filtered"`` (``"none"`` for the Slotine--Li scheme).
    bandwidth : float
        ``wf`` of the velocity-derivative filter (rad/s; ``filtered`` only).
    bounds : tuple of (float, float) or None
        ``(l_i, h_i)`` per adapted parameter, or None (no projection).
    delta : float
        The projection's hysteresis (unit of each parameter).
    scheme : str
        ``"craig"`` (the notes' law) or ``"slotine_li"`` (:mod:`.slotine_li`; then ``K1, K2, psi`` are empty and
        ``Lambda`` (1/s) and ``KD`` (N*m*s/rad) per joint are its gains).
    gain_matrix : tuple of tuple of float or None
        The full symmetric positive-definite ``K`` (m x m) when it is not diagonal (``controller.gain_matrix``, or
        ``T^-1 diag(gain on a) T^-T`` from ``controller.combination``); None: ``K = diag(gain)``.
    combination : tuple of tuple of float or None
        ``T`` (m x m, invertible) of ``controller.combination``: the combinations ``a = T p`` on which the spec's
        gain is diagonal; None when not given.
    combination_gain : tuple of float
        The spec's diagonal gain on ``a`` (with ``combination`` only).
    """

    names: tuple[str, ...]
    initial: tuple[float, ...]
    gain: tuple[float, ...]
    K1: tuple[float, ...]
    K2: tuple[float, ...]
    psi: tuple[float, ...]
    acceleration: str = "ideal"
    bandwidth: float = 0.0
    bounds: tuple[tuple[float, float], ...] | None = None
    delta: float = 0.0
    scheme: str = "craig"
    Lambda: tuple[float, ...] = ()
    KD: tuple[float, ...] = ()
    gain_matrix: tuple[tuple[float, ...], ...] | None = None
    combination: tuple[tuple[float, ...], ...] | None = None
    combination_gain: tuple[float, ...] = ()

    def K(self) -> np.ndarray:
        """The adaptation gain ``K`` (m x m, symmetric positive definite)."""
        if self.gain_matrix is None:
            return np.diag(np.asarray(self.gain, dtype=float))
        return np.asarray(self.gain_matrix, dtype=float)

    def to_json(self) -> dict[str, Any]:
        """JSON-ready settings."""
        out = {"adapt": list(self.names), "initial": list(self.initial), "gain": list(self.gain),
               "K1": list(self.K1), "K2": list(self.K2), "psi": list(self.psi), "acceleration": self.acceleration,
               "bandwidth": self.bandwidth, "bounds": None if self.bounds is None else [list(b) for b in self.bounds],
               "delta": self.delta, "scheme": self.scheme, "Lambda": list(self.Lambda), "KD": list(self.KD)}
        if self.gain_matrix is not None:
            out["gain_matrix"] = [list(r) for r in self.gain_matrix]
        if self.combination is not None:
            out["combination"] = [list(r) for r in self.combination]
            out["combination_gain"] = list(self.combination_gain)
        return out

    @classmethod
    def from_json(cls, x: Any) -> Adaptation:
        """The inverse of :meth:`to_json`."""
        bounds = x["bounds"]
        return cls(names=tuple(x["adapt"]), initial=tuple(x["initial"]), gain=tuple(x["gain"]), K1=tuple(x["K1"]),
                   K2=tuple(x["K2"]), psi=tuple(x["psi"]), acceleration=x["acceleration"],
                   bandwidth=float(x["bandwidth"]), bounds=None if bounds is None else tuple(tuple(b) for b in bounds),
                   delta=float(x["delta"]), scheme=x.get("scheme", "craig"), Lambda=tuple(x.get("Lambda", ())),
                   KD=tuple(x.get("KD", ())),
                   gain_matrix=None if x.get("gain_matrix") is None else tuple(tuple(r) for r in x["gain_matrix"]),
                   combination=None if x.get("combination") is None else tuple(tuple(r) for r in x["combination"]),
                   combination_gain=tuple(x.get("combination_gain", ())))


def _indices(plant: Any, names: Sequence[str]) -> list[int]:
    all_names = list(plant.robot.parameter_names)
    return [all_names.index(n) for n in names]


def _torque_of_parameters(plant: Any) -> Any:
    """``(q, qd, a, P) -> W(q, qd, a) P`` as the model layer's Newton--Euler in the parameter vector (cheaper
    than the regressor product: the RNEA with ``P`` as data), the robot's own symbols bound to the plant's
    values."""
    robot = plant.robot
    n = robot.n
    q, qd, a = (ca.SX.sym(x, n) for x in ("q", "qd", "a"))
    P = ca.SX.sym("P", len(robot.parameter_names))
    tau = regressor.inverse_dynamics(robot.description, q, qd, a, ca.vertsplit(P), friction=robot.friction,
                                     motor_inertia=robot.motor_inertia)
    syms = [sym for _, sym in robot.description.symbols]
    if syms:
        F = ca.Function("torque_of_parameters", [q, qd, a, P, ca.vertcat(*syms)], [tau])
        p = ca.DM(plant.model_parameters())
        return lambda q_, qd_, a_, P_: F(q_, qd_, a_, P_, p)
    F = ca.Function("torque_of_parameters", [q, qd, a, P], [tau])
    return lambda q_, qd_, a_, P_: F(q_, qd_, a_, P_)


def _estimate(P_true: np.ndarray, idx: Sequence[int], values: ca.SX) -> ca.SX:
    """``P^``: the true vector with the adapted entries replaced by ``values``."""
    entries = [ca.SX(float(v)) for v in P_true]
    for k, i in enumerate(idx):
        entries[i] = values[k]
    return ca.vertcat(*entries)


def estimated_dynamics(plant: Any, names: Sequence[str], values: Any) -> ca.Function:
    """``(q, qd, v) -> (D^, h^, W(q, qd, v) P^)`` with the adapted entries of ``P`` at ``values`` (the others true):
    ``D^ = dW(q, 0, a)/da P^`` (kg*m^2), ``h^ = W(q, qd, 0) P^`` (N*m); the law's model, for the tests."""
    n = plant.n_joints
    q, qd, v, acc = (ca.SX.sym(x, n) for x in ("q", "qd", "v", "acc"))
    P_hat = _estimate(true_parameters(plant), _indices(plant, names), ca.SX(ca.DM([float(x) for x in values])))
    tau_of = _torque_of_parameters(plant)
    D = ca.jacobian(tau_of(q, ca.SX.zeros(n), acc, P_hat), acc)
    h = tau_of(q, qd, ca.SX.zeros(n), P_hat)
    return ca.Function("estimated_dynamics", [q, qd, v], [D, h, tau_of(q, qd, v, P_hat)], ["q", "qd", "v"],
                       ["D_hat", "h_hat", "tau"])


def adaptive_law(plant: Any, a: Adaptation) -> Law:
    """The adaptive computed torque (module docstring) on the arm ``plant`` (whose true parameters are the known ones).

    Parameters
    ----------
    plant : RobotPlant
        The arm (its true regressor parameters are the known entries and the reference of ``V``).
    a : Adaptation
        Gains, the adapted parameters and the acceleration source.
    """
    n = plant.n_joints
    idx = _indices(plant, a.names)
    P_true = true_parameters(plant)
    tau_of = _torque_of_parameters(plant)
    K1, K2, psi = (ca.DM(list(x)) for x in (a.K1, a.K2, a.psi))
    gain = a.K()
    p = plant.model_parameters()
    fd = plant.robot.functions["forward_dynamics"]
    memo: dict[int, dict[str, ca.SX]] = {}
    names = tuple(state_name(x) for x in a.names)

    def parts(s: LawSymbols) -> dict[str, ca.SX]:
        key = id(s)
        if key in memo:
            return memo[key]
        q, qd = s.q, s.qd
        est = ca.vertcat(*[s.state(x) for x in names])
        if a.scheme == "slotine_li":
            memo[key] = slotine_li.parts(s, tau_of, n, P_true, idx, est, ca.DM(list(a.Lambda)), ca.DM(list(a.KD)),
                                         gain, _estimate)
            return memo[key]
        P_hat = _estimate(P_true, idx, est)
        e, ed = s.qD - q, s.qDd - qd
        v = s.qDdd + K1 * e + K2 * ed
        u = tau_of(q, qd, v, P_hat)
        acc = ca.SX.sym("acc", n)
        D_hat = ca.jacobian(tau_of(q, ca.SX.zeros(n), acc, P_hat), acc)
        if a.acceleration == "ideal":
            qdd = fd(q, qd, u, ca.DM(p)) if p is not None else fd(q, qd, u)
        else:
            vf = ca.vertcat(*[s.state(f"vf{j + 1}") for j in range(n)])
            qdd = a.bandwidth * (qd - vf)
        e1 = e + psi * ed
        Pa = ca.SX.sym("Pa", len(idx))
        Wa = ca.jacobian(tau_of(q, qd, qdd, _estimate(P_true, idx, Pa)), Pa)  # affine in P: free of Pa
        rate = ca.DM(gain) @ (Wa.T @ ca.solve(D_hat, e1))
        phi = ca.DM(P_true[idx]) - est
        V = ca.sum1((K2 + psi * K1) * e**2 + 2 * e * ed + psi * ed**2) + ca.dot(phi, ca.DM(np.linalg.inv(gain)) @ phi)
        Vdot = -ca.sum1(2 * K1 * e**2 + 2 * (psi * K2 - 1) * ed**2)
        memo[key] = {"u": u, "rate": rate, "V": V, "Vdot": Vdot, "e1": e1, "qd": qd, "vf_dot": None}
        if a.acceleration == "filtered":
            memo[key]["vf_dot"] = a.bandwidth * (qd - vf)
        return memo[key]

    def pick(name: str, k: int) -> Any:
        return lambda s: parts(s)[name][k]

    states = [State(x, pick("rate", k), float(a.initial[k])) for k, x in enumerate(names)]
    filtered = a.acceleration == "filtered" and a.scheme == "craig"
    if filtered:
        states += [State(f"vf{j + 1}", pick("vf_dot", j), 0.0) for j in range(n)]
    signals = {"V": lambda s: parts(s)["V"], "Vdot_bound": lambda s: parts(s)["Vdot"]}
    filtered_name = "s" if a.scheme == "slotine_li" else "e1"
    signals.update({f"{filtered_name}_{j + 1}": pick("e1", j) for j in range(n)})
    kw: dict[str, Any] = {}
    if filtered:
        kw = {"max_step": 0.2 / a.bandwidth,
              "max_step_reason": f"the velocity-derivative filter's pole ({a.bandwidth:.4g} 1/s) is integrated "
                                 "with the loop"}
    law = dynamic_law(KIND, plant, command=lambda s: parts(s)["u"], states=states, settings=a.to_json(),
                      signals=signals, signal_units=("", "1/s", *("rad",) * n), **kw)
    if a.bounds is None:
        return law
    return dataclasses.replace(law, project=_projection(law, a), project_resets=True)


def _projection(law: Law, a: Adaptation) -> ca.Function:
    """``xc -> xc`` with each adapted parameter reset into ``[l, h]`` once it leaves by ``delta`` (notes 4.4)."""
    xc = ca.SX.sym("xc", law.n_state)
    out = [xc[i] for i in range(law.n_state)]
    for k, (lo, hi) in enumerate(a.bounds or ()):
        x = out[k]
        out[k] = ca.if_else(x <= lo - a.delta, lo, ca.if_else(x >= hi + a.delta, hi, x))
    return ca.Function(f"{KIND}_project", [xc], [ca.vertcat(*out)], ["xc"], ["xc_projected"])


def fixed_law(plant: Any, names: Sequence[str], values: Sequence[float], K1: Sequence[float],
              K2: Sequence[float], scheme: str = "craig") -> Law:
    """The law with the estimates held at ``values`` (no state): ``W(q, qd, qD'' + K1 e + K2 e') P^`` (Craig), or
    ``Y(q, qd, qr', qr'') P^ + KD s`` (``scheme="slotine_li"``, ``K1`` then ``Lambda`` and ``K2`` ``KD``)."""
    idx = _indices(plant, names)
    P_hat = _estimate(true_parameters(plant), idx, ca.DM([float(v) for v in values]))
    tau_of = _torque_of_parameters(plant)
    k1, k2 = ca.DM(list(K1)), ca.DM(list(K2))

    def command(s: LawSymbols) -> ca.SX:
        if scheme == "slotine_li":
            return slotine_li.fixed_command(s, tau_of, plant.n_joints, P_hat, k1, k2)
        v = s.qDdd + k1 * (s.qD - s.q) + k2 * (s.qDd - s.qd)
        return tau_of(s.q, s.qd, v, P_hat)

    return dynamic_law(KIND, plant, command=command,
                       settings={"frozen": {x: float(v) for x, v in zip(names, values, strict=True)},
                                 "K1": list(K1), "K2": list(K2)})


@dataclass(frozen=True)
class Freezer:
    """``values -> fixed_law(...)``: the ``freeze`` of the frozen linearization contract."""

    plant: Any
    names: tuple[str, ...]
    K1: tuple[float, ...]
    K2: tuple[float, ...]
    scheme: str = "craig"

    def __call__(self, values: Sequence[float]) -> Law:
        return fixed_law(self.plant, self.names, values, self.K1, self.K2, self.scheme)


def state_name(name: str) -> str:
    """The controller state holding the estimate of the parameter ``name`` (``"m2 estimate"``)."""
    return f"{name} estimate"


def estimates(sim: Any, names: Sequence[str]) -> np.ndarray:
    """The adapted parameters along a run, ``(N, m)``."""
    cols = [list(sim.controller_state_names).index(state_name(x)) for x in names]
    return np.asarray(sim.controller_state, dtype=float)[:, cols]


@dataclass(frozen=True)
class AdaptiveData(FamilyData):
    """The adaptive computed torque's design data (:attr:`~designkit.synthesis.design.Design.data`).

    Attributes
    ----------
    adaptation : Adaptation
        What the law adapts and how (SI units).
    units : tuple of str
        The unit of each adapted parameter, in the order of ``adaptation.names``.
    true : tuple of float
        The arm's true value of each adapted parameter (its unit).
    convergence : Convergence
        How ``tracking_convergence`` judges the error (``controller.convergence``).
    start_warnings : tuple of str
        What is physically impossible about the starting estimates (:mod:`.physical`), one sentence each.
    """

    adaptation: Adaptation
    units: tuple[str, ...]
    true: tuple[float, ...]
    convergence: Convergence = field(default_factory=lambda: Convergence())
    start_warnings: tuple[str, ...] = ()


@dataclass(frozen=True)
class Convergence:
    """The tracking-convergence judgement's settings (``controller.convergence``).

    Attributes
    ----------
    window : float or None
        The trailing window (s); None: the reference's period for a sine, else a tenth of the run.
    tolerance : float
        Relative rise allowed from one window's maximum to the next (dimensionless).
    floor : float
        An error whose running maximum stays below it counts as converged (rad).
    """

    window: float | None = None
    tolerance: float = 0.0
    floor: float = 1e-6
