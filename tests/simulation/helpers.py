"""Shared scenarios and the one tolerance table of the simulation tests."""

from __future__ import annotations

from typing import Any

import numpy as np

from designkit.families import synthesize
from designkit.models.link import LinkPlant
from designkit.spec.schema import Spec
from designkit.synthesis.design import Design

# Scaled error (x - ref) / (1 + |ref|) bounds.
TOL = {
    "rk4_vs_exact": 1e-7,  # RK4 at dt |p|max = 0.02..0.05 against an exact linear solution
    "rk4_vs_foh": 1e-6,  # against python-control with first-order-hold inputs on a fine grid
    "exact": 0.0,  # same arithmetic, must be bit-identical
    "settled": 1e-4,  # a transient that has decayed by > 10 time constants
}

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
