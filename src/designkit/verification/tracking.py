"""Checks of trajectory-tracking designs: the error poles along the path, tracking under model mismatch,
and the actuator torques.

``error_poles``
    The closed loop linearized **along the reference trajectory** (at ``z = (qD(t), qD'(t))``, the
    state of perfect tracking, with ``r = r(t)``) at evenly spaced instants, on the controller's
    model: in error coordinates it must be the decoupled form ``[[0, I], [-K1, -K2]]`` whose blocks
    have the requested poles, at every instant (computed torque decouples and linearizes exactly,
    whatever the configuration).  Decided on the matrix, whose entries are well conditioned, not on
    its eigenvalues (a repeated pole moves by the square root of a perturbation).  The same is
    evaluated on the true plant when it differs from the model, and the largest move of the poles
    is reported (evidence of what the mismatch does to the error dynamics; not part of the verdict).
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
        try:
            out[k] = np.linalg.solve(Ek.T, Edk.T).T
        except np.linalg.LinAlgError:  # a singular configuration: no task-error coordinates there
            out[k] = np.nan
    return out


def pole_move(got: np.ndarray, requested: np.ndarray) -> float:
    """Largest ``|p - p_requested|`` (1/s) over the pairing of ``got`` with ``requested`` that minimises the
    total distance (Hungarian assignment: a repeated pole is paired once per occurrence)."""
    from scipy.optimize import linear_sum_assignment

    cost = np.abs(np.asarray(got, dtype=complex)[:, None] - np.asarray(requested, dtype=complex)[None, :])
    rows, cols = linear_sum_assignment(cost)
    return float(np.max(cost[rows, cols])) if rows.size else 0.0


def _error_matrix(design: Any) -> np.ndarray:
    """The requested error dynamics in error coordinates ``(e, e')``: ``[[0, I], [-K1, -K2]]``, one
    decoupled block ``e_i'' + K2_i e_i' + K1_i e_i = 0`` per joint or task coordinate."""
    K1, K2 = (np.atleast_1d(np.asarray(design.gains[k], dtype=float)) for k in ("K1", "K2"))
    n = K1.size
    return np.block([[np.zeros((n, n)), np.eye(n)], [-np.diag(K1), -np.diag(K2)]])


def error_poles_check(spec: Any, design: Any, plant: Any = None) -> Check:
    """Check ``"error_poles"`` (see the module docstring).

    Decided on the matrices, not on their eigenvalues: at every instant the linearized error
    dynamics must equal the decoupled companion form ``[[0, I], [-K1, -K2]]`` of the gains to
    :data:`~designkit.verification.tolerances.ERROR_DYNAMICS_REL` (relative to its largest entry),
    and each block's characteristic polynomial ``s^2 + K2_i s + K1_i`` must be the requested pair's
    ``(s - p1)(s - p2)`` to ``POLE_REL`` (scaled coefficients).  Eigenvalues of repeated poles are
    ill-conditioned (a double pole moves by the square root of a perturbation), the matrices are
    not.  The pole moves reported (true plant, damped least squares) are eigenvalue distances after
    an optimal pairing (:func:`pole_move`).
    """
    from designkit.simulation.reference import reference_for
    from designkit.verification.tolerances import ERROR_DYNAMICS_REL

    n = design.plant.n_joints
    motion = design.motion
    law = design.linear_law
    requested = np.asarray(design.poles, dtype=complex)
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
    target = _error_matrix(design)
    big = float(np.max(np.abs(target))) or 1.0
    deviation = np.array([float(np.max(np.abs(Ak - target))) / big if np.all(np.isfinite(Ak)) else np.inf
                          for Ak in A])
    k_worst = int(np.argmax(deviation))
    worst = float(deviation[k_worst])
    pairs = requested.reshape(-1, 2)
    R_scale = float(np.max(np.abs(requested))) or 1.0
    coeff = max(float(np.max(np.abs(np.poly(pair)[1:] - np.array([target[n + i, n + i] * -1, -target[n + i, i]]))
                          / np.array([R_scale, R_scale**2]))) for i, pair in enumerate(pairs))
    moves = np.array([pole_move(np.linalg.eigvals(Ak), requested) if np.all(np.isfinite(Ak)) else np.inf
                      for Ak in A])
    ok = bool(worst <= ERROR_DYNAMICS_REL and coeff <= POLE_REL)
    space = "task-error dynamics" if motion is not None else "closed loop"
    cert: dict[str, Any] = {
        "instants": int(t.size), "horizon_s": float(t[-1]), "space": "task" if motion is not None else "joint",
        "requested_poles": [[p.real, p.imag] for p in requested],
        "largest_deviation_from_decoupled_form": worst, "worst_at_s": float(t[k_worst]),
        "tolerance": ERROR_DYNAMICS_REL, "characteristic_coefficient_error": coeff,
        "largest_eigenvalue_distance_1_per_s": float(np.max(moves)),
    }
    if ok:
        detail = (f"on the controller's model the {space} linearized at {t.size} instants along the reference is "
                  f"the decoupled form e'' + K2 e' + K1 e = 0 with the requested poles (largest deviation "
                  f"{worst:.2g} of its largest entry, t = {t[k_worst]:.3g} s; eigenvalues within "
                  f"{np.max(moves):.2g} 1/s)")
    elif not np.isfinite(worst):
        singular = t[~np.array([np.all(np.isfinite(Ak)) for Ak in A])]
        detail = (f"the {space} is not defined at {singular.size} of {t.size} instants along the path "
                  f"(first at t = {singular[0]:.3g} s): the task Jacobian is singular there (or the loop "
                  "is not finite), so the error dynamics cannot have the requested poles")
    else:
        detail = (f"the {space} leaves the decoupled form with the requested poles along the path: deviation "
                  f"{worst:.3g} of its largest entry (tolerance {ERROR_DYNAMICS_REL:g}) at t = {t[k_worst]:.3g} s, "
                  f"poles moved by up to {np.max(moves):.3g} 1/s")
    if plant is not None and plant is not design.plant:
        At = (_task_error_matrices(plant, law, motion, t, R) if motion is not None
              else _path_jacobians(plant, law, t, R, n))
        shifts = np.array([pole_move(np.linalg.eigvals(Ak), requested) if np.all(np.isfinite(Ak)) else np.inf
                           for Ak in At])
        k = int(np.argmax(shifts))
        cert["true_plant"] = {"largest_pole_move_1_per_s": float(shifts[k]), "at_s": float(t[k])}
        detail += (f"; on the true plant the model mismatch moves them by up to {shifts[k]:.3g} 1/s "
                   f"(t = {t[k]:.3g} s)")
    damping = motion.damping if motion is not None else None
    if damping:  # damped least squares trades the exact poles for bounded joint accelerations: evidence only
        k = int(np.argmax(moves))
        defined = np.array([bool(np.all(np.isfinite(Ak))) for Ak in A])
        unstable = [float(t[j]) for j, Ak in enumerate(A) if defined[j] and np.max(np.linalg.eigvals(Ak).real) > 0]
        k = int(np.argmax(np.where(defined, moves, -1.0))) if defined.any() else 0
        cert["damped_least_squares"] = {"damping": damping, "largest_pole_move_1_per_s": float(moves[k]),
                                        "at_s": float(t[k]), "unstable_instants_s": unstable}
        detail = (f"damped least squares (lambda = {damping:g}) moves the task-error poles by up to {moves[k]:.3g} 1/s "
                  f"along the path (t = {t[k]:.3g} s)"
                  + (f"; the frozen linearization has a pole in the right half plane at {len(unstable)} of {t.size} "
                     f"instants ({unstable[0]:.3g}-{unstable[-1]:.3g} s): the damping gives up the error dynamics "
                     "near the singularity, the simulation shows what that costs" if unstable else "")
                  + (f"; the task-error coordinates are undefined at {int((~defined).sum())} instants on the "
                     f"singularity (first at t = {t[~defined][0]:.3g} s)" if not defined.all() else "")
                  + " [informational]")
        return Check(name="error_poles", passed=True, target="reported (damped least squares)",
                     achieved=float(moves[k]), margin=None, unit="1/s", detail=detail, certificate=cert,
                     required=False)
    return Check(name="error_poles", passed=ok, target=f"decoupled requested error dynamics at every instant, to "
                 f"{ERROR_DYNAMICS_REL:g}", achieved=worst, margin=ERROR_DYNAMICS_REL - worst, unit="1 (relative)",
                 detail=detail, certificate=cert)


def tracking_bounds_check(spec: Any, design: Any, plant: Any, law: Any = None) -> Check:
    """Check ``"tracking_bounds"`` (see the module docstring); ``law`` the simulated law (default ``design.law``)."""
    from designkit.simulation.run import build
    from designkit.verification.robustness import box_from_uncertainty

    box = box_from_uncertainty(plant, spec.plant.uncertainty)
    thetas = np.vstack([box.vertices, box.random]) if box.samples else box.vertices
    simulator = build(spec, design, plant=plant, law=law, expected_runs=len(thetas))
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
            "envelope": np.max(np.abs(np.array([r.tracking_errors for r in runs])), axis=0),
            "peaks": peaks, "parameters": np.asarray(thetas, float), "parameter_names": tuple(box.names)}
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
