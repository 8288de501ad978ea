"""Check ``singularity``: how close a task-space design's path comes to a singular configuration.

Along the joint path that tracks the reference exactly (the path of the design's motion,
:class:`designkit.simulation.motion.TaskMotion`: inverse kinematics at the instants it was computed
at, :func:`designkit.models.task.joint_path`), the singular values ``sigma`` of the task Jacobian
``J`` give its condition number ``kappa = sigma_max/sigma_min`` and Yoshikawa's manipulability
``w = prod sigma``.  The path is near-singular where ``kappa`` exceeds the motion's
``max_condition``.

Verdict.  With the exact inverse (``qdd* = J^-1 (a* - Jdot qd)``: the motion's ``damping`` is None),
a near-singular point FAILS: the resolved joint accelerations grow as ``1/sigma_min`` there
(reported: ``1/sigma_min`` at the worst point).  With damped least squares
``(J^T J + lambda^2 I)^-1 J^T`` (``lambda`` the motion's ``damping``), the resolution's gain is
at most ``max_sigma sigma/(sigma^2 + lambda^2) = 1/(2 lambda)`` whatever the configuration, so the
check passes and reports what the damping costs: the task-space gain
``sigma_min^2/(sigma_min^2 + lambda^2)`` along the worst direction at the worst point, and the
largest distortion ``lambda^2/(sigma_min^2 + lambda^2)`` over the path (the fraction of a task
acceleration lost along the weakest direction).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from designkit.verification.check import Check

__all__ = ["singularity_check"]


def singularity_check(design: Any, motion: Any) -> Check:
    """Check ``"singularity"`` (see the module docstring) of ``design`` along ``motion.path``, with the motion's
    resolution (``damping``) and limit (``max_condition``)."""
    path = motion.path
    limit = float(motion.max_condition)
    damping = motion.damping
    k = path.worst
    kappa = float(path.condition[k])
    sigma_min = float(path.sigma[k, -1])
    near = path.condition > limit
    t = path.time
    where = (f"t = {t[k]:.4g} s (q = [{', '.join(f'{v:.3g}' for v in path.q[k])}])")
    stretch = (f"{t[near][0]:.4g}-{t[near][-1]:.4g} s" if near.any() else "")
    cert: dict[str, Any] = {
        "samples": int(t.size), "max_condition_allowed": limit, "worst_condition": kappa, "worst_at_s": float(t[k]),
        "worst_configuration": path.q[k].tolist(), "sigma_min_at_worst": sigma_min,
        "smallest_manipulability": float(np.min(path.manipulability)),
        "manipulability_at_start": float(path.manipulability[0]),
        "near_singular_fraction": float(np.mean(near)), "near_singular_interval_s": stretch or None,
        "coordinates": list(motion.space.names), "damping": damping,
    }
    data = {"time": t, "condition": path.condition, "manipulability": path.manipulability, "limit": limit}
    words = (f"condition number of J up to {kappa:.4g} at {where}; manipulability down to "
             f"{cert['smallest_manipulability']:.3g} (from {cert['manipulability_at_start']:.3g} at the start)")
    if damping is None:
        ok = not near.any()
        if ok:
            detail = f"the path stays away from singular configurations: {words}, within {limit:g}"
        else:
            detail = (f"the path comes near a singular configuration ({stretch}): {words}, above {limit:g}; the exact "
                      f"inverse amplifies task accelerations by 1/sigma_min = {1 / max(sigma_min, 1e-300):.3g} "
                      "there: use damped_least_squares or another path")
        return Check(name="singularity", passed=ok, target=f"condition number <= {limit:g} along the path",
                     achieved=kappa, margin=limit - kappa, unit="1", detail=detail, certificate=cert, data=data)
    lam2 = float(damping) ** 2
    gain = sigma_min**2 / (sigma_min**2 + lam2)
    loss = float(np.max(lam2 / (path.sigma[:, -1] ** 2 + lam2)))
    cert.update({"joint_acceleration_gain_bound": 1.0 / (2.0 * float(damping)), "task_gain_at_worst": gain,
                 "largest_distortion": loss})
    detail = (f"damped least squares (lambda = {damping:g}) bounds the resolution's gain by 1/(2 lambda) = "
              f"{1 / (2 * damping):.4g}; {words}"
              + (f" (near-singular {stretch})" if near.any() else "")
              + f"; task gain along the weakest direction there {gain:.3g}, largest loss over the path {loss:.3g}")
    return Check(name="singularity", passed=True, target="bounded resolution (damped least squares)",
                 achieved=kappa, margin=None, unit="1", detail=detail, certificate=cert, data=data, required=True)
