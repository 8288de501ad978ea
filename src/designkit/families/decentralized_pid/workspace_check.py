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
:func:`box_verdict`), and on any segment containing it.

The range of ``D_ii`` is **proven**: :func:`designkit.models.bounds.model_bound` encloses
``D_ii(q)`` over the box in ball arithmetic with branch and bound (:mod:`designkit.bounds`), so
``D_lo <= D_ii(q) <= D_hi`` holds for every configuration of the box, and gives the witness
configurations ``q_at_min``, ``q_at_max`` where ``D_ii`` comes within ``controller.workspace.tolerance``
(relative) of those bounds.  A PASS evaluates the conditions at the proven ends ``D_lo/f_i``,
``D_hi/f_i`` (so it holds on a segment containing every plant of the box); a FAIL evaluates them at a
witness (an attained configuration of the box where the loop is not asymptotically stable).  When
the critical inertia lies between a witness and its bound, the search goes on until it is decided
or the work limit is reached (then the joint is undecided).

How each end is decided.  Each condition is evaluated in floating point with its size
``|c0| + |c_Km Km| + |c_tau tau|``; it holds (fails) when it is above (below) ``ROUTH_ZERO_REL``
times its size, six orders above the rounding of the sum, and is zero within rounding otherwise
(undecided).  A second, independent route judges the same end: the joint loop's law composed with
the link ODE at ``(Km, tau)``, linearized by CasADi, and its eigenvalues plus the Routh array of
its characteristic polynomial (:class:`designkit.verification.robustness.Sweeper`).  The two must
agree, else the end is undecided.

What is proven and what is not.

