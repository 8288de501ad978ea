"""Base (identifiable) inertial parameters of a serial chain.

The regressor ``W(q, qd, qdd)`` of ``tau = W P`` has linearly dependent columns:
some standard parameters never act on the joints, others act only in fixed
combinations.  The base parameters ``beta = K P`` are the smallest set with
``tau = W_b beta``, ``W_b`` a subset of the columns of ``W`` (Gautier & Khalil,
"Direct calculation of minimum set of inertial parameters of serial robots",
IEEE T-RA 6(3), 1990; Mayeda, Yoshida & Osuka, IEEE T-RA 6(3), 1990).

Method: an evaluation set on which ``W`` is determined exactly
---------------------------------------------------------------
A constant vector ``r`` is a column relation when ``W(x) r = 0`` for *every*
state ``x``.  Random samples cannot prove that; instead we use the structure of
the model to pick a finite set of states on which any function of the
regressor's class that vanishes there vanishes everywhere (a *unisolvent*
set).  The class follows from the Lagrangian (see the notes' ``D_ij``,
``D_ijk``, ``D_i``):

* ``W = G(q) + A(q) qdd + B(q)[qd, qd] + Fv(qd) + Fc(sign qd)``: affine in
  ``qdd``, a quadratic form in ``qd``, plus the per-joint viscous and Coulomb
  friction columns of the model.
* Link angular and origin velocities, written in the link's own frame, have
  degree at most 1 in ``cos q_j, sin q_j`` of every revolute joint (and degree
  1 in every prismatic ``q_j``), so the kinetic part is a trigonometric
  polynomial of degree <= 2 in each revolute ``q_j`` (polynomial of degree <= 2
  in a prismatic one) and the gravity part ``G`` has degree <= 1.  The kinetic
  energy does not change when the whole chain moves about (along) joint 1, so
  ``A`` and ``B`` do not depend on ``q_1``.

The evaluation set is therefore (i) ``W(q, 0, 0)`` on the tensor grid of 3
equispaced angles per revolute joint (2 values per prismatic joint), which is
unisolvent for ``G``, and (ii) at ``q_1 = 0`` and the tensor grid of 5
equispaced angles per revolute joint ``2..n`` (3 values per prismatic joint):
``(qd, qdd) = (0, e_k)``, ``(+-e_a, 0)``, ``(2 e_a, 0)``, ``(e_a + e_b, 0)``,
which is unisolvent for the ``qd``/``qdd`` part (``1 + 3n + n(n-1)/2 + n``
coefficients, as many points).  On an equispaced grid the discrete Fourier
transform is exact for these degrees, so by Parseval the 2-norm of the grid
values bounds ``sup_q |W(q) r|``: the null space of the stacked evaluation
matrix ``Y`` *is* the null space of ``W`` as a function, and the residual of a
relation on ``Y`` bounds its residual at every state.

Discovery, then verification.  The pivots and relations are first computed
from 500 pseudo-random states of a seeded generator (QR of the stacked
regressor, floating point): columns are scaled to unit norm and a column is
kept (a *pivot*) when its distance to the span of the kept columns before it
exceeds ``tol`` -- the reduced row echelon form for the column order of
:func:`_preference_order` (links base to tip, within a link ``Izz, Ixx, Ixy,
Ixz, Iyz, mcx, mcy, Iyy, mcz, m``; in the modified DH convention this regroups
``M_j, MZ_j, YY_j`` of each link into link ``j-1``, as the Gautier--Khalil rules
do).  Independence found on any states holds everywhere; the relations found
may only be too many, so each one is then *verified* on the unisolvent set
(about 1.2e5 states for a 6R arm).  If one fails, discovery is repeated on the
unisolvent set itself.  Coefficients within 1e-12 of an integer are snapped to it.

What stays numerical, and is reported in :class:`Certificate`: the rank
decision (the gap between the smallest kept and the largest rejected scaled
pivot, typically 0.5 against 1e-15) and the relation coefficients
(least-squares values; their relative residual on the unisolvent set is about
1e-15).  The coefficients are not recognised as closed-form expressions of the
DH constants; the regrouping strings print them as numbers, and the tests check
that e.g. the PUMA's ``mcx2R`` regroups ``m3..m6`` with coefficient ``a2``.
The unisolvence argument depends on the degree bounds above, which the tests
check on the zoo robots by a discrete Fourier transform along each joint.
A related exact method is Wensing, Niemeyer & Slotine, "A geometric
characterization of observability in inertial parameter identification" (arXiv:1711.03896).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import casadi
import numpy as np
import scipy.linalg

from designkit.errors import ModelError

__all__ = ["BaseParameters", "Certificate", "base_parameters", "evaluation_states"]

_CHUNK = 8192  # states per mapped evaluation


@dataclass(frozen=True)
class Certificate:
    """Numerical evidence behind a base-parameter set.

    Parameters
    ----------
    n_states : int
        Number of states in the unisolvent evaluation set (verification).
    discovery_states : int
        Number of states the pivots and relations were computed from.
    tolerance : float
        Scaled pivot threshold used for the rank decision.
    smallest_kept : float
        Smallest scaled pivot of a kept column (distance to the span of the earlier kept
        columns, unit-norm columns, discovery states).
    largest_rejected : float
        Largest scaled pivot of a rejected, non-zero column; 0 when there is none.
    relation_residual : float
        Largest ``||Y_j - Y_kept c_j|| / ||Y_j||`` over regrouped columns ``j`` on the
        unisolvent set, which bounds the relation's residual at every state.
    zero_residual : float
        Largest norm of an "identically zero" column on the unisolvent set, relative to the largest column.
    """

    n_states: int
    discovery_states: int
    tolerance: float
    smallest_kept: float
    largest_rejected: float
    relation_residual: float
    zero_residual: float

    @property
    def gap(self) -> float:
        """``smallest_kept / largest_rejected`` (inf when no column is near the threshold)."""
        return self.smallest_kept / self.largest_rejected if self.largest_rejected > 0 else float("inf")


@dataclass(frozen=True)
class BaseParameters:
    """Base inertial parameters of a chain.

    Parameters
    ----------
    names : tuple of str
        Names of the base parameters: the kept standard parameter's name, with a
        trailing ``R`` when other parameters are regrouped into it (``"Izz1R"``).
    beta : numpy.ndarray
        Values of the base parameters for the robot, ``K @ P`` (SI units of each parameter).
    K : numpy.ndarray
        ``b x p`` map from the standard parameters ``P`` to ``beta``.
    W_base : casadi.Function
        ``"regressor_base"``: ``["q", "qd", "qdd"] -> ["Wb"]`` (``n x b``) with ``tau = Wb beta``.
    independent_columns : tuple of int
        Columns of the full regressor kept in ``W_base``, in order.
    zero_columns : tuple of int
        Columns of the full regressor that vanish identically (parameters with no effect).
    parameter_names : tuple of str
        Names of the standard parameters (columns of the regressor).
    regrouping : tuple of str
        One line per base parameter, e.g. ``"Izz1R = Izz1 + Iyy2 + 0.186447*m3"``.
    certificate : Certificate
        Rank gap and relation residual on the unisolvent evaluation set.
    """

    names: tuple[str, ...]
    beta: np.ndarray
    K: np.ndarray
    W_base: casadi.Function
    independent_columns: tuple[int, ...]
    zero_columns: tuple[int, ...]
    parameter_names: tuple[str, ...]
    regrouping: tuple[str, ...]
    certificate: Certificate

    @property
    def E(self) -> np.ndarray:
        """Alias of :attr:`K` (Gautier--Khalil write ``beta = E P``)."""
        return self.K

    @property
    def count(self) -> int:
        """Number of base parameters."""
        return len(self.names)


def _grid(joints: tuple[str, ...], revolute_points: int, prismatic_points: int) -> np.ndarray:
    axes = []
    for joint in joints:
        if joint == "revolute":
            axes.append(0.3 + 2.0 * np.pi * np.arange(revolute_points) / revolute_points)
        else:
            axes.append(np.linspace(-0.5, 0.5, prismatic_points))
    if not axes:
        return np.zeros((1, 0))
    return np.array(list(itertools.product(*axes)), dtype=float).reshape(-1, len(joints))


def evaluation_states(joints: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The unisolvent evaluation set for a chain's regressor (see the module docstring).

    Parameters
    ----------
    joints : tuple of {"revolute", "prismatic"}
        Joint types, base to tip.

    Returns
    -------
    (numpy.ndarray, numpy.ndarray, numpy.ndarray)
        ``q``, ``qd``, ``qdd``, each ``N x n`` (rad or m, per second, per second squared).
    """
    n = len(joints)
    eye = np.eye(n)
    # Gravity part: degree 1 in every joint, all joints.
    q_gravity = _grid(joints, 3, 2)
    blocks = [(q_gravity, np.zeros_like(q_gravity), np.zeros_like(q_gravity))]
    # Velocity/acceleration part: degree 2, independent of q_1.
    rest = _grid(joints[1:], 5, 3)
    q_kin = np.hstack([np.zeros((rest.shape[0], 1)), rest]) if n else rest
    rates: list[tuple[np.ndarray, np.ndarray]] = []
    for k in range(n):
        rates.append((np.zeros(n), eye[k]))
    for a in range(n):
        rates += [(eye[a], np.zeros(n)), (-eye[a], np.zeros(n)), (2.0 * eye[a], np.zeros(n))]
    for a, b in itertools.combinations(range(n), 2):
        rates.append((eye[a] + eye[b], np.zeros(n)))
    for qd, qdd in rates:
        blocks.append((q_kin, np.tile(qd, (q_kin.shape[0], 1)), np.tile(qdd, (q_kin.shape[0], 1))))
    return tuple(np.vstack([blk[i] for blk in blocks]) for i in range(3))  # type: ignore[return-value]


