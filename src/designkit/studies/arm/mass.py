"""Question 5: the influence of the mass parameters (the checks that vary them, the controller's model)."""

from __future__ import annotations

from typing import Any

import numpy as np

from designkit.display.numbers import fmt_number, quantity
from designkit.studies.arm.run import NEGLIGIBLE_ERROR, check_named, commanded_moves

__all__ = ["BOX_RUNS_MAX", "box_response_sentence", "mass_sentences"]

BOX_RUNS_MAX = 16
"""Corners of the parameter box re-simulated for the lab answer (a larger box is not re-simulated)."""


def box_response_sentence(result: Any, plant: Any) -> str:
    """Overshoot, settling time and steady-state error of a step run re-simulated at every corner of the spec's
    parameter box (on the true plant, with the designed law); ``""`` when there is no box or no step run."""
    spec = result.loaded.spec
    sim = result.simulation
    unc = getattr(spec.plant, "uncertainty", None)
    if unc is None or sim is None or sim.kind != "step":
        return ""
    from designkit.simulation.run import build
    from designkit.verification.robustness import box_from_uncertainty
    from designkit.verification.time_domain import response_metrics

    box = box_from_uncertainty(plant, unc)
    corners = np.asarray(box.vertices, float)
    if len(corners) > BOX_RUNS_MAX:
        return ""
    band = spec.requirements.settling_band if spec.requirements is not None else 0.02
    rows = []
    for theta in corners:
        # built on the corner's plant: the loop starts at rest there (its integrals hold that arm still), as the
        # designed loop would on that arm
        corner = plant.with_params(**dict(zip(box.names, map(float, theta), strict=True)))
        run = build(spec, result.design, plant=corner).run()
        with np.errstate(all="ignore"):
            m = response_metrics(run, settling_band=band)
        rows.append((theta, m))

    def span(values: list[Any], unit: str) -> str:
        finite = [v for v in values if v is not None and np.isfinite(v)]
        if not finite:
            return "undefined at every corner"
        text = f"{fmt_number(min(finite), 3)} to {quantity(max(finite), unit, 3)}"
        return text + ("" if len(finite) == len(values) else f" ({len(values) - len(finite)} corners undefined)")

    def worst(values: list[Any]) -> str:
        k = max(range(len(values)), key=lambda i: -np.inf if values[i] is None or not np.isfinite(values[i])
                else values[i])
        return ", ".join(f"{n} = {fmt_number(v, 4)}" for n, v in zip(box.names, rows[k][0], strict=True))

    over = [m.overshoot for _, m in rows]
    settle = [m.settling_time for _, m in rows]
    sse = [m.steady_state_error for _, m in rows]
    names = ", ".join(f"{n} in [{fmt_number(lo, 4)}, {fmt_number(hi, 4)}]" for n, lo, hi in
                      zip(box.names, box.lo, box.hi, strict=True))
    return (f"Re-simulated on the true plant at the {len(corners)} corners of the parameter box ({names}): overshoot "
            f"{span(over, '%')} (largest at {worst(over)}), settling time to the {fmt_number(100 * band, 3)} % band "
            f"{span(settle, 's')} (longest at {worst(settle)}), steady-state error {span(sse, 'rad')}.")


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
    box_text = box_response_sentence(result, plant)
    if box_text:
        out.append(box_text)
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
