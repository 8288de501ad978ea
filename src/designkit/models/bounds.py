"""Proven bounds of a robot's model functions over boxes of configurations and velocities.

:func:`model_bound` encloses one entry of a model function -- the inertia matrix ``D(q)``, the
gravity torques ``g(q)``, the Coriolis and centrifugal torques ``C(q, q') q'`` for bounded
velocities, the inverse dynamics, or any other function in ``Robot.functions`` -- over a box, with
:func:`designkit.bounds.enclose` (Arb ball arithmetic, the mean-value form, branch and bound): the
result's ``[lower, upper]`` holds for every point of the box, and each end has a witness.

**Joints an inertia entry cannot depend on.**  For a serial chain on a fixed base, ``D_ij`` depends
only on ``q_(m+1), ..., q_n`` with ``m = min(i, j)`` (1-based): ``D_ij = S_i' I^c_k S_j`` (``k =
max(i, j)``) in the composite-rigid-body algorithm, and the composite inertia ``I^c_k`` of links
``k..n`` and the axes ``S_i``, ``S_j`` keep their relative pose when joints ``1..m`` move the whole
subchain (Featherstone, *Rigid Body Dynamics Algorithms*, 2008, sec. 6.2).  The expression graph does
not show this -- it depends on every joint through the rotations, and the cancellation is exact only
in real arithmetic -- so :func:`model_bound` holds those joints at the middle of their side instead of
letting the enclosure widen over them; a test checks the independence numerically on every zoo robot.
For the same reason the whole of ``D(q)`` and the Coriolis and centrifugal terms (``C(q, q')``, its
Christoffel symbols, ``C(q, q') q'``), which are derivatives of ``D``, do not depend on joint 1.

:func:`perturbation_enclosure` (:mod:`designkit.models.perturbation`, re-exported here) bounds the perturbation
each joint's decentralized model leaves over a box of configurations, velocities, accelerations and parameters.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from designkit import arguments
from designkit.errors import ModelError
from designkit.models.perturbation import PerturbationEnclosure, _side, perturbation_enclosure

__all__ = ["QUANTITIES", "PerturbationEnclosure", "model_bound", "perturbation_enclosure"]

QUANTITIES = ("mass_matrix", "gravity_torque", "coriolis_torque", "inverse_dynamics", "kinetic_energy",
              "potential_energy", "friction_torque")
"""Model functions :func:`model_bound` is documented for (any name in ``Robot.functions`` is accepted)."""


def _function(robot: Any, quantity: str) -> ca.Function:
    if quantity == "coriolis_torque":
        c = robot.functions["coriolis_matrix"]
        ins = [ca.SX.sym(c.name_in(i), c.sparsity_in(i)) for i in range(c.n_in())]
        return ca.Function("coriolis_torque", ins, [ca.mtimes(c(*ins), ins[1])], [c.name_in(i) for i in
                                                                                   range(c.n_in())], ["tau_c"])
    try:
        return robot.functions[quantity]
    except KeyError:
        raise ModelError("quantity", f"unknown model function {quantity!r}; known: "
                         f"{sorted([*robot.functions, 'coriolis_torque'])}") from None


def _independent_joints(quantity: str, index: Any) -> int:
    """How many leading joints the entry cannot depend on (module docstring): held fixed."""
    if quantity in ("coriolis_torque", "coriolis_matrix", "christoffel"):
        return 1
    if quantity == "mass_matrix" and index is not None:
        try:
            rc = (int(index), int(index)) if not isinstance(index, tuple | list) else (int(index[0]), int(index[1]))
        except (TypeError, ValueError, IndexError):
            return 0  # enclose names the bad index
        return max(min(rc) + 1, 1)
    return 1 if quantity == "mass_matrix" else 0


def model_bound(robot: Any, quantity: str, index: Any = None, *, q: Any = None, qd: Any = None, qdd: Any = None,
                tau: Any = None, p: Any = None, rel_tol: float = 1e-3, abs_tol: float = 0.0,
                max_boxes: int | None = None, strict: bool = True,
                thresholds: tuple[float | None, float | None] = (None, None)) -> Any:
    """The proven range of one entry of a robot's model function over a box.

    Parameters
    ----------
    robot : Robot
    quantity : str
        ``"mass_matrix"`` (kg*m^2, kg), ``"gravity_torque"``, ``"coriolis_torque"`` (``C(q, q') q'``),
        ``"inverse_dynamics"`` (N*m or N per joint), ``"kinetic_energy"``, ``"potential_energy"`` (J), or any
        other name in ``robot.functions``.
    index : int or (int, int), optional
        0-based entry of the output (``(i, i)`` for ``D_ii``).
    q, qd, qdd, tau : (low, high) or value, optional
        The box of each input the function takes (rad or m; rad/s or m/s; rad/s^2 or m/s^2; N*m or N),
        one value or one per joint per side; a single value holds the input fixed.
    p : array_like, optional
        Values of a symbolic robot's parameters (held fixed).
    rel_tol, abs_tol, max_boxes, strict, thresholds
        As :func:`designkit.bounds.enclose`.

    Returns
    -------
    designkit.bounds.Enclosure

    Examples
    --------
    >>> import designkit as dk
    >>> arm = dk.robot("planar2r")
    >>> e = model_bound(arm, "mass_matrix", (0, 0), q=([-3.14, -1.0], [3.14, 1.0]), rel_tol=1e-6)
    >>> bool(e.lower <= arm.mass_matrix([0.0, 1.0])[0, 0] <= e.upper)
    True
    """
    from designkit.bounds import MAX_BOXES, enclose
    from designkit.models.robot import Robot

    arguments.instance(robot, "robot", Robot, "a Robot (dk.robot, dk.robot_from_dh, dk.robot_from_urdf)",
                       error=ModelError)
    f = _function(robot, arguments.text(quantity, "quantity", error=ModelError))
    n = robot.n
    given = {"q": q, "qd": qd, "qdd": qdd, "tau": tau}
    box: dict[str, Any] = {}
    for i in range(f.n_in()):
        name = f.name_in(i)
        if name in given:
            if given[name] is None:
                raise ModelError(name, f"{quantity} depends on {name}: give its box (low, high)")
            box[name] = _side(given[name], n, name)
        elif f.nnz_in(i):
            if p is None:
                raise ModelError("p", f"{quantity} takes the robot's parameters {name!r}: give their values")
            box[name] = np.asarray(p, dtype=float).reshape(-1)
    extra = [k for k, v in given.items() if v is not None and k not in box]
    if extra:
        raise ModelError(extra[0], f"{quantity} does not take {extra[0]} (its inputs: "
                         f"{[f.name_in(i) for i in range(f.n_in())]})")
    held = _independent_joints(quantity, index)
    if held and "q" in box:
        lo, hi = (side.copy() for side in box["q"])
        lo[:held] = hi[:held] = 0.5 * (lo[:held] + hi[:held])  # any value: the witness stays in the box
        box["q"] = (lo, hi)
    return enclose(f, box, index=index, rel_tol=rel_tol, abs_tol=abs_tol,
                   max_boxes=MAX_BOXES if max_boxes is None else max_boxes, strict=strict, thresholds=thresholds)
