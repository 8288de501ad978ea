"""Base (identifiable) inertial parameters of a serial chain.

The regressor ``W(q, qd, qdd)`` of ``tau = W P`` has linearly dependent columns:
some standard parameters never act on the joints, others act only in fixed
combinations.  The base parameters ``beta = K P`` are the smallest set with
``tau = W_b beta``, ``W_b`` a subset of the columns of ``W`` (Gautier & Khalil,
"Direct calculation of minimum set of inertial parameters of serial robots",
IEEE T-RA 6(3), 1990; Mayeda, Yoshida & Osuka, IEEE T-RA 6(3), 1990).

The exactness argument -- a finite *unisolvent* set of states on which ``W``
is determined, so that a relation holding there holds everywhere -- and the
verification on it live in :mod:`designkit.models.unisolvent`.

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
The unisolvence argument depends on the degree bounds stated in
:mod:`designkit.models.unisolvent`, which the tests check on the zoo robots by
a discrete Fourier transform along each joint.
A related exact method is Wensing, Niemeyer & Slotine, "A geometric
characterization of observability in inertial parameter identification" (arXiv:1711.03896).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi
import numpy as np
import scipy.linalg

from designkit.errors import ModelError
from designkit.models.unisolvent import evaluation_states, regressor_rows, relation_residuals

__all__ = ["BaseParameters", "Certificate", "base_parameters", "evaluation_states"]


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



def _stacked_r(reg: casadi.Function, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
    """R factor of the stacked evaluations ``Y`` (all rows of W at all states), by chunks."""
    p = reg.size2_out(0)
    r = np.zeros((0, p))
    for rows in regressor_rows(reg, q, qd, qdd):
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
        residual, zero_level = relation_residuals(reg, full, kept=found.kept, dependent=found.dependent,
                                                  relation=found.relation, zero=found.zero)
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
