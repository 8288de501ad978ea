"""The notes' projection with hysteresis (applied after every integration step) and the excitation indicator on
parameter choices whose regressor columns are dependent."""

from __future__ import annotations

import numpy as np
import pytest

from designkit.families.adaptive_computed_torque.excitation import excitation
from designkit.families.adaptive_computed_torque.laws import Adaptation, adaptive_law
from designkit.models.robot_plant import zoo_plant


@pytest.mark.parametrize(("value", "expected"), [
    (3.0, 3.0),      # inside [2, 6]
    (1.96, 1.96),    # below l, but by less than delta = 0.05: left alone (hysteresis)
    (1.95, 2.0),     # l - delta: reset to l
    (1.0, 2.0),
    (6.04, 6.04),
    (6.05, 6.0),     # h + delta: reset to h
    (9.0, 6.0),
])
def test_projection_resets_only_beyond_delta(value, expected):
    plant = zoo_plant("planar2r")
    a = Adaptation(names=("m1", "m2"), initial=(5.0, 3.0), gain=(1.0, 1.0), K1=(100.0, 100.0), K2=(20.0, 20.0),
                   psi=(0.1, 0.1), bounds=((4.0, 10.0), (2.0, 6.0)), delta=0.05)
    law = adaptive_law(plant, a)
    out = np.asarray(law.project([7.0, value])).ravel()
    assert out[0] == 7.0
    assert out[1] == pytest.approx(expected, abs=0)


def _sine(n: int, amplitude: np.ndarray, q0: np.ndarray, t: np.ndarray) -> np.ndarray:
    w = 2 * np.pi * 0.5
    s, c = np.sin(w * t)[:, None], np.cos(w * t)[:, None]
    return np.stack([q0 + amplitude * s, amplitude * w * c, -amplitude * w * w * s], axis=2)


def test_dependent_columns_are_not_exciting_whatever_the_trajectory():
    """The PUMA's wrist frames share an origin: the columns of m4, m5, m6 are identical, so no trajectory
    separates them (indicator ~ 0); m2 with the rotor inertias is separable on the same sine."""
    plant = zoo_plant("puma560", motor_inertia=True)
    t = np.linspace(0.0, 10.0, 1001)
    q0 = np.array([0.0, 0.785, -3.1416, 0.0, 0.785, 0.0])
    ref = _sine(6, np.array([0.8, 0.5, -0.7, 0.5, 0.5, 0.5]), q0, t)
    bad = excitation(plant, ["m4", "m5", "m6"], [100.0] * 6, [1.0] * 3, t, ref)
    good = excitation(plant, ["m2", "Ia1", "Ia2", "Ia3"], [100.0] * 6, [1.0] * 4, t, ref)
    assert bad.rate < 1e-9 and bad.alpha_min < 1e-9 * good.alpha_min
    assert good.rate > 1e-3 and good.alpha_min > 1.0
    assert not bad.exciting
