"""Stability of a decentralized design's joint loops at every configuration of a workspace box: ``workspace``.

A decentralized PID (:mod:`designkit.families.decentralized_pid`) designs joint ``i``'s loop on
its simplified link at one configuration ``q*``: ``Km_i = 1/f_i`` ((rad/s)/(N*m), or (m/s)/N for
a prismatic joint) and ``tau_i = D_ii(q*)/f_i`` (s).  As the arm moves, ``D_ii(q)`` and with it
``tau_i`` change; this check certifies each joint's loop for **every** configuration ``q`` of the
box ``controller.workspace`` (``low <= q <= high``, rad or m per joint), not only at ``q*``.

Stability conditions (derived here, pinned by a SymPy test).  At a frozen ``q`` the joint loop is
``x1' = x2``, ``x2' = -x2/tau + (Km/tau)(u + xi)``, ``x3' = x1 - xD`` with
``u = -K1 x1 - K2 x2 - K3 x3 + (reference terms)``, so its state matrix and characteristic
polynomial are::

    A = [[0, 1, 0], [-Km K1/tau, -(1 + Km K2)/tau, -Km K3/tau], [1, 0, 0]]
    tau det(sI - A) = tau s^3 + (1 + Km K2) s^2 + Km K1 s + Km K3 = a3 s^3 + a2 s^2 + a1 s + a0.

With ``a3 = tau > 0`` the Routh array's first column is ``a3, a2, (a2 a1 - a3 a0)/a2, a0``; all
positive, and ``Km > 0``, gives the conditions

* C1 ``1 + Km K2 > 0``  (``a2 > 0``),
* C2 ``K3 > 0``  (``a0 = Km K3 > 0``),
* C3 ``K1 (1 + Km K2) - tau K3 > 0``  (``(a2 a1 - a3 a0)/Km > 0``; ``a1 = Km K1 > 0`` then follows),

each **affine in (Km, tau)** for fixed gains.  They are read from the joint loop's own
``characteristic.linear_conditions`` (:func:`designkit.synthesis.pid.servo_conditions`), so no
formula is retyped here.  Solved for ``tau`` (C3 with ``K3 > 0``): the loop is stable exactly for
``tau < tau_crit = K1 (1 + Km K2)/K3``, i.e. ``D_ii < D_crit = f_i tau_crit``.

Why the two ends of the range suffice (vertex argument).  ``Km_i`` does not depend on ``q`` and
``tau_i(q) = D_ii(q)/f_i`` takes its values in ``[tau_lo, tau_hi] = [min D_ii, max D_ii]/f_i``,
so the joint's plants ``{(Km_i, tau_i(q)) : q in box}`` lie on the segment
``{Km_i} x [tau_lo, tau_hi]``.  An affine ``g`` on a segment is a convex combination of its end
values, ``g(Km, l tau_lo + (1 - l) tau_hi) = l g(Km, tau_lo) + (1 - l) g(Km, tau_hi)`` for
``0 <= l <= 1``, so ``g > 0`` at both ends implies ``g > 0`` on the whole segment (the same holds
at the four corners of any box of ``(Km, tau)``: a box is the convex hull of its corners,
:func:`box_verdict`).  Conversely both ends are attained, at the configurations ``q_at_min`` and
``q_at_max`` where ``D_ii`` was evaluated, so a condition ``<= 0`` at an end names a configuration of
the box where the loop is not asymptotically stable.

How each end is decided.  Each condition is evaluated in floating point with its size
``|c0| + |c_Km Km| + |c_tau tau|``; it holds (fails) when it is above (below) ``ROUTH_ZERO_REL``
times its size, six orders above the rounding of the sum, and is zero within rounding otherwise
(undecided).  A second, independent route judges the same end: the joint loop's law composed with
the link ODE at ``(Km, tau)``, linearized by CasADi, and its eigenvalues plus the Routh array of
its characteristic polynomial (:class:`designkit.verification.robustness.Sweeper`).  The two must
agree, else the end is undecided.

What is proven and what is not.

* The verdict for the range ``[tau_lo, tau_hi]`` is exact in the sense above.
* **The range itself is not rigorous**: it comes from :func:`designkit.models.link.link_range`,
  ``D_ii`` on a grid of ``samples`` points per outboard joint (``D_ii`` does not depend on joints
  ``1..i``) polished by a bounded quasi-Newton search (L-BFGS-B with the exact CasADi gradient) --
  an inner estimate of the true range, not interval arithmetic; a narrow peak of ``D_ii`` between
  grid points could be missed.  A FAIL never depends on this (its configuration is an evaluated
  point); a PASS holds for the range reported, and the certificate carries ``D_crit`` so that any
  other bound on ``max D_ii`` can be compared with it.
* Frozen configurations: each ``q`` held fixed.  The time variation of ``tau_i`` as the arm moves,
  the intercoupling (off-diagonal inertia, Coriolis, centrifugal and uncompensated gravity
  torques, all in ``xi``) and the plant's parameter uncertainty are not covered here (the
  ``coupling``, ``lyapunov`` and ``robustness`` checks and the simulation address them).
* Velocity limits do not enter: ``Km_i = 1/f_i`` and ``tau_i = D_ii(q)/f_i`` do not depend on the
  joint velocities (the viscous friction ``f_i`` is linear; Coulomb friction and the
  velocity-dependent Coriolis and centrifugal torques are part of ``xi``), so they would bound the
  perturbation, not change the loop's characteristic polynomial.  The spec has no velocity key.

The check's margin is, per joint, ``1 - tau_hi/tau_crit = 1 - max D_ii/D_crit`` (1): the share
of the critical inertia the workspace leaves unused, positive iff the loop is stable over the
whole range (:attr:`JointWorkspace.margin`); overall, the smallest over the joints.  The relative
condition values ``g / (|c0| + |c_Km Km| + |c_tau tau|)`` at both ends are in the certificate too.
The certificate carries the workspace, the method, and per joint the ranges of ``D_ii`` and
``tau_i`` with the configurations where they are attained, ``tau_crit`` and ``D_crit``, the
conditions at both ends, the spectral abscissa there, and the smallest margin with its
configuration; on failure ``evidence`` names the joint, the configuration, the violated condition
and the eigenvalues there.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.synthesis.design import LinearCondition
from designkit.verification.certificate import to_json
from designkit.verification.check import Check
from designkit.verification.suite import CheckRule
from designkit.verification.tolerances import ROUTH_ZERO_REL

__all__ = ["ConditionValue", "JointWorkspace", "VertexVerdict", "box_verdict", "joint_workspace",
           "stable_tau_interval", "workspace_check"]

PARAMETERS = ("Km", "tau")
"""The link parameters the joint loops' conditions may depend on."""

