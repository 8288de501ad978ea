"""The self-tuner on an ARX model of general orders as one sampled CasADi law (:mod:`.arx` for the algebra).

Discrete memory, updated at each sample ``k`` from the measured output ``y(k)`` and the reference ``r(k)``:

* ``th1 .. thn``, ``P11 .. Pnn``, ``phi1 .. phin``, ``eps``: the estimates, the covariance, this sample's regressor
  and its a-priori error (as in the link's forms, :mod:`.laws`);
* ``y1 ..``, ``u1 ..``, ``xD1 ..``: past outputs, inputs and references (``y(k-1)`` first).  Before the first sample
  the plant is taken at rest with zero input (past outputs ``y(0)``, past inputs 0), so the regressors are exact
  from the first sample on when the plant starts at rest;
* the controller's coefficients ``R1 ..`` (``R`` monic), ``S0 ..``, ``T0 ..``, ``u`` the command of this sample,
  and the flags ``held`` and ``bounded``.

At each sample: the RLS update of :func:`.rls.rls_step`, the Diophantine equation of the estimated model solved by
CasADi's linear solve (the Sylvester matrix of :func:`.arx.sylvester`), then
``u(k) = -R1 u(k-1) - ... + T(q) r - S(q) y`` (every polynomial divided by ``q^deg R``).  With ``safeguards``, the
controller is held (previous coefficients kept) when the new coefficients are not finite or larger than
:data:`MAX_COEFFICIENT`, or when the static gain ``B(1)`` (zeros kept) or ``b0`` (zeros cancelled) is below
:data:`MIN_GAIN` of ``sum |b_j|``: a model with no input-output gain gives no controller.
"""

from __future__ import annotations

from typing import Any

import casadi as ca

from designkit.families.self_tuning.arx import Orders, controller_degrees, place, solve_design
from designkit.families.self_tuning.rls import rls_step
from designkit.synthesis.law import Law, LawSymbols, Memory, dynamic_law

__all__ = ["MAX_COEFFICIENT", "MIN_GAIN", "arx_controller_names", "arx_law", "arx_memory_names", "initial_arx"]

MAX_COEFFICIENT = 1e9
"""A controller coefficient beyond this is refused (the controller held)."""
MIN_GAIN = 1e-9
"""The gain the design divides by, relative to ``sum |b_j|``, below which the controller is held."""


def orders_of(st: Any) -> Orders:
    """The :class:`.arx.Orders` of the settings."""
    return Orders(*st.orders)


def degrees(st: Any) -> tuple[int, int, int]:
    """``(deg R, deg S, deg T)`` of the settings' design."""
    return controller_degrees(orders_of(st), len(st.am) - 1, len(st.ao) - 1, st.cancel)


def arx_controller_names(st: Any) -> tuple[str, ...]:
    """``R1 .. R_nr, S0 .. S_ns, T0 .. T_nt``."""
    nr, ns, nt = degrees(st)
    return (*(f"R{i + 1}" for i in range(nr)), *(f"S{j}" for j in range(ns + 1)), *(f"T{j}" for j in range(nt + 1)))


def lags(st: Any) -> tuple[int, int, int]:
    """How many past outputs, inputs and references the law keeps."""
    o = orders_of(st)
    nr = degrees(st)[0]
    return max(o.na, nr), max(o.d + o.nb - 1, nr), nr


def arx_memory_names(st: Any) -> tuple[str, ...]:
    """Every memory entry of the law, in order (module docstring)."""
    n = st.n
    ny, nu, nx = lags(st)
    return (*(f"th{i + 1}" for i in range(n)), *(f"P{i + 1}{j + 1}" for i in range(n) for j in range(n)),
            *(f"phi{i + 1}" for i in range(n)), "eps", *(f"y{i + 1}" for i in range(ny)),
            *(f"u{i + 1}" for i in range(nu)), *(f"xD{i + 1}" for i in range(nx)), "k", *arx_controller_names(st),
            "u", "held", "bounded")


def initial_arx(st: Any) -> tuple[float, ...]:
    """The controller coefficients designed on ``theta0`` (NumPy), in :func:`arx_controller_names`' order."""
    p = place(st.theta0, orders_of(st), st.am, st.ao, st.cancel)
    return (*p.R[1:], *p.S, *p.T)


def _solve(M: list[list[Any]], rhs: list[Any]) -> list[Any]:
    x = ca.solve(ca.vertcat(*[ca.horzcat(*row) for row in M]), ca.vertcat(*rhs))
    return [x[i] for i in range(x.shape[0])]


