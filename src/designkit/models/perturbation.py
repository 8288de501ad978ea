"""Proven bound of the perturbation ``xi_i`` each joint's decentralized model leaves, over a box of configurations,
velocities, accelerations and, optionally, of the robot's parameters (re-exported by :mod:`designkit.models.bounds`).

Joint ``i`` is modelled as ``D_ii^ q_i'' + f_i q_i' = u_i - g^_i(q) + xi_i`` with constants ``D_ii^``, ``f_i`` and
the gravity feed-forward ``g^(q)`` of the *nominal* parameters ``p0`` (or none); the true arm's parameters ``p``
lie in a box ``[p_low, p_high]`` (``p0`` itself without one).  So

    -xi_i = (D_ii(q, p) - D_ii^) q_i'' + sum_(j != i) D_ij(q, p) q_j'' + sum_(j,k) Gamma_ijk(q, p) q_j' q_k'
            + (g_i(q, p) - [g_i(q, p0) when fed forward]) + (Fv_i(p) - f_i) q_i' + Fc_i(p) sign(q_i')

The parameters with ``p_high > p_low`` are input dimensions of the enclosure like the joints, bisected by the same
branch and bound; the others are constants.  The joints an entry cannot depend on (:mod:`designkit.models.bounds`)
are a property of the chain's geometry for *every* value of the inertial parameters, so holding them is valid with
the parameters free.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from designkit.errors import ModelError

__all__ = ["PerturbationEnclosure", "evaluate_rows", "perturbation_enclosure"]


def _side(value: Any, n: int, name: str) -> tuple[np.ndarray, np.ndarray]:
    """``(low, high)`` arrays of ``n`` values from ``(low, high)`` (each one value or ``n``) or one value."""
    if isinstance(value, tuple | list) and len(value) == 2:
        lo, hi = value
    else:
        lo = hi = value
    try:
        lo_a = np.broadcast_to(np.asarray(lo, dtype=float).reshape(-1), (n,)).copy()
        hi_a = np.broadcast_to(np.asarray(hi, dtype=float).reshape(-1), (n,)).copy()
    except (TypeError, ValueError):
        raise ModelError(name, f"must be (low, high) with one value or {n} values per side") from None
    return lo_a, hi_a


@dataclass(frozen=True)
class PerturbationEnclosure:
    """Proven bounds of the perturbation ``xi_i`` each joint's decentralized model leaves, over a box.

    Parameters
    ----------
    upper : tuple of float
        Per joint, proven: ``|xi_i| <= upper[i]`` (N*m or N) at every point of the box.
    sampled : tuple of float
        Per joint, the largest ``|xi_i|`` attained at a point of the box (evaluated with the model's
        inverse dynamics, not with the enclosure): a lower bound of ``sup |xi_i|``.
    argmax : tuple of dict
        Per joint, that point: ``{"q", "qd", "qdd"}`` (rad, rad/s, rad/s^2 per joint), and ``"p"`` (the whole
        parameter vector, SI units) when a parameter box was given.
    terms : tuple of dict
        Per joint, on the box that sets ``upper[i]``: the proven bound of each part of ``xi_i`` (N*m):
        ``own_inertia``, ``coupling``, ``coriolis``, ``gravity`` (with a feed-forward, the residual
        ``g(q, p) - g(q, p0)``), ``friction`` (with the change of the viscous and Coulomb coefficients over the
        parameter box).  With a parameter box each part holds for every parameter of it.
    boxes : int
        Boxes of configurations (and parameters) enclosed (ball-arithmetic evaluations of ``D``, the Christoffel
        symbols and ``g``).
    converged : tuple of bool
        Per joint, ``upper - sampled <= rel_tol sampled + abs_tol`` reached before the work limit.
    seconds : float
        Wall time (s).
    """

    upper: tuple[float, ...]
    sampled: tuple[float, ...]
    argmax: tuple[dict, ...]
    terms: tuple[dict, ...]
    boxes: int
    converged: tuple[bool, ...]
    seconds: float
    rel_tol: float
    max_boxes: int


@dataclass(frozen=True)
class _Level:
    """Entries of ``D``, ``Gamma`` (``j <= k``), the gravity part and the friction changes whose inputs are the
    box sides ``free`` (joints ``0..n-1``, then the free parameters ``n..``), as a ball tape of ``[entries, vec of
    their Jacobian in the free sides]`` and one of the entries alone."""

    names: tuple[tuple, ...]
    free: tuple[int, ...]
    tape: Any
    tape_jac: Any


@dataclass(frozen=True)
class _Parameters:
    """The parameter box: nominal ``p0``, ``low``, ``high`` (None for a numeric robot), the free ones' indices."""

    nominal: np.ndarray | None
    low: np.ndarray | None
    high: np.ndarray | None
    free: tuple[int, ...]
    given: bool

    @property
    def moved(self) -> np.ndarray:
        """Per parameter, whether the box holds a value other than the nominal one."""
        if self.nominal is None:
            return np.zeros(0, dtype=bool)
        return (self.low != self.nominal) | (self.high != self.nominal)


