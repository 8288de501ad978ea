"""Question 5: the influence of the mass parameters (the checks that vary them, the controller's model)."""

from __future__ import annotations

from typing import Any

import numpy as np

from designkit.analysis.lab.run import NEGLIGIBLE_ERROR, check_named, commanded_moves
from designkit.display.numbers import fmt_number, quantity

__all__ = ["mass_sentences"]


def mass_sentences(result: Any, plant: Any) -> tuple[str, ...]:
    design = result.design
    out = []
    differs = [(q.name, q.unit, q.value, plant.parameter(q.name).value) for q in design.plant.parameters
                if q.name in plant.parameter_names and q.value != plant.parameter(q.name).value]
    if differs:
        out.append("The controller's model differs from the true plant: " + ", ".join(
            f"{name} {fmt_number(m, 4)} against {quantity(t, unit, 4)}" for name, unit, m, t in differs)
            + " (model against plant); the torque this costs is the model error torque below.")
    bounds = check_named(result, "tracking_bounds")
    sim = result.simulation
    if bounds is not None and bounds.achieved is not None:
        cert = bounds.certificate
        per_joint = cert.get("bound_per_joint_rad", [])
        j = int(np.argmax(per_joint)) if per_joint else 0
        where = ", ".join(f"{k} = {fmt_number(v, 4)}" for k, v in dict(cert.get("worst_parameters", {})).items())
        errors = None if sim is None or sim.task_space else np.abs(np.asarray(sim.tracking_errors, dtype=float))
        nominal = float(np.max(errors[:, j])) if errors is not None and errors.shape[1] > j else None
        runs = f"{cert.get('corners')} corners" + (f" and {cert.get('random_samples')} random samples"
                                                    if cert.get("random_samples") else "")
        text = (f"Over {cert.get('runs')} runs on the true plant at the parameter box's {runs} the largest "
                f"|q − qD| is {fmt_number(bounds.achieved, 3)} rad at joint {j + 1} ({where})")
        if nominal is not None and np.isfinite(nominal):
            move = float(commanded_moves(sim)[j])
            if nominal <= NEGLIGIBLE_ERROR * max(move, 1.0):
                text += f", where this run tracks to the integrator's precision ({fmt_number(nominal, 2)} rad)"
            else:
                text += f", {fmt_number(bounds.achieved / nominal, 3)} times this run's {fmt_number(nominal, 3)} rad"
        out.append(text + ".")
    grid = check_named(result, "robust_grid")
    if grid is not None:
        cert = grid.certificate
        worst = dict(cert.get("worst_abscissa", {}))
        abscissa = worst.pop("spectral_abscissa", None)
        where = ", ".join(f"{k} = {fmt_number(v, 4)}" for k, v in worst.items())
        if cert.get("unstable") or cert.get("undecided"):
            bad = cert.get("unstable", 0) + cert.get("undecided", 0)
            out.append(f"The linearized loop is unstable or undecided for {bad} of the {cert.get('plants')} plants "
                       "of the parameter box.")
        else:
            out.append(f"The linearized loop stays stable for all {cert.get('plants')} plants of the parameter box; "
                       f"its slowest pole, Re = {fmt_number(abscissa, 3)} 1/s, is at {where}.")
    if not out:
        out.append("The spec gives no parameter box and the controller's model is the plant: this run does not vary "
                   "the mass parameters (give plant.uncertainty, or controller.model for a model-based design).")
    return tuple(out)
