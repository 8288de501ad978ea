"""Checks of trajectory-tracking designs: the error poles along the path, tracking under model mismatch,
and the actuator torques.

``error_poles``
    The closed loop linearized **along the reference trajectory** (at ``z = (qD(t), qD'(t))``, the
    state of perfect tracking, with ``r = r(t)``) at evenly spaced instants, on the controller's
    model: its eigenvalues must be the requested error poles at every instant (computed torque
    decouples and linearizes exactly, whatever the configuration).  The same is evaluated on the
    true plant when it differs from the model, and the largest move of the poles is reported
    (evidence of what the mismatch does to the error dynamics; not part of the verdict).
    For a task-space design (resolved acceleration) the instants are on the joint path that tracks
    the reference exactly, and the matrix whose eigenvalues are compared is the linearized
    dynamics of the task errors ``eps = (xD - x(q), xD' - J qd)``: with the closed loop
    ``z' = f(z, r)`` and ``E = d eps/dz``, ``A_task = d(E f)/dz E^-1`` (``eps`` is affine in the
    reference with constant coefficients, so the reference's motion adds nothing).
``tracking_bounds``
    The simulation repeated on the true plant at every corner of ``plant.uncertainty`` and at its
    seeded random interior samples (one built simulator, the parameters fed per run): the largest
    ``|q - qD|`` over the runs, per joint, with the parameters where it occurs.  Against
    ``requirements.tracking_error`` when given (then part of the verdict), else informational.
``torque_limits``
    The simulated commanded torque of every joint against ``plant.limits.torque``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from designkit.verification.check import Check
from designkit.verification.pole_zero import match_roots
from designkit.verification.tolerances import POLE_REL

__all__ = ["error_poles_check", "torque_limits_check", "tracking_bounds_check"]

PATH_SAMPLES = 41
"""Instants along the reference at which the error poles are computed."""


def _path_jacobians(plant: Any, law: Any, t: np.ndarray, R: np.ndarray, n: int) -> np.ndarray:
    from designkit.synthesis.closed_loop import loop_functions

    fns = loop_functions(plant, law)
    nz = fns.n_state + fns.n_controller
    Z = np.zeros((t.size, nz))
    Z[:, list(plant.positions)] = R[:, :n]
    Z[:, list(plant.velocities)] = R[:, n:2 * n]
    P = np.tile(np.asarray(plant.parameter_vector, dtype=float), (t.size, 1))
    return fns.evaluate(Z, R, np.zeros(len(plant.disturbances)), P)[1]


def _task_error_matrices(plant: Any, law: Any, motion: Any, t: np.ndarray, R: np.ndarray) -> np.ndarray:
    """``A_task`` (see the module docstring) at the instants ``t`` of the exact joint path."""
    import casadi as ca

    n = plant.n_joints
    fns = motion.functions
    q, qd, r = ca.SX.sym("q", n), ca.SX.sym("qd", n), ca.SX.sym("r", 3 * n)
    y = ca.SX.zeros(len(plant.states))
    y[list(plant.positions)], y[list(plant.velocities)] = q, qd
    u = law.command(y, ca.SX(0, 1), ca.SX(0, 1), r)
    f = plant.ode()(y, u, ca.SX.zeros(len(plant.disturbances)), ca.DM(plant.parameter_vector))
    z = ca.vertcat(q, qd)
    zdot = ca.vertcat(*[f[i] for i in plant.positions], *[f[i] for i in plant.velocities])
    eps = ca.vertcat(r[:n] - fns.tracked(q), r[n:2 * n] - fns.rate(q, qd))
    E = ca.jacobian(eps, z)
    Edot = ca.jacobian(E @ zdot, z)
    F = ca.Function("task_error_matrices", [q, qd, r], [E, Edot]).map(t.size)
    Es, Eds = F(motion.path.q.T, motion.path.qd.T, R.T)
    Es, Eds = np.asarray(Es), np.asarray(Eds)
    m = 2 * n
    out = np.empty((t.size, m, m))
    for k in range(t.size):
        Ek, Edk = Es[:, k * m:(k + 1) * m], Eds[:, k * m:(k + 1) * m]
        out[k] = np.linalg.solve(Ek.T, Edk.T).T
    return out


def error_poles_check(spec: Any, design: Any, plant: Any = None) -> Check:
    """Check ``"error_poles"`` (see the module docstring)."""
    from designkit.families import family
    from designkit.simulation.motion import motion_of
    from designkit.simulation.reference import reference_for

    n = design.plant.n_joints
    motion = motion_of(spec, design)
    law = family(design.kind).law(design, None)
    requested = np.asarray(design.poles, dtype=complex)
    scale = float(np.max(np.abs(requested))) or 1.0
    if motion is not None:
        t = motion.path.time
        R = motion.reference.flat(t)
        A = _task_error_matrices(design.plant, law, motion, t, R)
    else:
        ref = reference_for(design.reference, spec.simulation, n)
        horizon = ref.horizon if ref.horizon > 0 else 1.0
        t = np.linspace(0.0, horizon, PATH_SAMPLES)
        R = ref.flat(t)
        A = _path_jacobians(design.plant, law, t, R, n)
    rows, worst, worst_t = [], 0.0, 0.0
    for k, Ak in enumerate(A):
        got = np.linalg.eigvals(Ak)
        m = match_roots(got, requested, scale)
        if m["ratio"] > worst:
            worst, worst_t = float(m["ratio"]), float(t[k])
        rows.append(m["ratio"])
    ok = bool(np.all(np.isfinite(rows)) and worst <= 1.0)
    cert: dict[str, Any] = {
        "instants": int(t.size), "horizon_s": float(t[-1]), "space": "task" if motion is not None else "joint",
        "requested_poles": [[p.real, p.imag] for p in requested],
        "worst_error_over_tolerance": worst, "worst_at_s": worst_t, "tolerance": POLE_REL,
    }
    detail = (f"on the controller's model the {'task-error dynamics' if motion is not None else 'closed loop'} "
              f"linearized at {t.size} instants along the reference "
              f"has exactly the requested error poles (worst {worst:.2g} x tolerance at t = {worst_t:.3g} s)"
              if ok else f"the error poles leave the requested ones along the path: {worst:.3g} x tolerance at "
              f"t = {worst_t:.3g} s")
    if plant is not None and plant is not design.plant:
        At = (_task_error_matrices(plant, law, motion, t, R) if motion is not None
              else _path_jacobians(plant, law, t, R, n))
        shifts = []
        for Ak in At:
            got = np.linalg.eigvals(Ak)
            shifts.append(match_roots(got, requested, scale)["ratio"] * POLE_REL * scale)
        k = int(np.argmax(shifts))
        cert["true_plant"] = {"largest_pole_move_1_per_s": float(shifts[k]), "at_s": float(t[k])}
        detail += (f"; on the true plant the model mismatch moves them by up to {shifts[k]:.3g} 1/s "
                   f"(t = {t[k]:.3g} s)")
    damping = design.extra.get("damping")
    if damping:  # damped least squares trades the exact poles for bounded joint accelerations: evidence only
        move = worst * POLE_REL * scale
        cert["damped_least_squares"] = {"damping": damping, "largest_pole_move_1_per_s": move, "at_s": worst_t}
        detail = (f"damped least squares (lambda = {damping:g}) moves the task-error poles by up to {move:.3g} 1/s "
                  f"along the path (t = {worst_t:.3g} s, where J is worst conditioned); exact elsewhere to "
                  f"{POLE_REL:g} [informational: the damping gives up exact poles near singularities]")
        return Check(name="error_poles", passed=True, target="reported (damped least squares)", achieved=move,
                     margin=None, unit="1/s", detail=detail, certificate=cert, required=False)
    return Check(name="error_poles", passed=ok, target=f"requested poles at every instant, to {POLE_REL:g} (scaled)",
                 achieved=worst * POLE_REL, margin=1.0 - worst, unit="1 (scaled)", detail=detail, certificate=cert)


def tracking_bounds_check(spec: Any, design: Any, plant: Any) -> Check:
    """Check ``"tracking_bounds"`` (see the module docstring)."""
    from designkit.simulation.run import build
    from designkit.verification.robustness import box_from_uncertainty

    box = box_from_uncertainty(plant, spec.plant.uncertainty)
    thetas = np.vstack([box.vertices, box.random]) if box.samples else box.vertices
    simulator = build(spec, design, plant=plant, expected_runs=len(thetas))
    peaks, runs = [], []
    for theta in thetas:
        res = simulator.run(parameters=dict(zip(box.names, map(float, theta), strict=True)))
        err = np.abs(res.tracking_errors)
        peak = np.max(err, axis=0) if np.all(np.isfinite(err)) else np.full(err.shape[1], np.inf)
        peaks.append(peak)
        runs.append(res)
    peaks = np.array(peaks)
    worst_run = int(np.argmax(np.max(peaks, axis=1)))
    bound = float(np.max(peaks))
    joint = int(np.argmax(peaks[worst_run]))
    where = ", ".join(f"{n}={v:.4g}" for n, v in zip(box.names, thetas[worst_run], strict=True))
    limit = spec.requirements.tracking_error if spec.requirements is not None else None
    cert = {
        "box": box.describe(), "runs": len(thetas), "corners": len(box.vertices), "random_samples": box.samples,
        "seed": box.seed if box.samples else None,
        "bound_per_joint_rad": np.max(peaks, axis=0).tolist(), "worst_parameters": dict(
            zip(box.names, map(float, thetas[worst_run]), strict=True)),
    }
    data = {"time": np.asarray(runs[worst_run].time), "errors": np.asarray(runs[worst_run].tracking_errors),
            "envelope": np.max(np.abs(np.array([r.tracking_errors for r in runs])), axis=0)}
    finite = np.isfinite(bound)
    detail = (f"largest |q - qD| over {len(thetas)} runs on the true plant (corners and samples of the box): "
              f"{bound:.4g} rad, joint {joint + 1}, at {where}" if finite else
              f"a run diverged (at {where})")
    if limit is None:
        return Check(name="tracking_bounds", passed=bool(finite), target="reported (no tracking_error requirement)",
                     achieved=bound if finite else None, margin=None, unit="rad", detail=detail + " [informational]",
                     certificate=cert, required=False, data=data)
    return Check(name="tracking_bounds", passed=bool(finite and bound <= limit), target=f"<= {limit:g} rad",
                 achieved=bound if finite else None, margin=float(limit - bound) if finite else None, unit="rad",
                 detail=detail, certificate=cert, data=data)


def torque_limits_check(spec: Any, simulation: Any) -> Check:
    """Check ``"torque_limits"``: peak commanded torque of every joint within ``plant.limits.torque``."""
    u = np.asarray(simulation.u_command, dtype=float)
    limits = np.broadcast_to(np.asarray(spec.plant.limits.torque, dtype=float), (u.shape[1],))
    peaks = np.max(np.abs(u), axis=0) if np.all(np.isfinite(u)) else np.full(u.shape[1], np.inf)
    k = int(np.argmax(peaks / limits))
    ok = bool(np.all(peaks <= limits))
    names = simulation.input_names
    over = [f"{names[j]} {peaks[j]:.4g} > {limits[j]:g}" for j in range(len(peaks)) if peaks[j] > limits[j]]
    detail = (f"every joint within its torque limit; nearest {names[k]}: {peaks[k]:.4g} of {limits[k]:g} N*m" if ok
              else "over the limit: " + "; ".join(over) + " N*m")
    return Check(name="torque_limits", passed=ok, target="peak |u| <= limit on every joint",
                 achieved=float(peaks[k]), margin=float(limits[k] - peaks[k]), unit="N*m", detail=detail,
                 certificate={"peaks": peaks.tolist(), "limits": limits.tolist()})
