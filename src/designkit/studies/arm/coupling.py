"""Question 4: how effective the controller is in neutralizing intercouplings, centripetal and Coriolis forces."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.display.numbers import fmt_number, fmt_percent, quantity
from designkit.models.torques import coupling_torques, model_error_torque
from designkit.studies.arm.run import NEGLIGIBLE_ERROR, PathSamples, check_named, family_label

__all__ = ["Coupling", "JointCoupling", "coupling_level", "coupling_sentences", "measure_coupling"]

NEGLIGIBLE_COUPLING = 0.05
"""Coupling below this fraction of the joint's own inertial torque is negligible."""
MODERATE_COUPLING = 0.3
"""Coupling up to this fraction of the joint's own inertial torque is moderate (significant beyond)."""
DOMINANT_COUPLING = 1.0
"""Coupling above this fraction of the joint's own inertial torque dominates it."""

@dataclass(frozen=True)
class JointCoupling:
    """Torques left to the controller at one joint along the path (question 4), peaks of ``|.|`` (N*m or N).

    Parameters
    ----------
    joint : int
        1-based.
    unit : str
    off_diagonal, coriolis : float
        ``sum_{j != i} D_ij qdd_j`` and the Coriolis and centrifugal torque.
    coupling, coupling_at : float
        Their sum, and when it peaks (s).
    own_inertial : float
        ``D_ii qdd_i``.
    ratio : float
        ``coupling / own_inertial`` (``inf`` when the joint has no inertial torque of its own).
    model_error : float or None
        ``ID_true - ID_model`` (model-based designs only).
    """

    joint: int
    unit: str
    off_diagonal: float
    coriolis: float
    coupling: float
    coupling_at: float
    own_inertial: float
    ratio: float
    model_error: float | None = None


@dataclass(frozen=True)
class Coupling:
    """Intercoupling, centripetal and Coriolis torques (question 4).

    Parameters
    ----------
    joints : tuple of JointCoupling
    stride : int
        Every ``stride``-th instant of the run was evaluated.
    sentences : tuple of str
    """

    joints: tuple[JointCoupling, ...]
    stride: int
    sentences: tuple[str, ...]


def coupling_level(ratio: float) -> str:
    """The coupling of a joint in words, from ``coupling / own inertial torque``.

    >>> [coupling_level(r) for r in (0.01, 0.2, 0.6, 2.0, float("inf"))]
    ['negligible', 'moderate', 'significant', 'dominant', 'dominant']
    """
    if ratio < NEGLIGIBLE_COUPLING:
        return "negligible"
    if ratio <= MODERATE_COUPLING:
        return "moderate"
    if ratio <= DOMINANT_COUPLING:
        return "significant"
    return "dominant"