def _parameters(robot: Any, p: Any, p_box: Any) -> _Parameters:
    if p is None:
        if p_box is not None:
            raise ModelError("p_box", "a parameter box needs the nominal parameters p")
        return _Parameters(None, None, None, (), False)
    p0 = np.asarray(p, dtype=float).reshape(-1)
    if p_box is None:
        return _Parameters(p0, p0, p0, (), False)
    lo, hi = _side(p_box, p0.size, "p_box")
    bad = np.flatnonzero(~(np.isfinite(lo) & np.isfinite(hi)) | (lo > hi))
    if bad.size:
        k = int(bad[0])
        name = robot.symbol_names[k] if k < len(robot.symbol_names) else str(k)
        raise ModelError(f"p_box[{k}]", f"{name}: low {lo[k]:g} must be finite and at most high {hi[k]:g}")
    return _Parameters(p0, lo, hi, tuple(int(j) for j in np.flatnonzero(hi > lo)), True)


def _depends(expr: ca.SX, on: ca.SX, which: np.ndarray) -> bool:
    """Whether ``expr`` depends structurally on an element of ``on`` flagged in ``which``."""
    if not which.any() or expr.is_constant():
        return False
    return bool(np.any(np.array(ca.which_depends(ca.densify(expr), on, 1, False), dtype=bool) & which))