RANGE_METHOD = ("D_ii(q) on a grid of `samples` points per outboard joint (D_ii does not depend on joints 1..i), "
                "the best grid points polished by SciPy L-BFGS-B with the exact CasADi gradient, within the box "
                "(designkit.models.link.link_range): a local search, an inner estimate of the range, not interval "
                "arithmetic")
VERDICT_METHOD = ("Hurwitz conditions of tau s^3 + (1 + Km K2) s^2 + Km K1 s + Km K3, affine in (Km, tau) for fixed "
                  "gains, evaluated at both ends of each joint's tau range (an affine function on a segment is "
                  "positive everywhere iff at both ends); each end re-judged by the eigenvalues and Routh array of "
                  "the CasADi linearization of the joint's law on its link; frozen configurations")


# ----------------------------------------------------------------------------- the vertex argument


@dataclass(frozen=True)
class ConditionValue:
    """One affine condition evaluated at one plant ``(Km, tau)``.

    Parameters
    ----------
    label : str
        The condition in words.
    unit : str
        Unit of ``value`` and ``size``.
    value : float
        ``g = c0 + c_Km Km + c_tau tau``.
    size : float
        ``|c0| + |c_Km Km| + |c_tau tau|``, the scale its rounding is judged against.
    """

    label: str
    unit: str
    value: float
    size: float

    @property
    def relative(self) -> float:
        """``value / size`` (1), in ``[-1, 1]``; 0 when every term vanishes."""
        return self.value / self.size if self.size > 0 else 0.0

    @property
    def status(self) -> int:
        """1 holds, -1 fails, 0 zero within rounding (``|g| <= ROUTH_ZERO_REL size``, ``size > 0``).

        A condition whose terms all vanish is exactly ``0 > 0``: it fails.
        """
        if self.size == 0.0:
            return -1
        if abs(self.value) <= ROUTH_ZERO_REL * self.size:
            return 0
        return 1 if self.value > 0 else -1