def coupling_sentences(joints: Sequence[JointCoupling], nature: str, label: str = "The controller",
                       intercoupling: Sequence[Any] = ()) -> tuple[str, ...]:
    """Sentences on the coupling torques, chosen from the numbers.

    Parameters
    ----------
    joints : sequence of JointCoupling
    nature : str
        ``"per-joint loops"``, ``"model-based"`` or ``"other"``.
    label : str
        The controller in words.
    intercoupling : sequence of dict
        The ``coupling`` check's ``intercoupling_error`` rows (``joint``, ``max_abs_rad``, ``at_s``), if any.
    """
    out = []
    cancelled = nature == "model-based" and bool(joints) and all(
        j.model_error is not None and (j.model_error == 0 or j.model_error < NEGLIGIBLE_COUPLING * j.coupling)
        for j in joints)
    for j in joints:
        level = coupling_level(j.ratio)
        if cancelled and level != "negligible":  # the arm has it, the loop does not feel it: no claim of dominance
            level = f"{level} in the arm's dynamics, but cancelled by the controller's model (below)"
        own = (f"{fmt_percent(j.ratio)} of its own inertial torque D_{j.joint}{j.joint} q̈_{j.joint} "
               f"(peak {quantity(j.own_inertial, j.unit, 3)})" if math.isfinite(j.ratio)
               else "while the joint has no inertial torque of its own (it does not accelerate by itself)")
        text = (f"At joint {j.joint} the intercoupling, centripetal and Coriolis torques reach "
                f"{quantity(j.coupling, j.unit, 3)} (t = {fmt_number(j.coupling_at, 3)} s; off-diagonal inertia "
                f"{quantity(j.off_diagonal, j.unit, 3)}, Coriolis and centrifugal "
                f"{quantity(j.coriolis, j.unit, 3)}), {own}: {level}.")
        out.append(text)
    if not joints:
        return tuple(out)
    if nature == "model-based":
        errs = [j.model_error for j in joints if j.model_error is not None]
        if errs and max(errs) == 0:
            out.append(f"{label} computes them from its model, which is the plant here: they are cancelled "
                       "exactly (model error torque 0 at every joint).")
        elif errs:
            e = max((j for j in joints if j.model_error is not None), key=lambda j: j.model_error)
            share = e.model_error / e.coupling if e.coupling > 0 else math.inf
            text = (f"{label} cancels them through its model up to the model error torque ID_plant − ID_model, "
                    f"which reaches {quantity(e.model_error, e.unit, 3)} at joint {e.joint}, {fmt_number(share, 3)} "
                    "times the coupling "
                    f"torque there")
            if share < NEGLIGIBLE_COUPLING:
                text += ": the coupling is cancelled almost exactly"
            elif share > 1:
                text += (": the model mismatch, not the coupling, is what the feedback e'' + K2 e' + K1 e has to "
                         "absorb")
            else:
                text += ": what is left acts as a disturbance on the error dynamics e'' + K2 e' + K1 e = 0"
            out.append(text + ".")
    elif nature == "per-joint loops":
        text = (f"{label} has no model of them: each joint's loop sees them as the perturbation xi_i of its "
                "simplified link and can only reject them by feedback")
        if intercoupling:
            r = max(intercoupling, key=lambda row: row["max_abs_rad"])
            text += (f"; the coupling check measures what gets through: joint {r['joint']} departs from its "
                     f"decoupled response by up to {fmt_number(r['max_abs_rad'], 3)} rad (t = "
                     f"{fmt_number(r['at_s'], 3)} s)")
        out.append(text + ".")
    return tuple(out)


def measure_coupling(result: Any, plant: Any, path: PathSamples | None, nature: str) -> Coupling:
    if path is None:
        return Coupling((), 1, ("The simulated path is not finite: the coupling torques are not measured.",))
    tq = coupling_torques(plant, path.q, path.qd, path.qdd)
    model_err = None
    if nature == "model-based":
        model_err = np.abs(model_error_torque(plant, result.design.plant, path.q, path.qd, path.qdd))
    joints = []
    size = float(np.max(np.abs(tq["own"]), initial=0.0))
    for i in range(path.q.shape[1]):
        c = np.abs(tq["coupling"][:, i])
        k = int(np.argmax(c))
        own = float(np.max(np.abs(tq["own"][:, i])))
        peak = float(c[k])
        moves_itself = own > NEGLIGIBLE_ERROR * max(size, peak)  # else its own acceleration is numerical noise
        ratio = peak / own if moves_itself else (0.0 if peak == 0 else math.inf)
        joints.append(JointCoupling(
            i + 1, plant.inputs[i].unit, float(np.max(np.abs(tq["off_diagonal"][:, i]))),
            float(np.max(np.abs(tq["coriolis"][:, i]))), peak, float(path.t[k]), own, ratio,
            float(np.max(model_err[:, i])) if model_err is not None else None))
    check = check_named(result, "coupling")
    rows = check.certificate.get("intercoupling_error", ()) if check is not None else ()
    return Coupling(tuple(joints), path.stride, coupling_sentences(joints, nature, family_label(result), rows))
