"""Question 3: the influence of the working configuration (the inertia each joint sees along the path)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.display.numbers import fmt_number, fmt_percent, fmt_poles, plain_complex, quantity
from designkit.studies.arm.run import PathSamples, check_named, family_label

__all__ = ["Configuration", "JointInertia", "configuration_sentences", "measure_configuration"]


@dataclass(frozen=True)
class JointInertia:
    """The inertia ``D_ii`` a joint sees along the motion (question 3).

    Parameters
    ----------
    joint : int
        1-based.
    unit : str
        ``kg*m^2`` (revolute) or ``kg`` (prismatic).
    low, high : float
        Smallest and largest ``D_ii`` along the path, ``low_at``, ``high_at`` when (s).
    ratio : float
        ``high / low``.
    design_value : float or None
        ``D_ii(q*)`` the joint loop was designed for (per-joint loop designs).
    design_poles, poles_at_low, poles_at_high : tuple of complex
        The joint loop's poles at ``D_ii(q*)`` and at the ends of the range (1/s; empty when not applicable).
    """

    joint: int
    unit: str
    low: float
    low_at: float
    high: float
    high_at: float
    ratio: float
    design_value: float | None = None
    design_poles: tuple[complex, ...] = ()
    poles_at_low: tuple[complex, ...] = ()
    poles_at_high: tuple[complex, ...] = ()


@dataclass(frozen=True)
class Configuration:
    """Influence of the configuration (question 3): ``joints`` and the generated ``sentences``."""

    joints: tuple[JointInertia, ...]
    sentences: tuple[str, ...]



def _poles(poles: Sequence[complex]) -> str:
    return "(" + fmt_poles(poles) + ")"


def _inertia_unit(plant: Any, i: int) -> str:
    return "kg" if plant.inputs[i].unit == "N" else "kg*m^2"


def _loop_poles(loop: Any, inertia_factor: float) -> tuple[complex, ...]:
    """Poles of a joint loop on its simplified link with ``tau`` scaled by ``inertia_factor`` (``tau = D/f``)."""
    ch = loop.characteristic
    if ch is None or "tau" not in ch.parameters:
        return ()
    theta = {p: loop.plant.parameter(p).value for p in ch.parameters}
    theta["tau"] = theta["tau"] * inertia_factor
    coeffs = [float(np.asarray(c)) for c in ch.coefficients(loop.gains, **theta)]
    return tuple(complex(r) for r in np.roots(coeffs))


def measure_configuration(result: Any, plant: Any, path: PathSamples | None, nature: str) -> Configuration:
    design = result.design
    if path is None:
        return Configuration((), ("The simulated path is not finite: the configuration's influence is not measured.",))
    M = np.asarray(plant.robot.mass_matrix(path.q, p=plant.model_parameters()), dtype=float)
    D = np.diagonal(M, axis1=1, axis2=2)
    joints = []
    # per-joint loops are designed on the simplified links at the configuration the design is linearized at
    op = design.operating_point
    n = D.shape[1]
    star = np.asarray(op["r"], dtype=float)[:n].tolist() if nature == "per-joint loops" and op else None
    design_D = None
    if star is not None:
        Ms = design.plant.robot.mass_matrix(np.asarray(star, float), p=design.plant.model_parameters())
        design_D = np.diag(np.asarray(Ms, float)).tolist()
    for i in range(D.shape[1]):
        lo, hi = int(np.argmin(D[:, i])), int(np.argmax(D[:, i]))
        low, high = float(D[lo, i]), float(D[hi, i])
        extra: dict[str, Any] = {}
        if design_D is not None and i < len(design.loops):
            loop, d0 = design.loops[i], design_D[i]
            extra = {"design_value": d0, "design_poles": _loop_poles(loop, 1.0),
                     "poles_at_low": _loop_poles(loop, low / d0), "poles_at_high": _loop_poles(loop, high / d0)}
        joints.append(JointInertia(i + 1, _inertia_unit(plant, i), low, float(path.t[lo]), high, float(path.t[hi]),
                                   high / low if low > 0 else math.inf, **extra))
    sentences = list(configuration_sentences(joints))
    if nature == "per-joint loops":
        sentences += _loop_configuration_sentences(joints, star)
    elif nature == "model-based":
        sentences += _model_configuration_sentences(result, joints)
    return Configuration(tuple(joints), tuple(sentences))


def configuration_sentences(joints: Sequence[JointInertia]) -> tuple[str, ...]:
    """How much the inertia each joint sees varies along the motion (one sentence per joint)."""
    out = []
    for j in joints:
        if j.ratio - 1 <= 1e-9:
            out.append(f"The inertia joint {j.joint} sees does not depend on this motion "
                       f"(D_{j.joint}{j.joint} = {quantity(j.low, j.unit, 4)} throughout).")
        elif j.ratio < 1.01:
            out.append(f"The inertia joint {j.joint} sees is practically constant along this motion "
                       f"(D_{j.joint}{j.joint} = {quantity(j.low, j.unit, 4)}, within {fmt_percent(j.ratio - 1)}).")
        else:
            out.append(f"The inertia joint {j.joint} sees varies by a factor {fmt_number(j.ratio, 3)} along this "
                       f"motion: D_{j.joint}{j.joint} from {quantity(j.low, j.unit, 3)} (t = "
                       f"{fmt_number(j.low_at, 3)} s) to "
                       f"{quantity(j.high, j.unit, 3)} (t = {fmt_number(j.high_at, 3)} s).")
    return tuple(out)


def _loop_configuration_sentences(joints: Sequence[JointInertia], star: Any) -> list[str]:
    out = []
    where = "(" + ", ".join(fmt_number(v, 4) for v in star) + ")" if star is not None else "q*"
    for j in joints:
        if j.design_value is None:
            continue
        a, b = j.low / j.design_value, j.high / j.design_value
        text = (f"Joint {j.joint}'s loop was designed on its simplified link at q* = {where} for "
                f"D_{j.joint}{j.joint}(q*) = {quantity(j.design_value, j.unit, 3)}; ")
        if max(abs(a - 1), abs(b - 1)) < 0.01:
            out.append(text + "along the motion the inertia stays within 1 % of that value, so the loop keeps the "
                       "poles it was designed for.")
            continue
        text += (f"along the motion the inertia is {fmt_number(a, 3)}–{fmt_number(b, 3)} times that value, and so "
                 "is the time constant "
                 f"tau_{j.joint} = D_{j.joint}{j.joint}/f_{j.joint} of the link the gains were computed for")
        if j.design_poles and j.poles_at_low and j.poles_at_high:
            ends = []
            if abs(a - 1) >= 0.01:
                ends.append(f"{_poles(j.poles_at_low)} 1/s at the lightest configuration")
            if abs(b - 1) >= 0.01:
                ends.append(f"{_poles(j.poles_at_high)} 1/s at the heaviest")
            stable = all(p.real < 0 for p in (*j.poles_at_low, *j.poles_at_high))
            text += (f": its poles move from the placed {_poles(j.design_poles)} 1/s to " + " and ".join(ends)
                     + (" (still stable)" if stable else ": the frozen loop is unstable there"))
        out.append(text + ".")
    return out


def _model_configuration_sentences(result: Any, joints: Sequence[JointInertia]) -> list[str]:
    check = check_named(result, "error_poles")
    if check is None:
        return []
    cert = check.certificate
    widest = max(joints, key=lambda j: j.ratio) if joints else None
    varies = (f", although D_{widest.joint}{widest.joint} varies by a factor {fmt_number(widest.ratio, 3)}"
              if widest is not None and widest.ratio >= 1.01 else "")
    label = family_label(result)
    out = []
    instants = cert.get("instants")
    at = f" at {instants} instants" if instants else ""
    dimensionless = check.unit in ("", "1") or check.unit.startswith("1 ")
    evidence = (fmt_number(check.achieved, 2) + ("" if dimensionless else f" {check.unit}")
                if isinstance(check.achieved, float) else "")
    if "damped_least_squares" in cert:
        dls = cert["damped_least_squares"]
        out.append(f"{label} cancels the configuration-dependent dynamics through its model, but its damped "
                   f"least-squares resolution moves the task-error poles by up to "
                   f"{fmt_number(dls.get('largest_pole_move_1_per_s'), 3)} 1/s along the path (t = "
                   f"{fmt_number(dls.get('at_s'), 3)} s), "
                   "where J is worst conditioned.")
    elif check.passed:
        out.append(f"{label} cancels the configuration-dependent dynamics through its model: on the model the "
                   f"error dynamics linearized{at} along the reference are the requested decoupled ones (the "
                   f"error_poles check: {evidence or 'passed'}, target {check.target}){varies}, so the "
                   "configuration does not change the designed error dynamics.")
    else:
        out.append(f"On the model the error dynamics leave the requested ones along the path (the error_poles "
                   f"check: {evidence or 'failed'}, target {check.target}): {plain_complex(check.detail)}.")
    true = cert.get("true_plant")
    if true:
        move = float(true["largest_pole_move_1_per_s"])
        size = max((abs(complex(*p)) for p in cert.get("requested_poles", ())), default=1.0)
        text = (f"On the true plant the model mismatch moves them by up to {fmt_number(move, 3)} 1/s (t = "
                f"{fmt_number(true.get('at_s'), 3)} s)")
        if move < 1e-3 * size:
            text += (f", {fmt_number(move / size, 2)} of their size: the mismatch shows as a torque the model misses "
                     "(below), not as a change of the error dynamics")
        else:
            text += ": along the path the configuration acts through what the model gets wrong"
        out.append(text + ".")
    return out
