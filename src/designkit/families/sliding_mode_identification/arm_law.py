"""The robot form's law: a PD servo per joint driving the arm, and the sampled identifier of its base parameters
alongside it as discrete memory (notes section 5.5, its generalisation ``x' = A phi(x, t)`` with the model layer's
regressor as ``phi``).

The arm's torque is linear in its base parameters, ``u = Wb(q, qd, qdd) beta``
(:mod:`~designkit.families.sliding_mode_identification.arm`).  ``theta`` is the identified part of ``beta``
(``controller.identify``), the rest ``beta_k`` known at the model's values: ``u - Wk beta_k = Y theta``, ``Y`` the
identified columns.  At each sample ``k`` (period ``Ts``), from the measured ``q``, ``qd`` and the command ``u``::

    u      = K1 (qD - q) + K2 (qD' - qd)                   the servo (per joint; qD' = 0 for a square wave, a PRBS)
    slm_j  = qdh_j - qd_j                                   each joint's observer of its speed (rad/s)
    sw_j   = -k_j sign(slm_j)                               switching term (rad/s^2), held over the sample
    model  = Mh(q)^-1 (u - hh(q, qd))                       the estimated model's acceleration (0 where Mh is not
                                                            positive definite)
    qdh_j <- qdh_j + Ts (model_j + sw_j)
    a_j    = model_j(k-1) + sw_j(k-1) + (slm_j(k-1) - slm_j(k))/Ts     the equivalent switching term as acceleration
    qm, qdm = (q(k-1) + q(k))/2, (qd(k-1) + qd(k))/2        the mean state over the last sample (O(Ts^2))
    eps1   = u(k-1) - Wk(qm, qdm, a) beta_k - Y(qm, qdm, a) thetah         torque error now (N*m per joint)
    eps2   = the same with the values D = N Ts earlier and today's thetah
    m2     = max(1, Ts tr(Gamma Phi)/sigma),  Phi = Y1' Y1 + Y2' Y2
    thetah <- thetah + Ts Gamma (Y1' eps1 + Y2' eps2)/m2

The normalisation ``m2`` (:data:`STEP_LIMIT` ``sigma = 1``) is 1, the notes' plain gradient, while the sample's
step ``Ts lambda_max(Gamma^1/2 Phi Gamma^1/2) <= Ts tr(Gamma Phi)`` stays below ``sigma``; a larger one (a
transient, a jump of the reference) is divided down to ``sigma``, where the sampled update still decreases
``V``: ``V(k+1) - V(k) <= -(Ts/m2) theta~' Phi theta~ (2 - Ts lambda_max/m2) < 0``.  (Continuous time:
``V' = -2 (|eps1|^2 + |eps2|^2)/m2``.)

``a`` is exactly the backward difference ``(qd(k) - qd(k-1))/Ts`` whatever the model (the observer's update
makes the two equal), so the estimates do not depend on the observer being on its sliding mode (the link's
:mod:`~designkit.families.sliding_mode_identification.laws` is the one-joint case with ``Mh = 1/bh``,
``hh = (ah/bh) x2``).  ``eps1`` is counted from the second sample on, ``eps2`` once the shift registers hold a
reconstructed sample (``k > N``): before that they hold zeros, which are not a state of the arm.  ``Mh`` is the
derivative of ``Wb(q, qd, a) betah`` in ``a``; its LDL' factorisation gives the solve, and a pivot at or below
1e-6 of its diagonal entry says it is not positive definite (then the model term is 0).

Recorded signals: ``<name>_hat`` per identified parameter, and per joint ``slm<j>``, ``acc<j>`` (the
reconstructed acceleration), ``model<j>`` (the model term), ``eps1_<j>``, ``eps2_<j>``: the values of the sample,
stored in the memory (the signals read it after the update).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca

from designkit.families.sliding_mode_identification.arm import parameter_unit
from designkit.families.sliding_mode_identification.laws import KIND
from designkit.synthesis.law import Law, LawSymbols, Memory, dynamic_law

__all__ = ["ArmIdentifier", "arm_identifier_law", "ldl_solve", "signal_names"]

STEP_LIMIT = 1.0
"""``sigma``: the update is divided by ``m2 = max(1, Ts tr(Gamma Phi)/sigma)``, so that its sampled step
``Ts lambda_max(Gamma^1/2 Phi Gamma^1/2)/m2`` never exceeds ``sigma < 2`` (module docstring)."""
PIVOT_REL = 1e-6
"""A pivot of the LDL' factorisation of ``Mh`` at or below this fraction of its diagonal entry: not positive
definite."""


@dataclass(frozen=True)
class ArmIdentifier:
    """The numbers of the law (module docstring), SI units.

    Parameters
    ----------
    K1, K2 : tuple of float
        PD servo gains per joint (N*m/rad, N*m*s/rad).
    switching : tuple of float
        The observers' switching gains ``k_j`` (rad/s^2).
    window : float
        ``D`` (s).
    Ts : float
        Sampling period (s).
    names : tuple of str
        The identified base parameters.
    columns : tuple of int
        Their columns in ``Wb``.
    known : tuple of (int, float)
        The known columns of ``Wb`` and their values.
    gamma : tuple of float
        The adaptation gains (diagonal ``Gamma``), one per identified parameter.
    initial : tuple of float
        ``thetah(0)``.
    start : tuple of float
        The joints' initial positions (rad), the state before the first sample.
    """

    K1: tuple[float, ...]
    K2: tuple[float, ...]
    switching: tuple[float, ...]
    window: float
    Ts: float
    names: tuple[str, ...]
    columns: tuple[int, ...]
    known: tuple[tuple[int, float], ...]
    gamma: tuple[float, ...]
    initial: tuple[float, ...]
    start: tuple[float, ...]

    @property
    def samples(self) -> int:
        """``N = round(D/Ts)`` (at least 1)."""
        return max(1, int(round(self.window / self.Ts)))

    @property
    def n(self) -> int:
        """Number of joints."""
        return len(self.K1)

    def to_json(self) -> dict[str, Any]:
        """JSON-ready settings (:meth:`from_json` inverts it)."""
        return {"K1": list(self.K1), "K2": list(self.K2), "switching": list(self.switching), "window": self.window,
                "Ts": self.Ts, "names": list(self.names), "columns": list(self.columns),
                "known": [list(k) for k in self.known], "gamma": list(self.gamma), "initial": list(self.initial),
                "start": list(self.start)}

    @classmethod
    def from_json(cls, x: Any) -> ArmIdentifier:
        """The inverse of :meth:`to_json`."""
        return cls(K1=tuple(x["K1"]), K2=tuple(x["K2"]), switching=tuple(x["switching"]), window=float(x["window"]),
                   Ts=float(x["Ts"]), names=tuple(x["names"]), columns=tuple(int(c) for c in x["columns"]),
                   known=tuple((int(c), float(v)) for c, v in x["known"]), gamma=tuple(x["gamma"]),
                   initial=tuple(x["initial"]), start=tuple(x["start"]))


def signal_names(names: tuple[str, ...], n: int) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """The recorded signals and their units (module docstring)."""
    out = [f"{x}_hat" for x in names]
    units = [parameter_unit(x) for x in names]
    for j in range(1, n + 1):
        out += [f"slm{j}", f"acc{j}", f"model{j}", f"eps1_{j}", f"eps2_{j}"]
        units += ["rad/s", "rad/s^2", "rad/s^2", "N*m", "N*m"]
    return tuple(out), tuple(units)


def ldl_solve(M: ca.SX, b: ca.SX) -> tuple[ca.SX, ca.SX]:
    """``(M^-1 b, ok)`` by the LDL' factorisation of the symmetric ``M``; ``ok`` is 1 when every pivot exceeds
    :data:`PIVOT_REL` times its diagonal entry (``M`` positive definite), and the solution is 0 otherwise."""
    n = M.size1()
    L = [[ca.SX(0)] * n for _ in range(n)]
    d: list[ca.SX] = []
    ok = ca.SX(1)
    for i in range(n):
        for j in range(i):
            L[i][j] = (M[i, j] - sum((L[i][k] * L[j][k] * d[k] for k in range(j)), ca.SX(0))) / d[j]
        di = M[i, i] - sum((L[i][k] ** 2 * d[k] for k in range(i)), ca.SX(0))
        good = ca.logic_and(M[i, i] > 0, di > PIVOT_REL * M[i, i])
        ok = ca.logic_and(ok, good)
        d.append(ca.if_else(good, di, 1.0))
    z: list[ca.SX] = []
    for i in range(n):
        z.append(b[i] - sum((L[i][k] * z[k] for k in range(i)), ca.SX(0)))
    x: list[ca.SX] = [ca.SX(0)] * n
    for i in reversed(range(n)):
        x[i] = z[i] / d[i] - sum((L[k][i] * x[k] for k in range(i + 1, n)), ca.SX(0))
    return ca.if_else(ok, ca.vertcat(*x), ca.SX.zeros(n)), ok


def arm_identifier_law(plant: Any, ident: ArmIdentifier, Wb: ca.Function) -> Law:
    """The PD servos with the sampled identifier alongside (module docstring); ``Wb`` the base regressor
    ``(q, qd, qdd) -> n x b`` at the plant's kinematics."""
    n, N, Ts = ident.n, ident.samples, ident.Ts
    cols, kcols = list(ident.columns), [c for c, _ in ident.known]
    kvals = ca.DM([v for _, v in ident.known]) if ident.known else None
    G = ca.DM(list(ident.gamma))
    memo: dict[int, dict[str, ca.SX]] = {}

    def torque_error(Y: ca.SX, u: ca.SX, th: ca.SX) -> ca.SX:
        known = ca.mtimes(Y[:, kcols], kvals) if kvals is not None else ca.SX.zeros(n)
        return u - known - ca.mtimes(Y[:, cols], th)

    def parts(s: LawSymbols) -> dict[str, ca.SX]:
        key = id(s)
        if key in memo:
            return memo[key]
        q, qd = s.q, s.qd
        u = ca.vertcat(*[ident.K1[j] * (s.qD[j] - q[j]) + ident.K2[j] * (s.qDd[j] - qd[j]) for j in range(n)])
        th = ca.vertcat(*[s.memory(f"th{i}") for i in range(len(cols))])
        beta = ca.SX.zeros(Wb.size2_out(0))
        for i, c in enumerate(cols):
            beta[c] = th[i]
        for c, v in ident.known:
            beta[c] = v
        a_sym = ca.SX.sym("a", n)
        tau = ca.mtimes(Wb(q, qd, a_sym), beta)
        Mh = ca.substitute(ca.jacobian(tau, a_sym), a_sym, ca.SX.zeros(n))
        hh = ca.substitute(tau, a_sym, ca.SX.zeros(n))
        model, _ = ldl_solve(0.5 * (Mh + Mh.T), u - hh)
        mem = {name: ca.vertcat(*[s.memory(f"{name}{j}") for j in range(n)])
               for name in ("qdh", "pq", "pqd", "pu", "pslm", "psw", "pmodel")}
        slm = mem["qdh"] - qd
        sw = ca.vertcat(*[-ident.switching[j] * ca.sign(slm[j]) for j in range(n)])
        acc = mem["pmodel"] + mem["psw"] + (mem["pslm"] - slm) / Ts
        qm, qdm = 0.5 * (mem["pq"] + q), 0.5 * (mem["pqd"] + qd)
        eps1 = torque_error(Wb(qm, qdm, acc), mem["pu"], th)
        reg = {name: ca.vertcat(*[s.memory(f"b{name}{j}_{N - 1}") for j in range(n)])
               for name in ("q", "qd", "a", "u")}
        Y2 = Wb(reg["q"], reg["qd"], reg["a"])
        eps2 = torque_error(Y2, reg["u"], th)
        count = s.memory("count")
        w1 = ca.if_else(count >= 1, 1.0, 0.0)
        w2 = ca.if_else(count >= N + 1, 1.0, 0.0)
        Y1 = Wb(qm, qdm, acc)
        step = w1 * ca.mtimes(Y1[:, cols].T, eps1) + w2 * ca.mtimes(Y2[:, cols].T, eps2)
        trace = ca.dot(w1 * ca.sum1(Y1[:, cols] ** 2).T + w2 * ca.sum1(Y2[:, cols] ** 2).T, G)
        norm = ca.fmax(1.0, Ts * trace / STEP_LIMIT)
        new = th + Ts * G * step / norm
        out = {"u": u, "q": q, "qd": qd, "qm": qm, "qdm": qdm, "acc": acc, "slm": slm, "sw": sw, "model": model,
               "norm": norm, "qdh": mem["qdh"] + Ts * (model + sw), "eps1": w1 * eps1, "eps2": w2 * eps2, "theta": new,
               "count": ca.fmin(count + 1, N + 1)}
        memo[key] = out
        return out

    def take(name: str, j: int | None = None):
        return (lambda s: parts(s)[name]) if j is None else (lambda s: parts(s)[name][j])

    memory = [Memory(f"th{i}", take("theta", i), float(ident.initial[i]), parameter_unit(x))
              for i, x in enumerate(ident.names)]
    memory.append(Memory("count", take("count"), 0.0, ""))
    for name, source, unit, init in (("qdh", "qdh", "rad/s", None), ("pq", "q", "rad", ident.start),
                                     ("pqd", "qd", "rad/s", None), ("pu", "u", "N*m", None),
                                     ("pslm", "slm", "rad/s", None), ("psw", "sw", "rad/s^2", None),
                                     ("pmodel", "model", "rad/s^2", None)):
        memory += [Memory(f"{name}{j}", take(source, j), float(init[j]) if init else 0.0, unit) for j in range(n)]
    for name, source, unit in (("q", "qm", "rad"), ("qd", "qdm", "rad/s"), ("a", "acc", "rad/s^2"), ("u", "pu", "N*m")):
        for j in range(n):
            if source == "pu":
                memory.append(Memory(f"b{name}{j}_0", (lambda s, j=j: s.memory(f"pu{j}")), 0.0, unit))
            else:
                memory.append(Memory(f"b{name}{j}_0", take(source, j), 0.0, unit))
            memory += [Memory(f"b{name}{j}_{i}", (lambda s, m=f"b{name}{j}_{i - 1}": s.memory(m)), 0.0, unit)
                       for i in range(1, N)]
    for name, source, unit in (("racc", "acc", "rad/s^2"), ("reps1_", "eps1", "N*m"), ("reps2_", "eps2", "N*m")):
        memory += [Memory(f"{name}{j}", take(source, j), 0.0, unit) for j in range(n)]
    names, units = signal_names(ident.names, n)
    # the signals read the memory after the sample's update: the estimates, and this sample's values stored in it
    recorded: dict[str, Any] = {f"{x}_hat": (lambda s, i=i: s.memory(f"th{i}")) for i, x in enumerate(ident.names)}
    for j in range(n):
        for signal, entry in (("slm", "pslm"), ("acc", "racc"), ("model", "pmodel"), ("eps1_", "reps1_"),
                              ("eps2_", "reps2_")):
            recorded[f"{signal}{j + 1}"] = (lambda s, m=f"{entry}{j}": s.memory(m))
    recorded = {k: recorded[k] for k in names}
    return dynamic_law(
        KIND, plant, command=lambda s: parts(s)["u"], memory=memory, signals=recorded, signal_units=units,
        sampling_period=Ts, sampling_period_source="controller.sampling_period", discontinuous=True,
        settings={"form": "robot", "servo": {"K1": list(ident.K1), "K2": list(ident.K2)},
                  "switching_gain": list(ident.switching), "window": ident.window, "identify": list(ident.names),
                  "gamma": list(ident.gamma), "initial": list(ident.initial), "sampling_period": Ts,
                  "delay_samples": N},
    )