@dataclass(frozen=True)
class VertexVerdict:
    """The conditions at one corner ``(Km, tau)`` of a parameter box.

    Parameters
    ----------
    Km : float
        (rad/s)/(N*m) or (m/s)/N.
    tau : float
        s.
    conditions : tuple of ConditionValue
    """

    Km: float
    tau: float
    conditions: tuple[ConditionValue, ...]

    @property
    def passed(self) -> bool | None:
        """True every condition holds, False one fails, None one is zero within rounding."""
        status = [c.status for c in self.conditions]
        if any(s < 0 for s in status):
            return False
        return None if any(s == 0 for s in status) else True

    @property
    def margin(self) -> float:
        """Smallest relative condition value (1)."""
        return min(c.relative for c in self.conditions)

    @property
    def worst(self) -> ConditionValue:
        """The condition with the smallest relative value."""
        return min(self.conditions, key=lambda c: c.relative)


def _evaluate(cond: LinearCondition, Km: float, tau: float) -> ConditionValue:
    unknown = set(cond.coefficients) - set(PARAMETERS)
    if unknown:
        raise ValueError(f"condition {cond.label!r} depends on {sorted(unknown)}, not only on Km and tau")
    terms = [float(cond.constant), float(cond.coefficients.get("Km", 0.0)) * Km,
             float(cond.coefficients.get("tau", 0.0)) * tau]
    return ConditionValue(cond.label, cond.unit, math.fsum(terms), math.fsum(abs(t) for t in terms))


def box_verdict(conditions: Sequence[LinearCondition], Km: tuple[float, float],
                tau: tuple[float, float]) -> tuple[VertexVerdict, ...]:
    """The affine conditions at the corners of the box ``Km x tau`` (module docstring: the corners decide).

    Parameters
    ----------
    conditions : sequence of LinearCondition
        Affine in ``Km`` and ``tau`` only.
    Km : (float, float)
        ``(low, high)``, (rad/s)/(N*m); positive.
    tau : (float, float)
        ``(low, high)``, s; positive.

    Returns
    -------
    tuple of VertexVerdict
        One per distinct corner, ordered ``tau`` high before low and ``Km`` low before high (for
        the servo the largest ``tau`` is the worst corner of C3).  Every condition holds on the
        whole box iff it holds at every corner.

    Raises
    ------
    ValueError
        For an empty or non-positive box, or a condition on another parameter.

    Examples
    --------
    >>> from designkit.synthesis.pid import servo_conditions
    >>> conds = servo_conditions({"K1": 50.0, "K2": 6.75, "K3": 100.0})   # tau_crit = 0.5 (1 + 2 * 6.75) = 7.25 s
    >>> [v.passed for v in box_verdict(conds, (2.0, 2.0), (0.5, 7.0))]
    [True, True]
    >>> [v.passed for v in box_verdict(conds, (2.0, 2.0), (0.5, 7.5))]
    [False, True]
    """
    (k_lo, k_hi), (t_lo, t_hi) = (float(v) for v in Km), (float(v) for v in tau)
    if not (0 < k_lo <= k_hi and 0 < t_lo <= t_hi and math.isfinite(k_hi) and math.isfinite(t_hi)):
        raise ValueError(f"need 0 < Km_low <= Km_high and 0 < tau_low <= tau_high, got Km {Km}, tau {tau}")
    corners = dict.fromkeys((k, t) for t in (t_hi, t_lo) for k in (k_lo, k_hi))
    return tuple(VertexVerdict(k, t, tuple(_evaluate(c, k, t) for c in conditions)) for k, t in corners)


