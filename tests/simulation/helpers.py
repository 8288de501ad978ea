"""Shared scenarios of the simulation tests (tolerances: tests/tolerances.py)."""

from __future__ import annotations

from typing import Any

import numpy as np

from designkit.families import synthesize
from designkit.models.link import LinkPlant
from designkit.schema.spec import Spec
from designkit.synthesis.design import Design
from tests.tolerances import TOL  # noqa: F401  (re-exported for the simulation tests)

POSSPEED = {"kind": "pid_servo", "poles": [-4, -5, -20], "zero": -3}
TRACKING = {"kind": "pid_tracking", "poles": [-10, -12, -15]}
NOMINAL = {"kind": "link", "Km": 2.0, "tau": 0.5}


def make_spec(controller: dict[str, Any] | None = None, **simulation: Any) -> Spec:
    """A spec on the POSSPEED link (Km 2, tau 0.5) with the given controller and simulation keys."""
    return Spec.model_validate({
        "name": "sim-test", "plant": NOMINAL, "controller": controller or POSSPEED, "simulation": simulation,
    })


def design_of(spec: Spec) -> Design:
    return synthesize(spec)


def scaled_error(x: np.ndarray, ref: np.ndarray) -> float:
    return float(np.max(np.abs(np.asarray(x) - ref) / (1.0 + np.abs(ref))))


def overshoot(x1: np.ndarray, target: float) -> float:
    """Peak overshoot in % of the target."""
    return 100.0 * max(0.0, (np.max(x1) - target) / target)


OTHER_PLANT = LinkPlant(Km=2.4, tau=0.6)