def _sx_regressor(robot: object) -> tuple[casadi.SX, casadi.SX, casadi.SX, casadi.SX, casadi.Function]:
    try:
        reg = robot.functions["regressor"]  # type: ignore[attr-defined]
    except (AttributeError, KeyError):
        raise ModelError("robot has no 'regressor' function") from None
    if not reg.is_a("SXFunction"):
        reg = reg.expand()
    n = reg.size1_in(0)
    q, qd, qdd = (casadi.SX.sym(name, n) for name in ("q", "qd", "qdd"))
    return q, qd, qdd, reg(q, qd, qdd), reg


def _evaluate(mapped: casadi.Function, pattern: casadi.Sparsity, q: np.ndarray, qd: np.ndarray,
              qdd: np.ndarray) -> np.ndarray:
    """Dense ``W`` at ``N`` states, shape ``(N, n, p)``, through a zero-copy ``FunctionBuffer``.

    ``mapped`` is the regressor mapped over ``N`` states and ``pattern`` the sparsity of one ``W``.
    """
    count = q.shape[0]
    buffer, run = mapped.buffer()
    inputs = [np.ascontiguousarray(x.T).ravel(order="F") for x in (q, qd, qdd)]
    for index, array in enumerate(inputs):
        buffer.set_arg(index, memoryview(array))
    nonzeros = np.zeros(mapped.nnz_out(0))
    buffer.set_res(0, memoryview(nonzeros))
    run()
    if buffer.ret() != 0:
        raise ModelError(f"evaluation of {mapped.name()!r} failed (return code {buffer.ret()})")
    flat = np.array(pattern.row()) + pattern.size1() * np.array(pattern.get_col())  # column-major index
    dense = np.zeros((count, pattern.size2() * pattern.size1()))
    dense[:, flat] = nonzeros.reshape(count, -1)
    return dense.reshape(count, pattern.size2(), pattern.size1()).transpose(0, 2, 1)