def stable_tau_interval(conditions: Sequence[LinearCondition], Km: float) -> tuple[float, float]:
    """The open interval of ``tau`` (s) where every condition holds at ``Km`` (empty: ``low >= high``).

    Each condition ``c0 + c_Km Km + c_tau tau > 0`` is a half-line in ``tau``; for the servo only C3
    depends on ``tau`` and the interval is ``(0, tau_crit)`` with ``tau_crit = K1 (1 + Km K2)/K3``.

    Examples
    --------
    >>> from designkit.synthesis.pid import servo_conditions
    >>> stable_tau_interval(servo_conditions({"K1": 50.0, "K2": 6.75, "K3": 100.0}), 2.0)
    (0.0, 7.25)
    """
    low, high = 0.0, math.inf
    for cond in conditions:
        rest = float(cond.constant) + float(cond.coefficients.get("Km", 0.0)) * Km
        slope = float(cond.coefficients.get("tau", 0.0))
        if slope > 0:
            low = max(low, -rest / slope)
        elif slope < 0:
            high = min(high, rest / -slope)
        elif rest <= 0:
            return (0.0, 0.0)
    return (low, high)


# ----------------------------------------------------------------------------- one joint over the box


@dataclass(frozen=True, eq=False)
class JointWorkspace:
    """Joint ``joint``'s loop over the workspace box.

    Parameters
    ----------
    joint : int
        1-based joint number.
    name : str
        The loop's name (``"joint1"``).
    prismatic : bool
        Units: m, kg, (m/s)/N instead of rad, kg*m^2, (rad/s)/(N*m).
    damping : float
        ``f_i`` (N*m*s/rad or N*s/m).
    Km : float
        ``1/f_i``.
    inertia : (float, float)
        Smallest and largest ``D_ii`` found over the box (kg*m^2 or kg).
    tau : (float, float)
        ``inertia / f_i`` (s).
    configurations : (ndarray, ndarray)
        Where ``D_ii`` is smallest and largest (rad or m per joint); read-only.
    nominal_tau : float
        ``tau_i(q*)`` the gains were designed for (s).
    stable_tau : (float, float)
        Open interval of ``tau`` (s) where the loop is Hurwitz (:func:`stable_tau_interval`).
    ends : (VertexVerdict, VertexVerdict)
        The conditions at ``tau`` low and high.
    abscissa : (float, float)
        ``max Re(eig A)`` (1/s) of the linearized joint loop at ``tau`` low and high (second route).
    eigenvalues : (ndarray, ndarray)
        The eigenvalues there (1/s); read-only.
    route_status : (int, int)
        Second route's verdict at both ends: 1 stable, 0 undecided, -1 unstable.
    """

    joint: int
    name: str
    prismatic: bool
    damping: float
    Km: float
    inertia: tuple[float, float]
    tau: tuple[float, float]
    configurations: tuple[np.ndarray, np.ndarray]
    nominal_tau: float
    stable_tau: tuple[float, float]
    ends: tuple[VertexVerdict, VertexVerdict]
    abscissa: tuple[float, float]
    eigenvalues: tuple[np.ndarray, np.ndarray]
    route_status: tuple[int, int]

    def __post_init__(self) -> None:
        for name, dtype in (("configurations", float), ("eigenvalues", complex)):
            frozen = []
            for value in getattr(self, name):
                a = np.array(value, dtype=dtype)
                a.setflags(write=False)
                frozen.append(a)
            object.__setattr__(self, name, tuple(frozen))

    def end_passed(self, k: int) -> bool | None:
        """Verdict at end ``k`` (0 low, 1 high ``tau``): both routes must agree, else None."""
        cond, route = self.ends[k].passed, self.route_status[k]
        if cond is True and route == 1:
            return True
        if cond is False and route == -1:
            return False
        return None

    @property
    def passed(self) -> bool | None:
        """False when an end fails, None when one is undecided, True otherwise."""
        verdicts = [self.end_passed(k) for k in (0, 1)]
        if False in verdicts:
            return False
        return None if None in verdicts else True

    def _end_margins(self) -> tuple[float, float]:
        low, high = self.stable_tau
        if not low < high:  # a condition that does not depend on tau fails: unstable everywhere
            return self.ends[0].margin, self.ends[1].margin
        at_low = 1.0 - low / self.tau[0]
        at_high = 1.0 - self.tau[1] / high if math.isfinite(high) else 1.0
        return at_low, at_high

    @property
    def worst(self) -> int:
        """The end (0 low, 1 high ``tau``) with the smallest margin; the high end on a tie."""
        at_low, at_high = self._end_margins()
        return 0 if at_low < at_high else 1

    @property
    def margin(self) -> float:
        """How far the range stays from the stability limits of ``tau`` (1): ``1 - tau_hi/tau_crit``.

        With the stable interval ``(tau_a, tau_b)`` of :func:`stable_tau_interval`, the smaller of
        ``1 - tau_hi/tau_b`` and ``1 - tau_a/tau_lo`` (each 1 when that side is unbounded): the share of
        the critical ``D_ii`` still unused, positive iff the whole range is stable.  When the interval
        is empty (a condition independent of ``tau`` fails) it is the smallest relative condition value.
        """
        return min(self._end_margins())

    @property
    def constant(self) -> bool:
        """``D_ii`` the same over the whole box (to 1e-12 relative)."""
        return self.inertia[1] - self.inertia[0] <= 1e-12 * abs(self.inertia[1])

    def units(self) -> tuple[str, str, str]:
        """Units of the inertia, of ``Km`` and of the damping."""
        if self.prismatic:
            return "kg", "(m/s)/N", "N*s/m"
        return "kg*m^2", "(rad/s)/(N*m)", "N*m*s/rad"

    def to_dict(self) -> dict[str, Any]:
        """The certificate row (JSON-serialisable): ranges, where they are attained, limits, margin."""
        inertia_unit, km_unit, _ = self.units()
        return to_json({
            "joint": self.joint,
            "Km": self.Km,
            "Km_unit": km_unit,
            "inertia_range": list(self.inertia),
            "inertia_unit": inertia_unit,
            "q_at_min": self.configurations[0],
            "q_at_max": self.configurations[1],
            "tau_range_s": list(self.tau),
            "tau_nominal_s": self.nominal_tau,
            "tau_stable_s": list(self.stable_tau),
            "inertia_critical": self.stable_tau[1] * self.damping,
            "smallest_margin": self.margin,
            "q_at_smallest_margin": self.configurations[self.worst],
            "passed": self.passed,
        })

    def end_rows(self) -> list[dict[str, Any]]:
        """One certificate row per end of the range: conditions, second route, verdict."""
        rows = []
        for k, end in enumerate(self.ends):
            rows.append(to_json({
                "joint": self.joint,
                "end": "tau min" if k == 0 else "tau max",
                "configuration": self.configurations[k],
                "inertia": self.inertia[k],
                "tau_s": end.tau,
                "conditions": {c.label: c.value for c in end.conditions},
                "relative_condition": end.margin,
                "spectral_abscissa": self.abscissa[k],
                "routes": {"conditions": end.passed, "linearization": {1: True, 0: None, -1: False}[
                    self.route_status[k]]},
                "passed": self.end_passed(k),
            }))
        return rows


