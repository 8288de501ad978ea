"""A task-space path near a singular configuration of the task Jacobian (``singularity`` check): where, the
joint that sets the smallest singular value, and the fixes (damped least squares with the damping that
bounds the resolution's gain, or moving the path).

Entry point: :func:`explain` (cause and fix, from the check's certificate).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from designkit.display.numbers import at_time, fmt_number

__all__ = ["damping_for_condition", "explain"]


def damping_for_condition(sigma_min: float, condition: float, max_condition: float) -> float:
    """The damped-least-squares ``lambda`` (units of ``J``'s singular values) whose gain bound ``1/(2 lambda)``
    equals the ``1/sigma_min`` the exact inverse has at the allowed condition number.

    At the worst point ``sigma_max = condition * sigma_min``; with the condition number at
    ``max_condition`` the smallest singular value would be ``sigma_max / max_condition``, so
    ``lambda = sigma_max / (2 max_condition)`` bounds the resolution's gain
    ``max sigma / (sigma^2 + lambda^2) = 1/(2 lambda)`` by that amplification.

    Parameters
    ----------
    sigma_min : float
        Smallest singular value of ``J`` at the worst point (``J`` mixes m/rad and 1 rows: no single unit).
    condition : float
        Condition number of ``J`` there.
    max_condition : float
        The design's limit on the condition number.

    Returns
    -------
    float
        ``lambda`` (same scale as ``J``'s singular values).
    """
    return condition * sigma_min / (2.0 * max_condition)


def _singular_joint(result: Any, q: np.ndarray) -> tuple[int, float] | None:
    """The joint whose motion raises ``1/kappa`` of ``J`` fastest at ``q``, and ``d(1/kappa)/dq`` (1/rad), on the
    task functions of the design's motion (:class:`designkit.simulation.motion.TaskMotion`); None without one."""
    motion = result.design.motion
    if motion is None:
        return None
    import casadi as ca

    from designkit.models.task import task_functions

    model = result.design.plant
    try:
        fns = task_functions(model.robot, model.model_parameters(), motion.space)
    except Exception:  # noqa: BLE001 -- no task functions: no joint named
        return None

    def inv_kappa(x: np.ndarray) -> float:
        s = np.linalg.svd(np.asarray(fns.jacobian(ca.DM(x)), dtype=float), compute_uv=False)
        return float(s[-1] / s[0])

    h = 1e-6
    grad = np.array([(inv_kappa(q + h * e) - inv_kappa(q - h * e)) / (2 * h) for e in np.eye(q.size)])
    j = int(np.argmax(np.abs(grad)))
    return j, float(grad[j])


def explain(result: Any, check: Any) -> tuple[str, str] | None:
    """Cause and fix of a failing ``singularity`` check, from its certificate (None when the certificate lacks the
    worst point; the fix ``""`` when the design already resolves with damped least squares)."""
    cert = check.certificate if hasattr(check.certificate, "get") else {}
    need = ("worst_condition", "sigma_min_at_worst", "max_condition_allowed", "worst_configuration", "worst_at_s")
    if any(cert.get(k) is None for k in need):
        return None
    kappa, s_min = float(cert["worst_condition"]), float(cert["sigma_min_at_worst"])
    limit = float(cert["max_condition_allowed"])
    q = np.asarray(cert["worst_configuration"], dtype=float)
    config = "q = (" + ", ".join(fmt_number(v if abs(v) > 1e-12 else 0.0, 3) for v in q) + ") rad"
    stretch = cert.get("near_singular_interval_s")
    cause = (f"the path passes near a singular configuration of J: condition number {fmt_number(kappa)} at "
             f"{at_time(float(cert['worst_at_s']))} ({config}), {fmt_number(kappa / limit, 3)} times the "
             f"{fmt_number(limit)} allowed; σ_min = {fmt_number(s_min)}, so J⁻¹ amplifies task accelerations by "
             f"1/σ_min = {fmt_number(1 / s_min)} there")
    if stretch:
        share = cert.get("near_singular_fraction")
        cause += f" (above the limit over {stretch}" + (
            f", {fmt_number(100 * float(share), 3)} % of the path)" if share is not None else ")")
    joint = _singular_joint(result, q)
    move = ""
    if joint is not None and joint[1] != 0:
        j, grad = joint
        cause += (f"; the smallest singular value is set by joint {j + 1} (q{j + 1} = {fmt_number(q[j], 3)} rad; "
                  f"d(1/κ)/dq{j + 1} = {fmt_number(grad, 3)} 1/rad, the largest of the joints)")
        step = (1.0 / limit - 1.0 / kappa) / abs(grad)
        target = q[j] + math.copysign(step, grad)
        move = (f"; or move the path away from it: to first order the condition number falls to {fmt_number(limit)} "
                f"about {fmt_number(step, 3)} rad further along joint {j + 1} (q{j + 1} ≈ {fmt_number(target, 3)} "
                "rad at that point)")
    if cert.get("damping") is not None:
        return cause, ""
    lam = damping_for_condition(s_min, kappa, limit)
    shown = float(f"{lam * (1 + 5e-4):.3g}")  # rounded up: still within the bound
    gain = s_min**2 / (s_min**2 + shown**2)
    fix = (f"resolve with damped least squares (controller.damped_least_squares: {{damping: {fmt_number(shown, 3)}}}): "
           f"λ ≥ σ_max/(2 κ_max) = {fmt_number(kappa * s_min)}/(2 × {fmt_number(limit)}) = {fmt_number(lam)} "
           f"bounds "
           f"the resolution's gain by 1/(2λ) = {fmt_number(1 / (2 * shown))}, what J⁻¹ has at condition number "
           f"{fmt_number(limit)}, instead of {fmt_number(1 / s_min)}; the price is a task gain of "
           f"{fmt_number(gain, 3)} along the weakest direction at the worst point") + move
    return cause, fix
