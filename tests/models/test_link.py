"""Simplified link model: Km = 1/f, tau = D_ii/f (and not the notes' misprinted alpha/D_ii)."""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest

from designkit.errors import ModelError
from designkit.models.link import LinkParameters, LinkPlant, link_ode, link_range, simplified_link
from designkit.models.robots import robot
from tests.models.support import TOL_EXACT, scaled_error


@pytest.mark.parametrize(("field", "value"), [("Km", 0.0), ("Km", -1.0), ("tau", math.nan), ("tau", math.inf),
                                              ("tau", "0.5"), ("Km", True)])
def test_link_plant_validation_names_the_field(field, value):
    values = {"Km": 2.0, "tau": 0.5, field: value}
    with pytest.raises(ModelError) as info:
        LinkPlant(**values)
    assert info.value.path == field


def test_link_ode_is_named_and_matches_the_notes():
    f = link_ode(LinkPlant(Km=2.0, tau=0.5))
    assert f.name() == "link" and f.name_in() == ["x", "u", "xi"] and f.name_out() == ["xdot"]
    xdot = np.array(f([0.3, 1.5], 0.7, 0.1)).ravel()
    assert scaled_error(xdot, [1.5, -1.5 / 0.5 + 2.0 / 0.5 * 0.8]) < 1e-15


def test_simplified_link_of_a_pendulum_without_gravity_is_exact():
    """Without gravity the one-link arm *is* D q'' + f q' = u: its simulation equals the link model's."""
    arm = robot("onelink", g=0.0, friction=True)
    link = simplified_link(arm, 0, [0.0])
    f = arm.description.links[0].viscous
    assert isinstance(link, LinkPlant) and isinstance(link, LinkParameters)
    assert link.Km == pytest.approx(1.0 / f, rel=1e-15)
    assert link.tau == pytest.approx(link.inertia / f, rel=1e-15)
    # the notes' printed tau = alpha/D_ii has units 1/s and a different value
    assert not math.isclose(link.tau, f / link.inertia, rel_tol=1e-3)

    x, u = ca.SX.sym("x", 2), 0.8
    full = ca.vertcat(x[1], arm.functions["forward_dynamics"](x[0], x[1], u))
    reduced = link_ode(link)(x, u, 0.0)
    sim_full = ca.integrator("full", "cvodes", {"x": x, "ode": full}, 0.0, [0.5, 1.0, 2.0])
    sim_reduced = ca.integrator("reduced", "cvodes", {"x": x, "ode": reduced}, 0.0, [0.5, 1.0, 2.0])
    xf = np.array(sim_full(x0=[0.0, 0.0])["xf"])
    xr = np.array(sim_reduced(x0=[0.0, 0.0])["xf"])
    assert scaled_error(xf, xr) < 1e-6
    # steady speed is Km u
    assert xr[1, -1] == pytest.approx(link.Km * u * (1 - math.exp(-2.0 / link.tau)), rel=1e-5)


def test_simplified_link_uses_the_configuration_dependent_inertia():
    arm = robot("planar2r", motor_inertia=True)
    q = np.array([0.3, 1.1])
    link = simplified_link(arm, 0, q, damping=0.5)
    f = arm.description.links[0].viscous + 0.5
    assert link.damping == f
    assert link.inertia == arm.mass_matrix(q)[0, 0]
    assert link.tau == pytest.approx(arm.mass_matrix(q)[0, 0] / f, rel=1e-15)
    with pytest.raises(ModelError, match="i"):
        simplified_link(arm, 2, q)
    with pytest.raises(ModelError, match="viscous"):
        simplified_link(robot("planar2r", f1=0.0), 0, q)


def test_link_range_of_the_two_link_arm_matches_the_closed_form():
    # D11 = c + m2 d1 d2 cos(q2): largest at q2 = 0, smallest at the bound farthest from 0
    arm = robot("planar2r")
    low, high = np.array([-1.0, -0.4]), np.array([1.0, 2.5])
    r = link_range(arm, 0, low, high, samples=4)  # coarse grid: the bounded search must finish the job
    from designkit.models.robots.planar2r import DEFAULTS as P

    constant = P["m1"] * P["d1"] ** 2 / 4 + P["m2"] * (P["d1"] ** 2 + P["d2"] ** 2 / 4) + P["I1"] + P["I2"]
    coupling = P["m2"] * P["d1"] * P["d2"]
    f = P["f1"]
    assert r.Km_min == r.Km_max == pytest.approx(1 / f)
    assert r.tau_max == pytest.approx((constant + coupling) / f, rel=1e-9)
    assert r.tau_min == pytest.approx((constant + coupling * math.cos(2.5)) / f, rel=1e-9)
    assert r.q_at_max[1] == pytest.approx(0.0, abs=1e-5)
    assert r.q_at_min[1] == pytest.approx(2.5)
    # the last joint's inertia does not depend on q
    last = link_range(arm, 1, low, high)
    assert last.tau_min == pytest.approx(last.tau_max, rel=1e-12)


def test_link_range_bounds_every_sampled_configuration():
    arm = robot("puma560")
    qlim = np.array([link.qlim for link in arm.description.links])
    r = link_range(arm, 1, qlim[:, 0], qlim[:, 1], samples=5)
    samples = np.random.default_rng(30).uniform(qlim[:, 0], qlim[:, 1], (2000, 6))
    d22 = arm.mass_matrix(samples)[:, 1, 1]
    f = arm.description.links[1].viscous
    assert r.tau_min * f <= d22.min() + TOL_EXACT and d22.max() <= r.tau_max * f + TOL_EXACT
    assert arm.mass_matrix(r.q_at_min)[1, 1] == pytest.approx(r.inertia_min, rel=1e-12)
    assert arm.mass_matrix(r.q_at_max)[1, 1] == pytest.approx(r.inertia_max, rel=1e-12)
    assert np.all(r.q_at_min >= qlim[:, 0]) and np.all(r.q_at_max <= qlim[:, 1])


def test_link_range_validates_its_box():
    arm = robot("planar2r")
    with pytest.raises(ModelError):
        link_range(arm, 0, [1.0, 0.0], [0.0, 1.0])
    with pytest.raises(ModelError):
        link_range(arm, 0, [0.0], [1.0])