def joint_workspace(design: Any, i: int, low: Sequence[float], high: Sequence[float], *,
                    samples: int = 7) -> JointWorkspace:
    """Joint ``i`` (0-based) of a decentralized ``design`` over the box ``low <= q <= high``.

    Parameters
    ----------
    design : Design
        With per-joint ``loops`` on simplified links and a robot ``plant``.
    i : int
        0-based joint index.
    low, high : sequence of float
        The box (rad or m per joint).
    samples : int
        Grid points per outboard joint for the ``D_ii`` range.

    Returns
    -------
    JointWorkspace
    """
    from designkit.models.link import link_range
    from designkit.verification.robustness import Sweeper

    plant, loop = design.plant, design.loops[i]
    if loop.characteristic is None or loop.characteristic.linear_conditions is None:
        raise ValueError(f"{design.loop_names[i]}: its loop exposes no affine stability conditions")
    rng = link_range(plant.robot, i, low, high, samples=samples, p=plant.model_parameters())
    conditions = loop.characteristic.linear_conditions(loop.gains)
    Km = float(rng.Km_min)
    ends = box_verdict(conditions, (Km, Km), (rng.tau_min, rng.tau_max))
    ends = (ends[-1], ends[0])  # (tau low, tau high); one corner when the range is a point
    sweep = Sweeper(loop, PARAMETERS).sweep([[Km, rng.tau_min], [Km, rng.tau_max]])
    eig = np.linalg.eigvals(np.nan_to_num(sweep.A))
    return JointWorkspace(
        joint=i + 1,
        name=design.loop_names[i],
        prismatic=plant.robot.description.links[i].joint == "prismatic",
        damping=1.0 / Km,
        Km=Km,
        inertia=(float(rng.inertia_min), float(rng.inertia_max)),
        tau=(float(rng.tau_min), float(rng.tau_max)),
        configurations=(rng.q_at_min, rng.q_at_max),
        nominal_tau=float(loop.plant.tau),
        stable_tau=stable_tau_interval(conditions, Km),
        ends=ends,
        abscissa=(float(sweep.abscissa[0]), float(sweep.abscissa[1])),
        eigenvalues=(eig[0], eig[1]),
        route_status=(int(sweep.status[0]), int(sweep.status[1])),
    )


