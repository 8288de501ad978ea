"""Every verification check of a design, in report order.

1. ``pole_placement``  -- closed-loop poles/zeros equal the requested ones (python-control);
2. ``routh_hurwitz``   -- Routh array of the nominal characteristic polynomial, with the notes'
   gain conditions and their margins;
3. ``lyapunov``        -- quadratic Lyapunov function of the nominal closed loop (cvxpy LMI,
   re-checked with NumPy);
4. ``robust_vertices``, ``robust_grid``, ``common_lyapunov`` -- only when the spec gives
   ``plant.uncertainty``;
5. time-domain requirements (``overshoot``, ``settling_time``, ``rise_time``,
   ``steady_state_error``, ``max_control``) -- only when a simulation was run and the spec has
   requirements; measured on the :class:`~designkit.simulation.result.SimulationResult` fields only.
"""

from __future__ import annotations

from typing import Any

from designkit.verification.check import Check
from designkit.verification.hurwitz_conditions import routh_hurwitz_design
from designkit.verification.lyapunov import lyapunov_lmi
from designkit.verification.pole_zero import pole_placement
from designkit.verification.robustness import robustness_checks
from designkit.verification.time_domain import time_domain_checks


def run_checks(spec: Any, design: Any, family: Any, simulation: Any = None) -> tuple[Check, ...]:
    """Run the checks of the module docstring.

    Parameters
    ----------
    spec : Spec
        Validated spec (``plant.uncertainty`` and ``requirements`` are read).
    design : Design
        The synthesised controller.
    family : ControllerFamily
        Its family (characteristic polynomial and closed loop on other plants).
    simulation : SimulationResult or None
        Closed-loop run for the time-domain checks.

    Returns
    -------
    tuple of Check
    """
    checks: list[Check] = [
        pole_placement(design),
        routh_hurwitz_design(design, family),
        lyapunov_lmi(design.closed_loop.A),
    ]
    if spec.plant.uncertainty is not None:
        checks.extend(robustness_checks(design, family, spec.plant.uncertainty))
    if simulation is not None and spec.requirements is not None:
        checks.extend(time_domain_checks(spec.requirements, simulation))
    return tuple(checks)
