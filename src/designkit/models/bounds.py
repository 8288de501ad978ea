"""Proven bounds of a robot's model functions over boxes of configurations and velocities.

:func:`model_bound` encloses one entry of a model function -- the inertia matrix ``D(q)``, the
gravity torques ``g(q)``, the Coriolis and centrifugal torques ``C(q, q') q'`` for bounded
velocities, the inverse dynamics, or any other function in ``Robot.functions`` -- over a box, with
:func:`designkit.bounds.enclose` (Arb ball arithmetic, the mean-value form, branch and bound): the
result's ``[lower, upper]`` holds for every point of the box, and each end has a witness.

**Joints an inertia entry cannot depend on.**  For a serial chain on a fixed base, ``D_ij`` depends
only on ``q_(m+1), ..., q_n`` with ``m = min(i, j)`` (1-based): ``D_ij = S_i' I^c_k S_j`` (``k =
max(i, j)``) in the composite-rigid-body algorithm, and the composite inertia ``I^c_k`` of links
``k..n`` and the axes ``S_i``, ``S_j`` keep their relative pose when joints ``1..m`` move the whole
subchain (Featherstone, *Rigid Body Dynamics Algorithms*, 2008, sec. 6.2).  The expression graph does
not show this -- it depends on every joint through the rotations, and the cancellation is exact only
in real arithmetic -- so :func:`model_bound` holds those joints at the middle of their side instead of
letting the enclosure widen over them; a test checks the independence numerically on every zoo robot.
For the same reason the whole of ``D(q)`` and the Coriolis and centrifugal terms (``C(q, q')``, its
Christoffel symbols, ``C(q, q') q'``), which are derivatives of ``D``, do not depend on joint 1.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from designkit.errors import ModelError

__all__ = ["QUANTITIES", "PerturbationEnclosure", "model_bound", "perturbation_enclosure"]

QUANTITIES = ("mass_matrix", "gravity_torque", "coriolis_torque", "inverse_dynamics", "kinetic_energy",
              "potential_energy", "friction_torque")
"""Model functions :func:`model_bound` is documented for (any name in ``Robot.functions`` is accepted)."""


def _side(value: Any, n: int, name: str) -> tuple[np.ndarray, np.ndarray]:
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


def _function(robot: Any, quantity: str) -> ca.Function:
    if quantity == "coriolis_torque":
        c = robot.functions["coriolis_matrix"]
        ins = [ca.SX.sym(c.name_in(i), c.sparsity_in(i)) for i in range(c.n_in())]
        return ca.Function("coriolis_torque", ins, [ca.mtimes(c(*ins), ins[1])], [c.name_in(i) for i in
                                                                                   range(c.n_in())], ["tau_c"])
    try:
        return robot.functions[quantity]
    except KeyError:
        raise ModelError("quantity", f"unknown model function {quantity!r}; known: "
                         f"{sorted([*robot.functions, 'coriolis_torque'])}") from None


def _independent_joints(quantity: str, index: Any) -> int:
    """How many leading joints the entry cannot depend on (module docstring): held fixed."""
    if quantity in ("coriolis_torque", "coriolis_matrix", "christoffel"):
        return 1
    if quantity == "mass_matrix" and index is not None:
        try:
            rc = (int(index), int(index)) if not isinstance(index, tuple | list) else (int(index[0]), int(index[1]))
        except (TypeError, ValueError, IndexError):
            return 0  # enclose names the bad index
        return max(min(rc) + 1, 1)
    return 1 if quantity == "mass_matrix" else 0


def model_bound(robot: Any, quantity: str, index: Any = None, *, q: Any = None, qd: Any = None, qdd: Any = None,
                tau: Any = None, p: Any = None, rel_tol: float = 1e-3, abs_tol: float = 0.0,
                max_boxes: int | None = None, strict: bool = True,
                thresholds: tuple[float | None, float | None] = (None, None)) -> Any:
    """The proven range of one entry of a robot's model function over a box.

    Parameters
    ----------
    robot : Robot
    quantity : str
        ``"mass_matrix"`` (kg*m^2, kg), ``"gravity_torque"``, ``"coriolis_torque"`` (``C(q, q') q'``),
        ``"inverse_dynamics"`` (N*m or N per joint), ``"kinetic_energy"``, ``"potential_energy"`` (J), or any
        other name in ``robot.functions``.
    index : int or (int, int), optional
        0-based entry of the output (``(i, i)`` for ``D_ii``).
    q, qd, qdd, tau : (low, high) or value, optional
        The box of each input the function takes (rad or m; rad/s or m/s; rad/s^2 or m/s^2; N*m or N),
        one value or one per joint per side; a single value holds the input fixed.
    p : array_like, optional
        Values of a symbolic robot's parameters (held fixed).
    rel_tol, abs_tol, max_boxes, strict, thresholds
        As :func:`designkit.bounds.enclose`.

    Returns
    -------
    designkit.bounds.Enclosure

    Examples
    --------
    >>> import designkit as dk
    >>> arm = dk.robot("planar2r")
    >>> e = model_bound(arm, "mass_matrix", (0, 0), q=([-3.14, -1.0], [3.14, 1.0]), rel_tol=1e-6)
    >>> bool(e.lower <= arm.mass_matrix([0.0, 1.0])[0, 0] <= e.upper)
    True
    """
    from designkit.bounds import MAX_BOXES, enclose

    f = _function(robot, quantity)
    n = robot.n
    given = {"q": q, "qd": qd, "qdd": qdd, "tau": tau}
    box: dict[str, Any] = {}
    for i in range(f.n_in()):
        name = f.name_in(i)
        if name in given:
            if given[name] is None:
                raise ModelError(name, f"{quantity} depends on {name}: give its box (low, high)")
            box[name] = _side(given[name], n, name)
        elif f.nnz_in(i):
            if p is None:
                raise ModelError("p", f"{quantity} takes the robot's parameters {name!r}: give their values")
            box[name] = np.asarray(p, dtype=float).reshape(-1)
    extra = [k for k, v in given.items() if v is not None and k not in box]
    if extra:
        raise ModelError(extra[0], f"{quantity} does not take {extra[0]} (its inputs: "
                         f"{[f.name_in(i) for i in range(f.n_in())]})")
    held = _independent_joints(quantity, index)
    if held and "q" in box:
        lo, hi = (side.copy() for side in box["q"])
        lo[:held] = hi[:held] = 0.5 * (lo[:held] + hi[:held])  # any value: the witness stays in the box
        box["q"] = (lo, hi)
    return enclose(f, box, index=index, rel_tol=rel_tol, abs_tol=abs_tol,
                   max_boxes=MAX_BOXES if max_boxes is None else max_boxes, strict=strict, thresholds=thresholds)


# ----------------------------------------------------------------------------- the decentralized perturbation


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
        Per joint, that point: ``{"q", "qd", "qdd"}`` (rad, rad/s, rad/s^2 per joint).
    terms : tuple of dict
        Per joint, on the box that sets ``upper[i]``: the proven bound of each part of ``xi_i`` (N*m):
        ``own_inertia``, ``coupling``, ``coriolis``, ``gravity``, ``friction``.
    boxes : int
        Configuration boxes enclosed (ball-arithmetic evaluations of ``D``, the Christoffel symbols and ``g``).
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
    """The entries of ``D``, ``Gamma`` (``j <= k``) or ``g`` that depend only on joints ``free`` (0-based), as a ball
    tape of ``[entries, vec of their Jacobian in the free joints]`` and one of the entries alone."""

    names: tuple[tuple, ...]
    free: tuple[int, ...]
    tape: Any
    tape_jac: Any


def _levels(robot: Any, p: Any, gravity: bool, centre: np.ndarray) -> list[_Level]:
    """One :class:`_Level` per leading joint held: ``D_ij`` and ``Gamma_ijk`` depend only on ``q_(m+1), ..., q_n``
    with ``m`` the smallest of their (1-based) indices (module docstring; for ``Gamma``, a sum of derivatives of
    ``D_ab`` that depend on ``q_(min(a, b)+1), ...``), so those joints are replaced by constants (``centre``)
    before the tape is written: the enclosure no longer widens over joints the entry does not depend on."""
    from designkit.bounds.tape import compile_tape

    n = robot.n
    q = ca.SX.sym("q", n)
    args = [q] + ([ca.DM(np.asarray(p, dtype=float))] if p is not None else [])
    D = robot.functions["mass_matrix"](*args)
    G = robot.functions["christoffel"](*args)
    groups: dict[int, list[tuple[tuple, ca.SX]]] = {}
    for i in range(n):
        for j in range(n):
            groups.setdefault(min(i, j), []).append((("D", i, j), D[i, j]))
            for k in range(j, n):
                groups.setdefault(min(i, j, k), []).append((("G", i, j, k), G[i, j + n * k]))
    if gravity:
        g = robot.functions["gravity_torque"](*args)
        groups[-1] = [(("g", i), g[i]) for i in range(n)]
    out = []
    for m in sorted(groups):
        names = tuple(name for name, _ in groups[m])
        expr = ca.vertcat(*[e for _, e in groups[m]])
        free = tuple(range(m + 1, n))
        held = list(range(0, m + 1))
        if held:
            expr = ca.substitute(expr, q[held], ca.DM(centre[held]))
        qf = q[list(free)] if free else ca.SX(0, 1)
        F = ca.densify(expr)
        J = ca.densify(ca.vec(ca.jacobian(F, qf))) if free else ca.SX(0, 1)
        tape = compile_tape(ca.Function(f"xi_level{m + 1}", [qf], [F]))
        tape_jac = compile_tape(ca.Function(f"xi_level{m + 1}_jac", [qf], [ca.vertcat(F, J)]))
        out.append(_Level(names, free, tape, tape_jac))
    return out


def perturbation_enclosure(robot: Any, *, q: Any, qd_limit: Any, qdd_limits: Any, inertia: Any, damping: Any,
                           coulomb: Any, gravity: bool, p: Any = None, rel_tol: float = 0.05,
                           abs_tol: float = 1e-6, max_boxes: int = 150, samples: int = 2000,
                           seed: int = 0) -> PerturbationEnclosure:
    """Proven ``sup |xi_i|`` per joint of ``D_ii^ q_i'' + f_i q_i' = u_i + xi_i`` over a box.

    ``xi_i = (D_ii(q) - D_ii^) q_i'' + sum_(j != i) D_ij(q) q_j'' + sum_(j,k) Gamma_ijk(q) q_j' q_k'
    + [g_i(q)] + (friction_i(q_i') - f_i q_i')``: the robot's inverse dynamics minus the joint's
    simplified model, with the gravity torque when it is not fed forward (``gravity``).  The box:
    ``q`` in ``(low, high)``, ``|q_j'| <= qd_limit[j]``, and for joint ``i`` ``|q_j''| <= qdd_limits[i][j]``
    (one acceleration box per joint: the hierarchy of control gives each joint its own).

    **How it is proven.**  ``D(q)``, every Christoffel symbol ``Gamma_ijk(q)`` (``C(q, q') q' = sum_jk Gamma_ijk
    q_j' q_k'``, ``Gamma_ijk = Gamma_ikj``) and ``g(q)`` are enclosed together on a box of configurations by
    ball arithmetic on their expression graph (:mod:`designkit.bounds.tape`): the natural extension intersected
    with the mean-value form ``F(c) + J(Q)(Q - c)`` about the box's centre, ``J`` the exact Jacobian's enclosure
    (:mod:`designkit.bounds.forms`); each is then combined with the velocity and acceleration boxes by interval
    arithmetic (``q_j'^2`` in ``[0, V_j^2]``, ``q_j' q_k'`` in ``[-V_j V_k, V_j V_k]``), and the Coulomb part by
    ``|Fc_i|``.  So ``xi_i``'s enclosure on a configuration box holds for every velocity and acceleration of
    their boxes.  Branch and bound over the configurations (the box with the largest bound bisected across the
    side with the largest estimated effect on it, ``w_k sum |d entry/d q_k| x its velocity or acceleration
    weight`` from the Jacobian enclosures, Kearfott's smear rule; evaluations cached across the joints) tightens
    it until ``upper - sampled <= rel_tol sampled + abs_tol`` or ``max_boxes`` boxes per joint (the work limit;
    the bound holds either way).  Joint 1 is held at the middle of its side when gravity is left out (``D`` and
    ``Gamma`` do not depend on it: module docstring).

    **The attained values.**  At each box's centre, and at ``samples`` random configurations, every
    vertex of the velocity box is tried with the accelerations at the signs that add up, and ``xi_i`` is
    evaluated there with the robot's inverse dynamics (an independent route from the enclosure).

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
        ``|friction_i(q_i') - f_i q_i'|`` over the velocity box: ``|Fc_i|`` when ``f_i`` is the joint's viscous
        friction (the caller's responsibility: the robot's friction is not read here).
    gravity : bool
        Whether ``g(q)`` is part of ``xi`` (no gravity feed-forward).
    p : array_like, optional
        The robot's parameter values.
    rel_tol, abs_tol, max_boxes, samples, seed
        Tolerance, work limit per joint, random configurations of the sampled lower bound and their seed.

    Returns
    -------
    PerturbationEnclosure
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
    V = np.abs(np.asarray(qd_limit, dtype=float).reshape(n))
    A = np.abs(np.asarray(qdd_limits, dtype=float).reshape(n, n))
    Dh = np.asarray(inertia, dtype=float).reshape(n)
    f = np.asarray(damping, dtype=float).reshape(n)
    Fc = np.abs(np.asarray(coulomb, dtype=float).reshape(n))
    if not gravity:
        lo = lo.copy()
        hi = hi.copy()
        lo[0] = hi[0] = 0.5 * (lo[0] + hi[0])
    levels = _levels(robot, p, gravity, 0.5 * (lo + hi))
    arb = span_ball(0.0, 0.0).__class__
    acc = [[span_ball(-A[i, j], A[i, j]) for j in range(n)] for i in range(n)]
    vel2 = [[span_ball(-V[j] * V[k], V[j] * V[k]) for k in range(n)] for j in range(n)]
    fric = [span_ball(-Fc[i], Fc[i]) for i in range(n)]

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
            grav = ball[("g", i)] if gravity else arb(0)
            total = own + coup + cor + grav + fric[i]
            bounds[i] = upper_float(abs(total))
            parts.append({"own_inertia": upper_float(abs(own)), "coupling": upper_float(abs(coup)),
                          "coriolis": upper_float(abs(cor)), "gravity": upper_float(abs(grav)),
                          "friction": float(Fc[i])})
        smear = np.zeros((n, n))  # joint i's bound's sensitivity to side k: |d xi_i/d q_k| w_k, roughly
        width = bhi - blo
        for i in range(n):
            for k in range(n):
                if width[k] <= 0:
                    continue
                tot = sum(slope.get((("D", i, j), k), 0.0) * A[i, j] for j in range(n))
                for j in range(n):
                    for kk in range(j, n):
                        tot += slope.get((("G", i, j, kk), k), 0.0) * V[j] * V[kk] * (1.0 if j == kk else 2.0)
                if gravity:
                    tot += slope.get((("g", i), k), 0.0)
                smear[i, k] = tot * width[k]
        cache[key] = (bounds, parts, smear)
        return cache[key]

    corners = np.array(np.meshgrid(*[[-1.0, 1.0]] * n, indexing="ij")).reshape(n, -1).T * V  # velocity vertices

    def attained(qs: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Per joint the largest |xi_i| over the velocity vertices at configurations ``qs`` (m, n)."""
        m = qs.shape[0]
        Qr = np.repeat(qs, corners.shape[0], axis=0)
        Vr = np.tile(corners, (m, 1))
        Dq = robot.mass_matrix(qs, p=p).reshape(m, n, n)
        best = np.full(n, -1.0)
        arg = [None] * n
        rest = robot.inverse_dynamics(Qr, Vr, np.zeros_like(Qr), p=p).reshape(-1, n) - f * Vr
        if not gravity:
            rest = rest - robot.gravity_torque(Qr, p=p).reshape(-1, n)
        for i in range(n):
            coef = np.repeat(Dq[:, i, :] - np.eye(n)[i] * Dh[i], corners.shape[0], axis=0)
            s = np.where(rest[:, i] >= 0, 1.0, -1.0)
            Acc = s[:, None] * np.sign(coef) * A[i]
            k = int(np.argmax(np.abs(rest[:, i]) + np.abs(coef) @ A[i]))
            xi = robot.inverse_dynamics(Qr[k], Vr[k], Acc[k], p=p).reshape(n)[i] - Dh[i] * Acc[k, i] - f[i] * Vr[k, i]
            if not gravity:
                xi -= float(robot.gravity_torque(Qr[k], p=p).reshape(n)[i])
            if abs(xi) > best[i]:
                best[i], arg[i] = abs(float(xi)), (Qr[k].copy(), Vr[k].copy(), Acc[k].copy())
        return best, arg

    rng = np.random.default_rng(seed)
    qs = lo + (hi - lo) * rng.random((max(int(samples), 1), n))
    sampled, argmax = attained(qs)
    free = hi > lo
    upper = np.empty(n)
    terms: list[dict] = [{} for _ in range(n)]
    converged = []
    for i in range(n):
        root = (tuple(lo), tuple(hi))
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
            k = int(np.argmax(np.where(free & (bhi > blo), sm, -1.0)))
            if sm[k] <= 0:  # no sensitivity left: the widest side
                k = int(np.argmax(np.where(free, bhi - blo, -1.0)))
            mid = 0.5 * (blo[k] + bhi[k])
            centre = 0.5 * (blo + bhi)
            val, arg = attained(centre[None, :])
            for jj in range(n):
                if val[jj] > sampled[jj]:
                    sampled[jj], argmax[jj] = val[jj], arg[jj]
            left_hi, right_lo = bhi.copy(), blo.copy()
            left_hi[k] = mid
            right_lo[k] = mid
            for child in ((tuple(blo), tuple(left_hi)), (tuple(right_lo), tuple(bhi))):
                heapq.heappush(heap, (-bound_box(child)[0][i], child))
                work += 1
        upper[i] = -heap[0][0]
        terms[i] = bound_box(heap[0][1])[1][i]
    return PerturbationEnclosure(
        upper=tuple(float(u) for u in upper), sampled=tuple(float(s) for s in sampled),
        argmax=tuple({"q": a[0].tolist(), "qd": a[1].tolist(), "qdd": a[2].tolist()} for a in argmax),
        terms=tuple(terms), boxes=len(cache), converged=tuple(converged), seconds=time.perf_counter() - t0,
        rel_tol=float(rel_tol), max_boxes=int(max_boxes))
