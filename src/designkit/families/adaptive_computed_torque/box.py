"""Which arms a parameter box (``plant.uncertainty``) may hold for the adaptive computed torque.

The law takes every regressor parameter it does not adapt as known, at the arm's true value, and its ideal
accelerometer reads the arm's own acceleration: the unknowns it copes with are the adapted parameters only.  So
its run over the box (the ``box_runs`` check) designs for each arm of the box (``Family.box_design = "each"``:
the same initial estimates and gains, the arm's known parameters), and a box is refused when an arm of it moves
a parameter the law does not adapt (a planar link's mass moves its first moment ``mcx`` and its inertia ``Izz``):
the law would be told what it is meant not to know.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from designkit.errors import SpecError
from designkit.families.adaptive_computed_torque.laws import _torque_of_parameters, true_parameters

__all__ = ["check_box"]

STATES = 8
"""Seeded random states at which a parameter's effect on the inverse dynamics is looked for."""


def _moves_torque(tau_of: Any, p: np.ndarray, changed: np.ndarray, n: int) -> bool:
    """Whether the regressor vector ``changed`` instead of ``p`` changes the arm's inverse dynamics at seeded random
    states (a parameter no motion of the arm sees, such as a planar link's ``Ixx``, does not)."""
    rng = np.random.default_rng(0)
    for _ in range(STATES):
        q, qd, qdd = (rng.uniform(-2.0, 2.0, n) for _ in range(3))
        a = np.asarray(tau_of(q, qd, qdd, p), dtype=float)
        b = np.asarray(tau_of(q, qd, qdd, changed), dtype=float)
        if np.max(np.abs(a - b)) > 1e-9 * max(1.0, float(np.max(np.abs(a)))):
            return True
    return False


def check_box(spec: Any, plant: Any, adapted: tuple[str, ...]) -> None:
    """Refuse (:class:`SpecError` at ``plant.uncertainty.<name>``) a box whose ends move a regressor parameter the
    law does not adapt and the arm's dynamics see."""
    unc = getattr(spec.plant, "uncertainty", None)
    if unc is None:
        return
    names = list(plant.robot.parameter_names)
    p0 = true_parameters(plant)
    tau_of = _torque_of_parameters(plant)
    for name, ends in unc.intervals.items():
        moved: list[str] = []
        for end in ends:
            p = true_parameters(plant.with_params(**{name: float(end)}))
            for i, x in enumerate(names):
                if x in adapted or x in moved or np.isclose(p[i], p0[i], rtol=1e-12, atol=0.0):
                    continue
                changed = p0.copy()
                changed[i] = p[i]
                if _moves_torque(tau_of, p0, changed, plant.n_joints):
                    moved.append(x)
        if moved:
            raise SpecError(f"plant.uncertainty.{name}",
                            f"over its interval the arm's {', '.join(moved)} change, which the adaptive computed "
                            f"torque takes as known (it adapts {', '.join(adapted)}): adapt them too "
                            "(controller.adapt), or leave the parameter out of the box")