def _levels(robot: Any, par: _Parameters, gravity: bool, centre: np.ndarray) -> tuple[list[_Level], np.ndarray]:
    """One :class:`_Level` per leading joint held: ``D_ij`` and ``Gamma_ijk`` depend only on ``q_(m+1), ..., q_n``
    with ``m`` the smallest of their (1-based) indices (:mod:`designkit.models.bounds`; for ``Gamma``, a sum of
    derivatives of ``D_ab`` that depend on ``q_(min(a, b)+1), ...``), so those joints are replaced by constants
    (``centre``) before the tape is written: the enclosure no longer widens over joints the entry does not depend
    on.  The gravity part (``g`` without a feed-forward, the residual ``g(q, p) - g(q, p0)`` with one when a
    parameter it depends on moves) depends on every joint; the friction changes on no joint.

    Also returns, per free parameter, whether ``D``, ``Gamma``, ``g`` and the friction coefficients are affine in it
    (its second derivative structurally zero): then ``|xi_i|`` is convex along that side for every other value, so
    its supremum over the side is at one of the two ends (:func:`perturbation_enclosure` splits it there)."""
    from designkit.bounds.tape import compile_tape

    n = robot.n
    q = ca.SX.sym("q", n)
    kp = len(par.free)
    ps = ca.SX.sym("p", kp)
    if par.nominal is None:
        args, full, p0 = [q], None, None
    else:
        p0 = ca.DM(par.nominal)
        if kp:
            where = {j: r for r, j in enumerate(par.free)}
            full = ca.vertcat(*[ps[where[j]] if j in where else ca.SX(float(par.low[j]))
                                for j in range(par.nominal.size)])
        else:
            full = ca.DM(par.low)
        args = [q, full]
    D = robot.functions["mass_matrix"](*args)
    G = robot.functions["christoffel"](*args)
    plain = [ca.vec(D), ca.vec(G)]  # the model's entries as functions of the parameters, for the affine test
    groups: dict[int, list[tuple[tuple, ca.SX]]] = {}
    for i in range(n):
        for j in range(n):
            groups.setdefault(min(i, j), []).append((("D", i, j), D[i, j]))
            for k in range(j, n):
                groups.setdefault(min(i, j, k), []).append((("G", i, j, k), G[i, j + n * k]))
    moved = par.moved
    symbols = ca.SX.sym("P", moved.size)
    t = ca.SX.sym("t")  # the mean-value point's place between p0 and p, the box side n + kp: [0, 1]
    gfun = robot.functions["gravity_torque"]
    if gravity:
        g = gfun(*args)
        groups[-1] = [(("g", i), g[i]) for i in range(n)]
    elif par.nominal is not None and _depends(gfun(q, symbols), symbols, moved):
        g = _change(gfun(q, symbols), symbols, full, p0, t)
        groups[-1] = [(("g", i), g[i]) for i in range(n)]
        plain.append(gfun(*args))
    if robot.friction and par.nominal is not None and moved.any():
        syms = ca.vertcat(*[s for _, s in robot.description.symbols])
        for i, link in enumerate(robot.description.links):
            for key, coef in (("fv", link.viscous), ("fc", link.coulomb)):
                c = ca.SX(coef) if not isinstance(coef, ca.SX) else coef
                if _depends(c, syms, moved):
                    groups.setdefault(n - 1, []).append(((key, i), _change(c, syms, full, p0, t)))
                    plain.append(ca.substitute(c, syms, ca.SX(full)))
    every = ca.vertcat(*plain)
    affine = np.array([not ca.depends_on(ca.jacobian(every, ps[r]), ps[r]) for r in range(kp)], dtype=bool)
    out = []
    for m in sorted(groups):
        names = tuple(name for name, _ in groups[m])
        expr = ca.vertcat(*[e for _, e in groups[m]])
        joints = tuple(range(m + 1, n))
        held = list(range(0, m + 1))
        if held:
            expr = ca.substitute(expr, q[held], ca.DM(centre[held]))
        with_t = bool(ca.depends_on(expr, t))
        x = ca.vertcat(q[list(joints)] if joints else ca.SX(0, 1), ps, t if with_t else ca.SX(0, 1))
        free = joints + tuple(range(n, n + kp)) + ((n + kp,) if with_t else ())
        F = ca.densify(expr)
        J = ca.densify(ca.vec(ca.jacobian(F, x))) if free else ca.SX(0, 1)
        tape = compile_tape(ca.Function(f"xi_level{m + 1}", [x], [F]))
        tape_jac = compile_tape(ca.Function(f"xi_level{m + 1}_jac", [x], [ca.vertcat(F, J)]))
        out.append(_Level(names, free, tape, tape_jac))
    return out, affine


def _change(expr: ca.SX, P: ca.SX, full: Any, p0: Any, t: ca.SX) -> ca.SX:
    """``expr(full) - expr(p0)`` written so that it cancels: ``J(p0 + t (full - p0)) (full - p0)`` with ``J`` the
    Jacobian of ``expr`` in ``P`` -- for each entry, some ``t`` in ``[0, 1]`` gives the difference exactly (the mean
    value theorem on the segment from ``p0`` to ``full``), so its enclosure over ``t`` in ``[0, 1]`` holds.  An
    entry affine in the parameters (a mass, a viscous coefficient) does not depend on ``t``: its enclosure is then
    ``coefficient(Q) (P - p0)``, not the width of two enclosures of ``expr`` that do not cancel."""
    d = ca.SX(full) - ca.SX(p0)
    return ca.mtimes(ca.substitute(ca.jacobian(expr, P), P, ca.SX(p0) + t * d), d)


def evaluate_rows(robot: Any, name: str, args: list[np.ndarray], P: np.ndarray | None, p0: Any) -> np.ndarray:
    """``robot.functions[name]`` at ``N`` rows of ``args`` with the parameters of each row ``P`` (N, n_p), or the
    shared ``p0`` when ``P`` is None; shape (N, n_out)."""
    if P is None:
        return getattr(robot, name)(*args, p=p0).reshape(args[0].shape[0], -1)
    f = robot.functions[name]
    rows = args[0].shape[0]
    out = f.map(rows)(*[np.ascontiguousarray(a.T) for a in args], np.ascontiguousarray(P.T))
    return np.asarray(out, dtype=float).T.reshape(rows, -1)