* The verdict for every configuration of the box is proven in the sense above (the rounding of the
  range is Arb's, of the conditions ``ROUTH_ZERO_REL``); the grid-and-local-search range of
  :func:`designkit.models.link.link_range` (``samples`` points per outboard joint, polished by
  L-BFGS-B) is reported beside it as a sampled (inner) estimate.
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

from designkit.families.decentralized_pid.data import DecentralizedPidData
from designkit.families.decentralized_pid.workspace_conditions import (
    PARAMETERS,
    ConditionValue,
    VertexVerdict,
    box_verdict,
    stable_tau_interval,
)
from designkit.verification.certificate import to_json
from designkit.verification.check import Check
from designkit.verification.suite import CheckRule

__all__ = ["ConditionValue", "JointWorkspace", "VertexVerdict", "box_verdict", "joint_workspace",
           "stable_tau_interval", "workspace_check"]

RANGE_METHOD = ("D_ii(q) enclosed over the box in Arb ball arithmetic (python-flint) on CasADi's expression graph, "
                "tightened by the mean-value form with the exact gradient and by branch and bound to the relative "
                "tolerance (designkit.models.bounds.model_bound); joints 1..i held, D_ii does not depend on them")
VERDICT_METHOD = ("Hurwitz conditions of tau s^3 + (1 + Km K2) s^2 + Km K1 s + Km K3, affine in (Km, tau) for fixed "
                  "gains, evaluated at both ends of each joint's tau range (an affine function on a segment is "
                  "positive everywhere iff at both ends); each end re-judged by the eigenvalues and Routh array of "
                  "the CasADi linearization of the joint's law on its link; frozen configurations")


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
        Proven bounds of ``D_ii`` over the box (kg*m^2 or kg): every configuration lies between.
    attained : (float, float)
        ``D_ii`` at the witnesses ``configurations`` (within the tolerance of ``inertia``).
    tau : (float, float)
        ``inertia / f_i`` (s).
    configurations : (ndarray, ndarray)
        The witnesses of the smallest and largest ``D_ii`` (rad or m per joint); read-only.
    nominal_tau : float
        ``tau_i(q*)`` the gains were designed for (s).
    stable_tau : (float, float)
        Open interval of ``tau`` (s) where the loop is Hurwitz (:func:`stable_tau_interval`).
    ends, attained_ends : (VertexVerdict, VertexVerdict)
        The conditions at ``tau`` low and high: at the proven bounds, and at the witnesses.
    abscissa, attained_abscissa : (float, float)
        ``max Re(eig A)`` (1/s) of the linearized joint loop there (second route).
    eigenvalues, attained_eigenvalues : (ndarray, ndarray)
        The eigenvalues there (1/s); read-only.
    route_status, attained_status : (int, int)
        Second route's verdict there: 1 stable, 0 undecided, -1 unstable.
    boxes : int
        Boxes the enclosure evaluated.
    converged : bool
        The enclosure reached its tolerance (or decided the critical inertia) within the work limit.
    sampled : (float, float)
        The grid-and-local-search range of ``D_ii`` (an inner estimate, for comparison).
    """

    joint: int
    name: str
    prismatic: bool
    damping: float
    Km: float
    inertia: tuple[float, float]
    attained: tuple[float, float]
    tau: tuple[float, float]
    configurations: tuple[np.ndarray, np.ndarray]
    nominal_tau: float
    stable_tau: tuple[float, float]
    ends: tuple[VertexVerdict, VertexVerdict]
    attained_ends: tuple[VertexVerdict, VertexVerdict]
    abscissa: tuple[float, float]
    attained_abscissa: tuple[float, float]
    eigenvalues: tuple[np.ndarray, np.ndarray]
    attained_eigenvalues: tuple[np.ndarray, np.ndarray]
    route_status: tuple[int, int]
    attained_status: tuple[int, int]
    boxes: int = 0
    converged: bool = True
    sampled: tuple[float, float] = (math.nan, math.nan)

    def __post_init__(self) -> None:
        for name, dtype in (("configurations", float), ("eigenvalues", complex), ("attained_eigenvalues", complex)):
            frozen = []
            for value in getattr(self, name):
                a = np.array(value, dtype=dtype)
                a.setflags(write=False)
                frozen.append(a)
            object.__setattr__(self, name, tuple(frozen))

    def end_passed(self, k: int) -> bool | None:
        """Verdict at end ``k`` (0 low, 1 high ``tau``): both routes must agree, else None.

        False when both fail at the witness; True when both hold at the proven bound and at the witness;
        None otherwise.
        """
        if self.attained_ends[k].passed is False and self.attained_status[k] == -1:
            return False
        witness_fine = self.attained_ends[k].passed is True and self.attained_status[k] == 1
        if self.ends[k].passed is True and self.route_status[k] == 1 and witness_fine:
            return True
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
        """How far the proven range stays from the stability limits of ``tau`` (1): ``1 - tau_hi/tau_crit``.

        With the stable interval ``(tau_a, tau_b)`` of :func:`stable_tau_interval`, the smaller of
        ``1 - tau_hi/tau_b`` and ``1 - tau_a/tau_lo`` (each 1 when that side is unbounded): the share of
        the critical ``D_ii`` still unused, positive when the whole range is stable (computed from the
        proven bounds, so it errs on the safe side by at most the tolerance).  When the interval is
        empty (a condition independent of ``tau`` fails) it is the smallest relative condition value.
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
            "inertia_attained": list(self.attained),
            "inertia_sampled": list(self.sampled),
            "inertia_unit": inertia_unit,
            "q_at_min": self.configurations[0],
            "q_at_max": self.configurations[1],
            "boxes": self.boxes,
            "converged": self.converged,
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
                "inertia_attained": self.attained[k],
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
                    samples: int = 7, tolerance: float = 1e-3) -> JointWorkspace:
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
        Grid points per outboard joint of the sampled estimate shown beside the proven range.
    tolerance : float
        Relative gap between each proven bound of ``D_ii`` and its witness.

    Returns
    -------
    JointWorkspace
    """
    from designkit.models.bounds import model_bound
    from designkit.models.link import link_range
    from designkit.verification.robustness import Sweeper

    plant, loop = design.plant, design.loops[i]
    if loop.characteristic is None or loop.characteristic.linear_conditions is None:
        raise ValueError(f"{design.loop_names[i]}: its loop exposes no affine stability conditions")
    sampled = link_range(plant.robot, i, low, high, samples=samples, p=plant.model_parameters())
    conditions = loop.characteristic.linear_conditions(loop.gains)
    Km = float(sampled.Km_min)
    f = 1.0 / Km
    stable = stable_tau_interval(conditions, Km)
    thresholds = (stable[0] * f if stable[0] > 0 else None, stable[1] * f if math.isfinite(stable[1]) else None)
    p = plant.model_parameters()
    enc = model_bound(plant.robot, "mass_matrix", (i, i), q=(np.asarray(low, float), np.asarray(high, float)),
                      p=None if p is None or len(p) == 0 else p, rel_tol=tolerance, strict=False,
                      thresholds=thresholds)
    proven = (enc.lower, enc.upper)
    attained = (enc.min_value, enc.max_value)
    configurations = (enc.argmin["q"], enc.argmax["q"])

    def judged(inertia: tuple[float, float]) -> tuple[tuple[VertexVerdict, VertexVerdict], Any, np.ndarray]:
        taus = (inertia[0] / f, inertia[1] / f)
        ends = box_verdict(conditions, (Km, Km), taus)
        sweep = Sweeper(loop, PARAMETERS).sweep([[Km, taus[0]], [Km, taus[1]]])
        return (ends[-1], ends[0]), sweep, np.linalg.eigvals(np.nan_to_num(sweep.A))

    ends, sweep, eig = judged(proven)
    a_ends, a_sweep, a_eig = judged(attained)
    return JointWorkspace(
        joint=i + 1,
        name=design.loop_names[i],
        prismatic=plant.robot.description.links[i].joint == "prismatic",
        damping=f,
        Km=Km,
        inertia=proven,
        attained=attained,
        tau=(proven[0] / f, proven[1] / f),
        configurations=configurations,
        nominal_tau=float(loop.plant.tau),
        stable_tau=stable,
        ends=ends,
        attained_ends=a_ends,
        abscissa=(float(sweep.abscissa[0]), float(sweep.abscissa[1])),
        attained_abscissa=(float(a_sweep.abscissa[0]), float(a_sweep.abscissa[1])),
        eigenvalues=(eig[0], eig[1]),
        attained_eigenvalues=(a_eig[0], a_eig[1]),
        route_status=(int(sweep.status[0]), int(sweep.status[1])),
        attained_status=(int(a_sweep.status[0]), int(a_sweep.status[1])),
        boxes=enc.boxes,
        converged=enc.converged,
        sampled=(float(sampled.inertia_min), float(sampled.inertia_max)),
    )


# ----------------------------------------------------------------------------- the check


def _vector(q: np.ndarray) -> str:
    return "[" + ", ".join(f"{v:.4g}" for v in q) + "]"


def _joint_detail(j: JointWorkspace) -> str:
    inertia_unit = j.units()[0]
    k = j.worst
    where = "every configuration (D_ii constant over the box)" if j.constant else f"q = {_vector(j.configurations[k])}"
    return (f"joint {j.joint}: tau in [{j.tau[0]:.4g}, {j.tau[1]:.4g}] s (D_{j.joint}{j.joint} proven in "
            f"[{j.inertia[0]:.4g}, {j.inertia[1]:.4g}] {inertia_unit}, attained up to {j.attained[1]:.4g}; stable for "
            f"D_{j.joint}{j.joint} < {j.stable_tau[1] * j.damping:.4g} {inertia_unit}), smallest margin "
            f"{j.margin:.3g} at {where}")


def _failure(j: JointWorkspace) -> tuple[str, dict[str, Any]]:
    k = next(k for k in (1, 0) if j.end_passed(k) is False)
    end, inertia_unit = j.attained_ends[k], j.units()[0]
    cond = next(c for c in end.conditions if c.status < 0)
    unit = f" {cond.unit}" if cond.unit else ""
    low, high = j.stable_tau
    where = (f"stable only for tau in ({low:.4g}, {high:.4g}) s" if low < high
             else "unstable for every tau: a condition independent of tau fails")
    detail = (f"joint {j.joint} unstable at q = {_vector(j.configurations[k])} (D_{j.joint}{j.joint} = "
              f"{j.attained[k]:.4g} {inertia_unit}, tau = {end.tau:.4g} s; {where}, designed for "
              f"{j.nominal_tau:.4g} s): "
              f"{cond.label.removesuffix(' > 0')} = {cond.value:.4g}{unit} <= 0, max Re(eig) = "
              f"{j.attained_abscissa[k]:+.4g} 1/s")
    evidence = to_json({
        "joint": j.joint,
        "configuration": j.configurations[k],
        "inertia": j.attained[k],
        "tau_s": end.tau,
        "Km": end.Km,
        "condition": cond.label,
        "value": cond.value,
        "spectral_abscissa": j.attained_abscissa[k],
        "eigenvalues": j.attained_eigenvalues[k],
    })
    return detail, evidence


def workspace_check(design: Any, workspace: Mapping[str, Any] | None = None) -> Check:
    """Check ``workspace``: every joint loop of ``design`` Hurwitz at every configuration of the box.

    Parameters
    ----------
    design : Design
        A decentralized design (per-joint ``loops`` on simplified links, a robot ``plant``).
    workspace : Mapping, optional
        ``{"low": [...], "high": [...], "samples": int, "tolerance": float}`` (rad or m per joint); default
        ``design.data.workspace`` (:class:`~designkit.families.decentralized_pid.data.DecentralizedPidData`, set by
        the family from ``controller.workspace``).

    Returns
    -------
    Check
        True: every joint certified over its ``D_ii`` range (see the module docstring for what that
        range is).  False: a joint's loop is unstable at a configuration of the box, named in the
        detail and in ``certificate["evidence"]``.  None: a condition zero within rounding, or the two
        routes disagree.  ``margin``: smallest relative condition value over the joints (1).
    """
    ws = dict(design.data.workspace if workspace is None else workspace)
    low, high = (np.asarray(ws[k], dtype=float) for k in ("low", "high"))
    samples = int(ws.get("samples", 7))
    tolerance = float(ws.get("tolerance", 1e-3))
    joints = [joint_workspace(design, i, low, high, samples=samples, tolerance=tolerance)
              for i in range(len(design.loops))]
    worst = min(joints, key=lambda j: j.margin)
    cert: dict[str, Any] = {
        "method": VERDICT_METHOD,
        "range_method": RANGE_METHOD,
        "rigorous_range": True,
        "tolerance": tolerance,
        "boxes": sum(j.boxes for j in joints),
        "workspace": to_json({**ws, "low": low, "high": high, "samples": samples, "tolerance": tolerance}),
        "nominal_configuration": to_json(getattr(design.data, "configuration", None)),
        "joints": [j.to_dict() for j in joints],
        "ends": [row for j in joints for row in j.end_rows()],
        "smallest_margin": {"joint": worst.joint, "margin": worst.margin,
                            "configuration": to_json(worst.configurations[worst.worst])},
    }
    data = {"joints": [{"name": j.name, "joint": j.joint, "tau": j.tau, "tau_nominal": j.nominal_tau,
                        "tau_stable": j.stable_tau} for j in joints]}
    target = "each joint's PID loop Hurwitz at every configuration of the workspace box (proven bounds of D_ii)"
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
        why = ("the enclosure of D_ii did not decide the critical inertia within its work limit"
               if not j.converged else "a stability condition is zero within rounding at an end of its range, or the "
               "conditions and the linearization disagree")
        detail = f"undecided: joint {j.joint}: {why} ({_joint_detail(j)})"
        return Check("workspace", None, target, worst.margin, worst.margin, unit, detail, cert, data=data)
    detail = (f"{len(joints)} joint loops proven Hurwitz for every configuration of the box (frozen q; each D_ii "
              f"enclosed in ball arithmetic to {tolerance:.3g} relative); worst {_joint_detail(worst)}")
    return Check("workspace", True, target, worst.margin, worst.margin, unit, detail, cert, data=data)


def _figure(result: Any, check: Check) -> Any:
    from designkit.families.decentralized_pid.figures import workspace_figure

    return workspace_figure(result, check)


def _run(design: Any, ctx: Any) -> tuple[Check, ...]:
    return (workspace_check(design),)


RULE = CheckRule(
    name="workspace", order=70, linear=True,
    applies=lambda d, c: bool(d.loops) and isinstance(d.data, DecentralizedPidData) and d.data.workspace is not None,
    run=_run, label="Joint loops stable over the workspace", figures=(_figure,),
)
"""The decentralized PID's own check: every joint loop for every configuration of ``controller.workspace``."""