def _stacked_r(reg: casadi.Function, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
    """R factor of the stacked evaluations ``Y`` (all rows of W at all states), by chunks."""
    p = reg.size2_out(0)
    pattern = reg.sparsity_out(0)
    maps: dict[int, casadi.Function] = {}
    r = np.zeros((0, p))
    for start in range(0, q.shape[0], _CHUNK):
        stop = min(start + _CHUNK, q.shape[0])
        if stop - start not in maps:
            maps[stop - start] = reg.map(stop - start)
        rows = _evaluate(maps[stop - start], pattern, q[start:stop], qd[start:stop], qdd[start:stop]).reshape(-1, p)
        stacked = np.vstack([r, rows])
        r = scipy.linalg.qr(stacked, mode="r", overwrite_a=True, check_finite=False)[0][:p]
    return r


def _preference_order(p: int, n: int) -> list[int]:
    """Columns in the order the reduced row echelon form keeps them.

    Links from base to tip; within a link ``Izz, Ixx, Ixy, Ixz, Iyz, mcx, mcy, Iyy, mcz, m``
    (the regressor's own order is ``m, mcx, mcy, mcz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz``);
    extra columns (motor inertia, friction) last.  A column is rejected when it is a
    combination of columns before it, so in the modified DH convention ``Iyy_j``,
    ``mcz_j`` and ``m_j`` are the ones regrouped, as in Gautier--Khalil.
    """
    within = (9, 4, 5, 6, 8, 1, 2, 7, 3, 0)
    links = [10 * i + k for i in range(min(n, p // 10)) for k in within]
    return links + [j for j in range(p) if j not in set(links)]


def _format_relation(name: str, kept: str, terms: list[tuple[float, str]]) -> str:
    out = f"{name} = {kept}"
    for coef, other in terms:
        sign = "-" if coef < 0 else "+"
        mag = abs(coef)
        out += f" {sign} {other}" if np.isclose(mag, 1.0, rtol=1e-12, atol=0) else f" {sign} {mag:.6g}*{other}"
    return out


def _sample_states(n: int, count: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Deterministic pseudo-random states (seed 0) for the discovery step."""
    rng = np.random.default_rng(0)
    return rng.uniform(-np.pi, np.pi, (count, n)), rng.uniform(-2, 2, (count, n)), rng.uniform(-2, 2, (count, n))


@dataclass(frozen=True)
class _Discovery:
    zero: np.ndarray  # bool mask of identically zero columns
    kept: list[int]  # pivot columns, ascending
    dependent: list[int]  # regrouped columns, in preference order
    pivots: np.ndarray  # scaled pivot of every column
    relation: np.ndarray  # (len(kept), p): Y_j = Y[:, kept] @ relation[:, j] for dependent j


def _discover(r: np.ndarray, order: list[int], tol: float, zero_tol: float) -> _Discovery:
    """Pivots and relations from the R factor of some stacked evaluations."""
    p = r.shape[1]
    norms = np.linalg.norm(r, axis=0)
    zero = norms <= zero_tol * max(norms.max(initial=0.0), 1e-300)
    scaled = np.where(zero, 0.0, r / np.where(zero, 1.0, norms))
    kept: list[int] = []
    pivots = np.zeros(p)
    for j in [k for k in order if not zero[k]]:
        basis = scaled[:, kept]
        coef = np.linalg.lstsq(basis, scaled[:, j], rcond=None)[0] if kept else np.zeros(0)
        pivots[j] = np.linalg.norm(scaled[:, j] - basis @ coef)
        if pivots[j] > tol:
            kept.append(int(j))
    dependent = [j for j in order if not zero[j] and j not in kept]
    kept.sort()
    relation = np.zeros((len(kept), p))
    for j in dependent:
        coef = np.linalg.lstsq(scaled[:, kept], scaled[:, j], rcond=None)[0] * norms[j] / norms[kept]
        coef[np.abs(coef) < 1e-13 * np.abs(coef).max()] = 0.0
        integers = np.round(coef)
        snap = np.abs(coef - integers) <= 1e-12 * np.maximum(1.0, np.abs(coef))
        coef[snap] = integers[snap]  # +-1 regroupings are exact
        relation[:, j] = coef
    return _Discovery(zero, kept, dependent, pivots, relation)


def _verify(reg: casadi.Function, states: tuple[np.ndarray, ...], found: _Discovery) -> tuple[float, float]:
    """Relative residuals of the relations and of the zero columns on the unisolvent set."""
    p = reg.size2_out(0)
    pattern = reg.sparsity_out(0)
    maps: dict[int, casadi.Function] = {}
    column_sq = np.zeros(p)
    residual_sq = np.zeros(len(found.dependent))
    coefficients = found.relation[:, found.dependent]
    for start in range(0, states[0].shape[0], _CHUNK):
        stop = min(start + _CHUNK, states[0].shape[0])
        if stop - start not in maps:
            maps[stop - start] = reg.map(stop - start)
        Y = _evaluate(maps[stop - start], pattern, *(x[start:stop] for x in states)).reshape(-1, p)
        column_sq += np.einsum("ij,ij->j", Y, Y)
        if found.dependent:
            R = Y[:, found.dependent] - Y[:, found.kept] @ coefficients
            residual_sq += np.einsum("ij,ij->j", R, R)
    norms = np.sqrt(column_sq)
    largest = max(norms.max(initial=0.0), 1e-300)
    relation = np.sqrt(residual_sq) / np.maximum(norms[found.dependent], 1e-300) if found.dependent else [0.0]
    return float(np.max(relation)), float(norms[found.zero].max(initial=0.0) / largest)


def base_parameters(robot: object, *, tol: float = 1e-8, zero_tol: float = 1e-10,
                    verify_tol: float = 1e-9) -> BaseParameters:
    """Base inertial parameters of a robot, with their regrouping and reduced regressor.

    Relations are discovered on 500 pseudo-random states (a seeded generator) and
    then verified on the unisolvent evaluation set of the module docstring; if one
    fails, discovery is repeated on the whole evaluation set.

    Parameters
    ----------
    robot : Robot
        A numeric model with ``functions["regressor"]`` (``q, qd, qdd -> W``, ``n x p``),
        ``parameters`` (``P``, length ``p``), ``parameter_names`` and ``description``.
    tol : float
        Scaled pivot threshold for the rank decision (unit-norm columns).
    zero_tol : float
        A column whose norm is below ``zero_tol`` times the largest column norm is identically zero.
    verify_tol : float
        Largest relative residual of a relation on the unisolvent set.

    Returns
    -------
    BaseParameters
        Names, values ``beta = K P``, ``K``, ``W_base`` and the certificate.

    Raises
    ------
    ModelError
        If the robot is symbolic or has no regressor, the rank decision is ambiguous
        (a scaled pivot within a factor 100 of ``tol``), or a relation fails verification.
    """
    if getattr(robot, "parameters", None) is None:
        raise ModelError("base parameters need a numeric robot (this one is symbolic or has no parameters)")
    q, qd, qdd, W, reg = _sx_regressor(robot)
    names = tuple(robot.parameter_names)  # type: ignore[attr-defined]
    values = np.asarray(robot.parameters, dtype=float).ravel()  # type: ignore[attr-defined]
    p = W.size2()
    if len(names) != p or values.size != p:
        raise ModelError(f"regressor has {p} columns but the robot lists {len(names)} names, {values.size} values")
    joints = tuple(link.joint for link in robot.description.links)  # type: ignore[attr-defined]
    full = evaluation_states(joints)
    order = _preference_order(p, len(joints))
    sample = _sample_states(len(joints), 500)
    for discovery in (sample, full):
        found = _discover(_stacked_r(reg, *discovery), order, tol, zero_tol)
        residual, zero_level = _verify(reg, full, found)
        if residual <= verify_tol and zero_level <= zero_tol:
            break
    else:
        raise ModelError(f"base-parameter relations fail verification: residual {residual:.3g}, "
                         f"zero-column level {zero_level:.3g}")
    kept, dependent = found.kept, found.dependent
    smallest_kept = float(found.pivots[kept].min()) if kept else 0.0
    largest_rejected = float(found.pivots[dependent].max()) if dependent else 0.0
    if smallest_kept < 1e2 * tol or largest_rejected > tol * 1e-2:
        raise ModelError(
            f"ambiguous rank decision: smallest kept pivot {smallest_kept:.3g}, largest rejected "
            f"{largest_rejected:.3g} (tol {tol:.1g})"
        )
    K = found.relation.copy()
    K[np.arange(len(kept)), kept] = 1.0
    base_names = []
    lines = []
    for row, k in enumerate(kept):
        terms = [(float(K[row, j]), names[j]) for j in dependent if K[row, j] != 0.0]
        name = names[k] + ("R" if terms else "")
        base_names.append(name)
        lines.append(_format_relation(name, names[k], terms))
    w_base = casadi.Function("regressor_base", [q, qd, qdd], [W[:, kept]], ["q", "qd", "qdd"], ["Wb"])
    certificate = Certificate(full[0].shape[0], discovery[0].shape[0], tol, smallest_kept, largest_rejected,
                              residual, zero_level)
    return BaseParameters(
        names=tuple(base_names),
        beta=K @ values,
        K=K,
        W_base=w_base,
        independent_columns=tuple(kept),
        zero_columns=tuple(int(j) for j in np.flatnonzero(found.zero)),
        parameter_names=names,
        regrouping=tuple(lines),
        certificate=certificate,
    )