# ----------------------------------------------------------------------------- the check


def _vector(q: np.ndarray) -> str:
    return "[" + ", ".join(f"{v:.4g}" for v in q) + "]"


def _joint_detail(j: JointWorkspace) -> str:
    inertia_unit = j.units()[0]
    k = j.worst
    where = "every configuration (D_ii constant over the box)" if j.constant else f"q = {_vector(j.configurations[k])}"
    return (f"joint {j.joint}: tau in [{j.tau[0]:.4g}, {j.tau[1]:.4g}] s (D_{j.joint}{j.joint} in "
            f"[{j.inertia[0]:.4g}, {j.inertia[1]:.4g}] {inertia_unit}; stable for D_{j.joint}{j.joint} < "
            f"{j.stable_tau[1] * j.damping:.4g} {inertia_unit}), smallest margin {j.margin:.3g} at {where}")


def _failure(j: JointWorkspace) -> tuple[str, dict[str, Any]]:
    k = next(k for k in (1, 0) if j.end_passed(k) is False)
    end, inertia_unit = j.ends[k], j.units()[0]
    cond = next(c for c in end.conditions if c.status < 0)
    unit = f" {cond.unit}" if cond.unit else ""
    low, high = j.stable_tau
    where = (f"stable only for tau in ({low:.4g}, {high:.4g}) s" if low < high
             else "unstable for every tau: a condition independent of tau fails")
    detail = (f"joint {j.joint} unstable at q = {_vector(j.configurations[k])} (D_{j.joint}{j.joint} = "
              f"{j.inertia[k]:.4g} {inertia_unit}, tau = {end.tau:.4g} s; {where}, designed for "
              f"{j.nominal_tau:.4g} s): "
              f"{cond.label.removesuffix(' > 0')} = {cond.value:.4g}{unit} <= 0, max Re(eig) = "
              f"{j.abscissa[k]:+.4g} 1/s")
    evidence = to_json({
        "joint": j.joint,
        "configuration": j.configurations[k],
        "inertia": j.inertia[k],
        "tau_s": end.tau,
        "Km": end.Km,
        "condition": cond.label,
        "value": cond.value,
        "spectral_abscissa": j.abscissa[k],
        "eigenvalues": j.eigenvalues[k],
    })
    return detail, evidence