def perturbation_enclosure(robot: Any, *, q: Any, qd_limit: Any, qdd_limits: Any, inertia: Any, damping: Any,
                           coulomb: Any, gravity: bool, p: Any = None, p_box: Any = None, rel_tol: float = 0.05,
                           abs_tol: float = 1e-6, max_boxes: int = 150, samples: int = 2000,
                           seed: int = 0) -> PerturbationEnclosure:
    """Proven ``sup |xi_i|`` per joint of ``D_ii^ q_i'' + f_i q_i' = u_i + xi_i`` over a box.

    ``xi_i`` is the robot's inverse dynamics with parameters ``p`` in ``p_box`` minus the joint's simplified model
    (module docstring): with the gravity torque when it is not fed forward (``gravity``), else the residual of the
    nominal feed-forward ``g(q, p0)``.  The box: ``q`` in ``(low, high)``, ``|q_j'| <= qd_limit[j]``, for joint
    ``i`` ``|q_j''| <= qdd_limits[i][j]`` (one acceleration box per joint: the hierarchy of control gives each
    joint its own), and ``p`` in ``p_box``.

    **How it is proven.**  ``D(q, p)``, every Christoffel symbol ``Gamma_ijk(q, p)`` (``C(q, q') q' = sum_jk
    Gamma_ijk q_j' q_k'``, ``Gamma_ijk = Gamma_ikj``), the gravity part and the friction coefficients' change are
    enclosed together on a box of configurations and parameters by ball arithmetic on their expression graph
    (:mod:`designkit.bounds.tape`): the natural extension intersected with the mean-value form ``F(c) + J(B)(B -
    c)`` about the box's centre, ``J`` the exact Jacobian's enclosure (:mod:`designkit.bounds.forms`); each is then
    combined with the velocity and acceleration boxes by interval arithmetic (``q_j'^2`` in ``[0, V_j^2]``, ``q_j'
    q_k'`` in ``[-V_j V_k, V_j V_k]``), and the Coulomb part by ``|Fc_i|``.  So ``xi_i``'s enclosure on a box
    holds for every velocity and acceleration of their boxes.  Branch and bound over the configurations and the
    free parameters (the box with the largest bound bisected across the side with the largest estimated effect on
    it, ``w_k sum |d entry/d x_k| x its velocity or acceleration weight`` from the Jacobian enclosures, Kearfott's
    smear rule; evaluations cached across the joints) tightens it until ``upper - sampled <= rel_tol sampled +
    abs_tol`` or ``max_boxes`` boxes per joint (the work limit; the bound holds either way).  Joint 1 is held at
    the middle of its side when no gravity part is left (``D`` and ``Gamma`` do not depend on it).

    **The attained values.**  At ``samples`` random points (configuration, and parameters: half of them at
    vertices of the parameter box), and at each bisected box's centre (with its parameters at the centre and at
    its two extreme corners), every vertex of the velocity box is tried with the accelerations at the signs that
    add up, and ``xi_i`` is evaluated there with the robot's inverse dynamics (an independent route from the
    enclosure).

    Parameters
    ----------
    robot : Robot
    q : (low, high)
        Configuration box (rad or m per joint).
    qd_limit : array_like
        Velocity limits ``V_j`` (rad/s), the box ``|q_j'| <= V_j``.
    qdd_limits : array_like, shape (n, n)
        Row ``i``: the acceleration limits (rad/s^2) of every joint as joint ``i``'s bound sees them.
    inertia, damping, coulomb : array_like
        Per joint ``D_ii^`` (kg*m^2), ``f_i`` (N*m*s/rad) of the simplified model, and a bound (N*m) of
        ``|friction_i(q_i') - f_i q_i'|`` over the velocity box *at the nominal parameters*: ``|Fc_i|`` when
        ``f_i`` is the joint's viscous friction (the caller's responsibility); the change of the robot's viscous
        and Coulomb coefficients over ``p_box`` is added here.
    gravity : bool
        Whether ``g(q)`` is part of ``xi`` (no gravity feed-forward).
    p : array_like, optional
        The robot's nominal parameter values (those of the feed-forward; the true ones without ``p_box``).
    p_box : (low, high), optional
        The box of the true robot's parameters (one value or one per parameter per side, SI units); a side with
        ``low == high`` holds that parameter at that value.
    rel_tol, abs_tol, max_boxes, samples, seed
        Tolerance, work limit per joint, random points of the sampled lower bound and their seed.

    Returns
    -------
    PerturbationEnclosure

    Raises
    ------
    ModelError
        ``q[k]`` with ``low > high``; ``p_box[k]`` with ``low > high`` or not finite.
    """
    import heapq
    import time

    from designkit.bounds.tape import evaluate, point_ball, span_ball, upper_float

    t0 = time.perf_counter()
    n = robot.n
    lo, hi = _side(q, n, "q")
    if np.any(lo > hi):
        k = int(np.flatnonzero(lo > hi)[0])
        raise ModelError(f"q[{k}]", f"low {lo[k]:g} is above high {hi[k]:g}")
    par = _parameters(robot, p, p_box)
    pf = list(par.free)
    kp = len(pf)
    V = np.abs(np.asarray(qd_limit, dtype=float).reshape(n))
    A = np.abs(np.asarray(qdd_limits, dtype=float).reshape(n, n))
    Dh = np.asarray(inertia, dtype=float).reshape(n)
    f = np.asarray(damping, dtype=float).reshape(n)
    Fc = np.abs(np.asarray(coulomb, dtype=float).reshape(n))
    levels, affine = _levels(robot, par, gravity, 0.5 * (lo + hi))
    present = {name for lev in levels for name in lev.names}
    if not any(name[0] == "g" for name in present):
        lo = lo.copy()
        hi = hi.copy()
        lo[0] = hi[0] = 0.5 * (lo[0] + hi[0])
    arb = span_ball(0.0, 0.0).__class__
    acc = [[span_ball(-A[i, j], A[i, j]) for j in range(n)] for i in range(n)]
    vel = [span_ball(-V[j], V[j]) for j in range(n)]
    vel2 = [[span_ball(-V[j] * V[k], V[j] * V[k]) for k in range(n)] for j in range(n)]
    fric = [span_ball(-Fc[i], Fc[i]) for i in range(n)]
    sign = span_ball(-1.0, 1.0)

    def square(G: Any, j: int) -> Any:  # Gamma * [0, V_j^2], from the endpoints
        v2 = arb(V[j]) * arb(V[j])
        a, b = G.lower(), G.upper()
        return (arb(0).union(a) * v2).union(arb(0).union(b) * v2)

    cache: dict[tuple, tuple[np.ndarray, list[dict], np.ndarray]] = {}

    def bound_box(key: tuple) -> tuple[np.ndarray, list[dict], np.ndarray]:
        if key in cache:
            return cache[key]
        blo, bhi = np.array(key[0]), np.array(key[1])
        c = 0.5 * (blo + bhi)
        ball: dict[tuple, Any] = {}
        slope: dict[tuple, float] = {}
        for lev in levels:  # the natural extension intersected with the mean-value form
            fr = list(lev.free)
            m = len(lev.names)
            if not fr:
                for name, b in zip(lev.names, evaluate(lev.tape, []), strict=True):
                    ball[name] = b
                continue
            both = evaluate(lev.tape_jac, [span_ball(float(blo[k]), float(bhi[k])) for k in fr])
            at_c = evaluate(lev.tape, [point_ball(float(c[k])) for k in fr])
            steps = [span_ball(float(blo[k] - c[k]), float(bhi[k] - c[k])) for k in fr]
            for r, name in enumerate(lev.names):
                mv = at_c[r]
                for col, k in enumerate(fr):
                    if bhi[k] > blo[k]:
                        J = both[m + r + m * col]
                        mv = mv + J * steps[col]
                        slope[(name, k)] = abs(float(J.mid())) + float(J.rad())
                ball[name] = both[r].intersection(mv)

        def Dm(i: int, j: int) -> Any:
            return ball[("D", i, j)]

        def Gm(i: int, j: int, k: int) -> Any:
            return ball[("G", i, min(j, k), max(j, k))]

        bounds, parts = np.empty(n), []
        for i in range(n):
            own = (Dm(i, i) - arb(Dh[i])) * acc[i][i]
            coup = arb(0)
            for j in range(n):
                if j != i:
                    coup = coup + Dm(i, j) * acc[i][j]
            cor = arb(0)
            for j in range(n):
                cor = cor + square(Gm(i, j, j), j)
                for k in range(j + 1, n):
                    cor = cor + 2 * Gm(i, j, k) * vel2[j][k]
            grav = ball.get(("g", i), arb(0))
            fr_i = fric[i]
            if ("fv", i) in ball:
                fr_i = fr_i + ball[("fv", i)] * vel[i]
            if ("fc", i) in ball:
                fr_i = fr_i + ball[("fc", i)] * sign
            total = own + coup + cor + grav + fr_i
            bounds[i] = upper_float(abs(total))
            parts.append({"own_inertia": upper_float(abs(own)), "coupling": upper_float(abs(coup)),
                          "coriolis": upper_float(abs(cor)), "gravity": upper_float(abs(grav)),
                          "friction": float(Fc[i]) if fr_i is fric[i] else upper_float(abs(fr_i))})
        smear = np.zeros((n, n + kp))  # joint i's bound's sensitivity to side k: |d xi_i/d x_k| w_k, roughly
        width = bhi - blo
        for i in range(n):
            for k in range(n + kp):
                if width[k] <= 0:
                    continue
                tot = sum(slope.get((("D", i, j), k), 0.0) * A[i, j] for j in range(n))
                for j in range(n):
                    for kk in range(j, n):
                        tot += slope.get((("G", i, j, kk), k), 0.0) * V[j] * V[kk] * (1.0 if j == kk else 2.0)
                tot += slope.get((("g", i), k), 0.0) + slope.get((("fv", i), k), 0.0) * V[i]
                tot += slope.get((("fc", i), k), 0.0)
                smear[i, k] = tot * width[k]
        cache[key] = (bounds, parts, smear)
        return cache[key]

    corners = np.array(np.meshgrid(*[[-1.0, 1.0]] * n, indexing="ij")).reshape(n, -1).T * V  # velocity vertices
    nc = corners.shape[0]

    def attained(qs: np.ndarray, ps: np.ndarray | None) -> tuple[np.ndarray, list]:
        """Per joint the largest |xi_i| over the velocity vertices at configurations ``qs`` (m, n), with the
        parameters ``ps`` (m, n_p) of each (None: the nominal ones)."""
        m = qs.shape[0]
        Qr = np.repeat(qs, nc, axis=0)
        Vr = np.tile(corners, (m, 1))
        Pr = None if ps is None else np.repeat(ps, nc, axis=0)
        Dq = evaluate_rows(robot, "mass_matrix", [qs], ps, par.nominal).reshape(m, n, n)
        best = np.full(n, -1.0)
        arg = [None] * n
        rest = evaluate_rows(robot, "inverse_dynamics", [Qr, Vr, np.zeros_like(Qr)], Pr, par.nominal) - f * Vr
        if not gravity:  # the nominal feed-forward
            rest = rest - robot.gravity_torque(Qr, p=par.nominal).reshape(-1, n)
        for i in range(n):
            r_i = rest[:, i]
            coef = np.repeat(Dq[:, i, :] - np.eye(n)[i] * Dh[i], nc, axis=0)
            s = np.where(r_i >= 0, 1.0, -1.0)
            Acc = s[:, None] * np.sign(coef) * A[i]
            k = int(np.argmax(np.abs(r_i) + np.abs(coef) @ A[i]))
            pk = par.nominal if Pr is None else Pr[k]
            xi = robot.inverse_dynamics(Qr[k], Vr[k], Acc[k], p=pk).reshape(n)[i] - Dh[i] * Acc[k, i] - f[i] * Vr[k, i]
            if not gravity:
                xi -= float(robot.gravity_torque(Qr[k], p=par.nominal).reshape(n)[i])
            if abs(xi) > best[i]:
                best[i] = abs(float(xi))
                arg[i] = (Qr[k].copy(), Vr[k].copy(), Acc[k].copy(), None if Pr is None else Pr[k].copy())
        return best, arg

    rng = np.random.default_rng(seed)
    count = max(int(samples), 1)
    qs = lo + (hi - lo) * rng.random((count, n))
    vary = par.given and bool(par.moved.any())  # else every point has the nominal parameters
    ps = None
    if vary:
        ps = np.tile(par.low, (count, 1))
        if kp:
            u = rng.random((count, kp))
            u[: count // 2] = np.round(u[: count // 2])  # half of them at vertices of the parameter box
            ps[:, pf] = par.low[pf] + (par.high[pf] - par.low[pf]) * u
    sampled, argmax = attained(qs, ps)
    lo_all = np.concatenate([lo, par.low[pf] if kp else []])
    hi_all = np.concatenate([hi, par.high[pf] if kp else []])
    free = hi_all > lo_all
    if any(n + kp in lev.free for lev in levels):  # the mean-value point's side, [0, 1], never bisected
        lo_all, hi_all, free = np.append(lo_all, 0.0), np.append(hi_all, 1.0), np.append(free, False)
    upper = np.empty(n)
    terms: list[dict] = [{} for _ in range(n)]
    converged = []
    for i in range(n):
        root = (tuple(lo_all), tuple(hi_all))
        heap = [(-bound_box(root)[0][i], root)]
        work = 1
        while True:
            negb, key = heap[0]
            if -negb - sampled[i] <= rel_tol * sampled[i] + abs_tol:
                converged.append(True)
                break
            if work >= max_boxes or not free.any():
                converged.append(not free.any())
                break
            heapq.heappop(heap)
            blo, bhi = np.array(key[0]), np.array(key[1])
            sm = bound_box(key)[2][i]
            sm = np.pad(sm, (0, free.size - sm.size))
            k = int(np.argmax(np.where(free & (bhi > blo), sm, -1.0)))
            if sm[k] <= 0:  # no sensitivity left: the widest side
                k = int(np.argmax(np.where(free, bhi - blo, -1.0)))
            mid = 0.5 * (blo[k] + bhi[k])
            centre = 0.5 * (blo + bhi)[: n + kp]
            if vary:  # the parameters at the box's centre and at its two extreme corners
                pc = np.tile(par.low, (3 if kp else 1, 1))
                if kp:
                    pc[:, pf] = np.array([centre[n:], blo[n:n + kp], bhi[n:n + kp]])
                val, arg = attained(np.repeat(centre[None, :n], pc.shape[0], axis=0), pc)
            else:
                val, arg = attained(centre[None, :n], None)
            for jj in range(n):
                if val[jj] > sampled[jj]:
                    sampled[jj], argmax[jj] = val[jj], arg[jj]
            left_hi, right_lo = bhi.copy(), blo.copy()
            if k >= n and affine[k - n]:  # |xi_i| convex along the side: its ends (docstring)
                left_hi[k], right_lo[k] = blo[k], bhi[k]
            else:
                left_hi[k] = mid
                right_lo[k] = mid
            for child in ((tuple(blo), tuple(left_hi)), (tuple(right_lo), tuple(bhi))):
                heapq.heappush(heap, (-bound_box(child)[0][i], child))
                work += 1
        upper[i] = -heap[0][0]
        terms[i] = bound_box(heap[0][1])[1][i]

    def where(a: tuple) -> dict:
        out = {"q": a[0].tolist(), "qd": a[1].tolist(), "qdd": a[2].tolist()}
        if par.given:
            out["p"] = (par.nominal if a[3] is None else a[3]).tolist()
        return out

    return PerturbationEnclosure(
        upper=tuple(float(u) for u in upper), sampled=tuple(float(s) for s in sampled),
        argmax=tuple(where(a) for a in argmax), terms=tuple(terms), boxes=len(cache), converged=tuple(converged),
        seconds=time.perf_counter() - t0, rel_tol=float(rel_tol), max_boxes=int(max_boxes))
