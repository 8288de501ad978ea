"""Inertial parameters about the link-frame origin: the parallel-axis theorem against point-mass clouds."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from designkit.models.description import LinkDescription
from designkit.models.inertial_parameters import INERTIAL_NAMES, link_inertial_parameters
from tests.models.support import scaled_error


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**16), count=st.integers(1, 6))
def test_parallel_axis_parameters_match_a_point_mass_cloud(seed, count):
    rng = np.random.default_rng(seed)
    masses = rng.uniform(0.1, 2.0, count)
    points = rng.uniform(-1, 1, (count, 3))
    m = masses.sum()
    c = masses @ points / m

    def tensor(offset: np.ndarray) -> np.ndarray:
        r = points - offset
        return sum(mk * (rk @ rk * np.eye(3) - np.outer(rk, rk)) for mk, rk in zip(masses, r, strict=True))

    Ic = tensor(c)
    link = LinkDescription(mass=m, com=tuple(c), inertia=(Ic[0, 0], Ic[1, 1], Ic[2, 2], Ic[0, 1], Ic[0, 2], Ic[1, 2]))
    p = np.array(link_inertial_parameters(link), dtype=float)
    Io = tensor(np.zeros(3))
    expected = [m, *(m * c), Io[0, 0], Io[0, 1], Io[0, 2], Io[1, 1], Io[1, 2], Io[2, 2]]
    assert scaled_error(p, expected) < 1e-12


def test_parameters_are_named_in_the_order_they_are_returned():
    link = LinkDescription(mass=2.0, com=(0.1, 0.0, 0.0), inertia=(0.1, 0.2, 0.3, 0.0, 0.0, 0.0))
    values = dict(zip(INERTIAL_NAMES, link_inertial_parameters(link), strict=True))
    assert values["m"] == 2.0 and values["mcx"] == 0.2 and values["mcy"] == 0.0
    assert values["Iyy"] == 0.2 + 2.0 * 0.1**2 and values["Ixx"] == 0.1  # parallel axis along x only