def workspace_check(design: Any, workspace: Mapping[str, Any] | None = None) -> Check:
    """Check ``workspace``: every joint loop of ``design`` Hurwitz at every configuration of the box.

    Parameters
    ----------
    design : Design
        A decentralized design (per-joint ``loops`` on simplified links, a robot ``plant``).
    workspace : Mapping, optional
        ``{"low": [...], "high": [...], "samples": int}`` (rad or m per joint); default
        ``design.extra["workspace"]`` (set by the family from ``controller.workspace``).

    Returns
    -------
    Check
        True: every joint certified over its ``D_ii`` range (see the module docstring for what that
        range is).  False: a joint's loop is unstable at a configuration of the box, named in the
        detail and in ``certificate["evidence"]``.  None: a condition zero within rounding, or the two
        routes disagree.  ``margin``: smallest relative condition value over the joints (1).
    """
    ws = dict(design.extra["workspace"] if workspace is None else workspace)
    low, high = (np.asarray(ws[k], dtype=float) for k in ("low", "high"))
    samples = int(ws.get("samples", 7))
    joints = [joint_workspace(design, i, low, high, samples=samples) for i in range(len(design.loops))]
    worst = min(joints, key=lambda j: j.margin)
    cert: dict[str, Any] = {
        "method": VERDICT_METHOD,
        "range_method": RANGE_METHOD,
        "rigorous_range": False,
        "workspace": to_json({**ws, "low": low, "high": high, "samples": samples}),
        "nominal_configuration": to_json(design.extra.get("configuration")),
        "joints": [j.to_dict() for j in joints],
        "ends": [row for j in joints for row in j.end_rows()],
        "smallest_margin": {"joint": worst.joint, "margin": worst.margin,
                            "configuration": to_json(worst.configurations[worst.worst])},
    }
    data = {"joints": [{"name": j.name, "joint": j.joint, "tau": j.tau, "tau_nominal": j.nominal_tau,
                        "tau_stable": j.stable_tau} for j in joints]}
    target = "each joint's PID loop Hurwitz at every configuration of the workspace box"
    unit = "1 (1 - D_ii/D_crit)"
    failed = [j for j in joints if j.passed is False]
    if failed:
        detail, evidence = _failure(min(failed, key=lambda j: j.margin))
        cert["evidence"] = evidence
        return Check("workspace", False, target, worst.margin, worst.margin, unit, f"fails: {detail}", cert,
                     data=data)
    undecided = [j for j in joints if j.passed is None]
    if undecided:
        j = undecided[0]
        detail = (f"undecided: joint {j.joint}: a stability condition is zero within rounding at an end of its range, "
                  f"or the conditions and the linearization disagree ({_joint_detail(j)})")
        return Check("workspace", None, target, worst.margin, worst.margin, unit, detail, cert, data=data)
    detail = (f"{len(joints)} joint loops Hurwitz for every configuration of the box (frozen q; D_ii range by grid + "
              f"local search, not interval arithmetic); worst {_joint_detail(worst)}")
    return Check("workspace", True, target, worst.margin, worst.margin, unit, detail, cert, data=data)


def _figure(result: Any, check: Check) -> Any:
    from designkit.families.decentralized_pid.figures import workspace_figure

    return workspace_figure(result, check)


def _run(design: Any, ctx: Any) -> tuple[Check, ...]:
    return (workspace_check(design),)


RULE = CheckRule(
    name="workspace", order=70, linear=True,
    applies=lambda d, c: bool(d.loops) and d.extra.get("workspace") is not None,
    run=_run, label="Joint loops stable over the workspace", figures=(_figure,),
)
"""The decentralized PID's own check: every joint loop for every configuration of ``controller.workspace``."""