def arx_law(kind: str, nominal: Any, st: Any) -> Law:
    """The sampled ARX self-tuning law (module docstring) of controller kind ``kind`` for the plant layout of
    ``nominal``."""
    n = st.n
    o = orders_of(st)
    names = arx_memory_names(st)
    ctrl = arx_controller_names(st)
    nr, ns, nt = degrees(st)
    ny, nu, nx = lags(st)
    memo: dict[int, dict[str, ca.SX]] = {}

    def parts(s: LawSymbols) -> dict[str, ca.SX]:
        key = id(s)
        if key in memo:
            return memo[key]
        mem = s.memory
        k = mem("k")
        y, r = s.q[0], s.qD[0]
        first = k < 0.5
        ys = [ca.if_else(first, y, mem(f"y{i + 1}")) for i in range(ny)]
        us = [mem(f"u{i + 1}") for i in range(nu)]
        rs = [ca.if_else(first, r, mem(f"xD{i + 1}")) for i in range(nx)]
        theta = ca.vertcat(*[mem(f"th{i + 1}") for i in range(n)])
        P = ca.reshape(ca.vertcat(*[mem(f"P{i + 1}{j + 1}") for i in range(n) for j in range(n)]), n, n).T
        phi = ca.vertcat(*[-ys[i] for i in range(o.na)], *[us[o.d + j - 1] for j in range(o.nb)])
        est = rls_step(st, theta, P, phi, y, ca.logic_not(first) if st.estimate else ca.SX(0))
        th = [est["theta"][i] for i in range(n)]
        R, S, T, _ = solve_design(th, o, st.am, st.ao, st.cancel, _solve)
        new = [*R[1:], *S, *T]
        old = [mem(c) for c in ctrl]
        if st.safeguards:
            b = th[o.na:]
            scale = sum(ca.fabs(v) for v in b) + 1e-300
            gain = b[0] if st.cancel else sum(b)
            ok = ca.fabs(gain) > MIN_GAIN * scale
            for v in new:
                ok = ca.logic_and(ok, ca.fabs(v) < MAX_COEFFICIENT)  # false for NaN and inf
            coefs = [ca.if_else(ok, a, c) for a, c in zip(new, old, strict=True)]
            held = 1 - ok
        else:
            coefs, held = new, ca.SX(0)
        Rc, Sc, Tc = coefs[:nr], coefs[nr:nr + ns + 1], coefs[nr + ns + 1:]
        # R(q) u = T(q) r - S(q) y, divided by q^nr: lag of T_j is (nr - nt) + j, of S_j (nr - ns) + j
        past_y = [y, *ys]
        past_r = [r, *rs]
        u = -sum((Rc[i] * us[i] for i in range(nr)), ca.SX(0))
        u = u + sum((Tc[j] * past_r[nr - nt + j] for j in range(nt + 1)), ca.SX(0))
        u = u - sum((Sc[j] * past_y[nr - ns + j] for j in range(ns + 1)), ca.SX(0))
        values = {
            **{f"th{i + 1}": th[i] for i in range(n)},
            **{f"P{i + 1}{j + 1}": est["P"][i, j] for i in range(n) for j in range(n)},
            **{f"phi{i + 1}": phi[i] for i in range(n)}, "eps": est["eps"],
            **{f"y{i + 1}": past_y[i] for i in range(ny)},
            **{f"u{i + 1}": ([u, *us])[i] for i in range(nu)},
            **{f"xD{i + 1}": past_r[i] for i in range(nx)}, "k": k + 1,
            **dict(zip(ctrl, coefs, strict=True)), "u": u, "held": held, "bounded": est["bounded"],
        }
        memo[key] = values
        return values

    def entry(name: str):
        return lambda s: parts(s)[name]

    initial = {name: 0.0 for name in names}
    initial.update({f"th{i + 1}": float(st.theta0[i]) for i in range(n)})
    initial.update({f"P{i + 1}{i + 1}": float(st.P0) for i in range(n)})
    initial.update(dict(zip(ctrl, initial_arx(st), strict=True)))
    memory = [Memory(name, entry(name), initial[name], "") for name in names]
    recorded = (*(f"th{i + 1}" for i in range(n)), *(f"phi{i + 1}" for i in range(n)), "eps", *ctrl, "held",
                "bounded", "k", *(f"P{i + 1}{i + 1}" for i in range(n)))
    return dynamic_law(
        kind, nominal, memory=memory, command=lambda s: s.memory("u"),
        signals={name: (lambda nm: (lambda s: s.memory(nm)))(name) for name in recorded},
        settings={"estimator": f"ARX (na = {o.na}, nb = {o.nb}, d = {o.d})", "sampling_period": st.Ts,
                  "forgetting": st.forgetting, "initial_covariance": st.P0, "initial_estimates": list(st.theta0),
                  "max_trace": st.max_trace, "safeguards": st.safeguards, "design": "pole placement",
                  "zeros": "cancelled" if st.cancel else "kept", "Am": list(st.am), "Ao": list(st.ao),
                  "estimating": st.estimate},
        sampling_period=st.Ts, sampling_period_source="controller.sampling_period",
    )
