"""Proven bounds of model functions (designkit.models.bounds): the joints an entry cannot depend on, closed forms.

Independent routes: the model's own numeric functions at random configurations (for the independence the
module relies on), the two-link arm's Coriolis and gravity torques in textbook closed form (Spong, Hutchinson &
Vidyasagar, *Robot Modeling and Control*, sec. 7.4) maximised analytically over the box, and random samples.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import designkit as dk
from designkit.errors import ModelError
from designkit.models.bounds import model_bound
from designkit.models.robot_plant import zoo_plant

H = 3.0 * 0.5 * 0.2  # m2 l1 lc2 of the zoo's planar2r (its description)


@pytest.mark.parametrize("name", ["planar2r", "puma560", "scara"])
def test_inertia_entries_do_not_depend_on_the_joints_before_them(name):
    """D_ij is unchanged when joints 1..min(i, j) move (what model_bound holds fixed), and the Coriolis torque
    when joint 1 moves."""
    plant = zoo_plant(name)
    arm, p = plant.robot, plant.model_parameters()
    rng = np.random.default_rng(5)
    q = rng.uniform(-2, 2, size=(20, arm.n))
    qd = rng.uniform(-2, 2, size=(20, arm.n))
    D = arm.mass_matrix(q, p=p)
    C = np.einsum("kij,kj->ki", arm.coriolis_matrix(q, qd, p=p), qd)
    for m in range(arm.n):
        moved = q.copy()
        moved[:, :m + 1] = rng.uniform(-3, 3, size=(20, m + 1))
        D2 = arm.mass_matrix(moved, p=p)
        block = np.s_[:, m:, m:]  # entries with min(i, j) >= m
        assert np.allclose(D2[block], D[block], rtol=1e-12, atol=1e-12 * np.abs(D).max())
    moved = q.copy()
    moved[:, 0] = rng.uniform(-3, 3, size=20)
    C2 = np.einsum("kij,kj->ki", arm.coriolis_matrix(moved, qd, p=p), qd)
    assert np.allclose(C2, C, rtol=1e-11, atol=1e-11 * np.abs(C).max())


def test_two_link_coriolis_torque_against_its_closed_form_maximum():
    """tau_c1 = -h sin q2 (2 q1' q2' + q2'^2): over q2 in [0.2, 1.2] and |q'| <= 2 the quadratic form takes
    [-4, 12] (at the box's corners), so the range is h [-12 sin 1.2, 4 sin 1.2]."""
    arm = dk.robot("planar2r")
    e = model_bound(arm, "coriolis_torque", 0, q=([0.0, 0.2], [0.0, 1.2]), qd=(-2.0, 2.0), rel_tol=1e-6)
    lo, hi = -12 * H * math.sin(1.2), 4 * H * math.sin(1.2)
    assert e.lower <= lo and e.upper >= hi
    assert e.lower == pytest.approx(lo, rel=2e-6) and e.upper == pytest.approx(hi, rel=2e-6)
    q, qd = e.argmin["q"], e.argmin["qd"]
    assert -H * math.sin(q[1]) * (2 * qd[0] * qd[1] + qd[1] ** 2) == pytest.approx(e.min_value, rel=1e-12)


def test_two_link_gravity_torque_bounded_over_a_box():
    """g_2 = m2 lc2 g0 cos(q1 + q2) (the zoo arm's gravity is -9.81 along y): over q1 + q2 in [0.3, 0.9] it is
    largest at 0.3 and smallest at 0.9."""
    arm = dk.robot("planar2r")
    e = model_bound(arm, "gravity_torque", 1, q=([0.1, 0.2], [0.4, 0.5]), rel_tol=1e-8)
    g2 = lambda s: 3.0 * 0.2 * 9.81 * math.cos(s)  # noqa: E731
    assert arm.gravity_torque([0.1, 0.2])[1] == pytest.approx(g2(0.3), rel=1e-12)  # the closed form is the model's
    assert e.lower <= g2(0.9) and e.upper >= g2(0.3)
    assert e.lower == pytest.approx(g2(0.9), rel=2e-8) and e.upper == pytest.approx(g2(0.3), rel=2e-8)


def test_puma_inertia_bound_contains_samples_and_its_witness_is_in_the_box():
    arm = dk.robot("puma560")
    low, high = np.full(6, -0.4), np.full(6, 0.4)
    e = model_bound(arm, "mass_matrix", (1, 1), q=(low, high), rel_tol=1e-4)
    Q = np.random.default_rng(2).uniform(low, high, size=(20_000, 6))
    d = arm.mass_matrix(Q)[:, 1, 1]
    assert e.lower <= d.min() + 1e-13 and e.upper >= d.max() - 1e-13
    assert np.all(e.argmax["q"] >= low) and np.all(e.argmax["q"] <= high)
    assert arm.mass_matrix(e.argmax["q"])[1, 1] == pytest.approx(e.max_value, rel=1e-12)


@pytest.mark.parametrize("kwargs, field", [
    ({"quantity": "nope", "index": 0, "q": (0, 1)}, "quantity"),
    ({"quantity": "coriolis_torque", "index": 0, "q": (0, 1)}, "qd"),
    ({"quantity": "mass_matrix", "index": (0, 0), "q": (0, 1), "qd": (0, 1)}, "qd"),
    ({"quantity": "mass_matrix", "index": (0, 0), "q": ([0, 1, 2], [1, 2, 3])}, "q"),
])
def test_bad_arguments_name_the_field(kwargs, field):
    with pytest.raises(ModelError) as err:
        model_bound(dk.robot("planar2r"), **kwargs)
    assert err.value.path == field


@settings(max_examples=12, deadline=None)
@given(name=st.sampled_from(["planar2r", "puma560", "scara"]), data=st.data())
def test_inertia_enclosures_of_zoo_robots_contain_random_samples(name, data):
    plant = zoo_plant(name)
    arm, p = plant.robot, plant.model_parameters()
    i = data.draw(st.integers(0, arm.n - 1), label="joint")
    centre = np.array(data.draw(st.lists(st.floats(-2, 2), min_size=arm.n, max_size=arm.n), label="centre"))
    width = data.draw(st.floats(0.0, 1.0), label="width")
    low, high = centre - width / 2, centre + width / 2
    e = model_bound(arm, "mass_matrix", (i, i), q=(low, high), p=p if p is not None and len(p) else None,
                    rel_tol=1e-2)
    Q = np.random.default_rng(i).uniform(low, high, size=(2000, arm.n))
    d = arm.mass_matrix(Q, p=p)[:, i, i]
    rounding = 1e-13 * (1 + np.abs(d).max())  # the samples' own floating-point rounding
    assert e.lower <= d.min() + rounding and e.upper >= d.max() - rounding
    # the witnesses are configurations of the box with the values reported
    for arg, value in ((e.argmin["q"], e.min_value), (e.argmax["q"], e.max_value)):
        assert np.all(arg >= low - 1e-15) and np.all(arg <= high + 1e-15)
        assert arm.mass_matrix(arg, p=p)[i, i] == pytest.approx(value, rel=1e-12)


@pytest.mark.parametrize("name", ["planar2r", "puma560", "scara"])
def test_christoffel_symbols_do_not_depend_on_the_joints_before_their_smallest_index(name):
    """Gamma_ijk is unchanged when joints 1..min(i, j, k) move (what perturbation_enclosure holds fixed)."""
    plant = zoo_plant(name)
    arm, p = plant.robot, plant.model_parameters()
    rng = np.random.default_rng(6)
    q = rng.uniform(-2, 2, size=(20, arm.n))
    G = arm.christoffel(q, p=p)
    for m in range(arm.n):
        moved = q.copy()
        moved[:, :m + 1] = rng.uniform(-3, 3, size=(20, m + 1))
        G2 = arm.christoffel(moved, p=p)
        block = np.s_[:, m:, m:, m:]
        assert np.allclose(G2[block], G[block], rtol=1e-11, atol=1e-11 * np.abs(G).max())


def _xi_samples(plant, lo, hi, V, A, Dh, f, gravity, count, seed):
    """|xi_i| by Newton-Euler at random points, half of them on the velocity and acceleration vertices."""
    arm, p, n = plant.robot, plant.model_parameters(), plant.n_joints
    rng = np.random.default_rng(seed)
    q = lo + (hi - lo) * rng.random((count, n))
    qd = V * rng.uniform(-1, 1, (count, n))
    qdd = A * rng.uniform(-1, 1, (count, n))
    qd[: count // 2] = V * np.sign(qd[: count // 2])
    qdd[: count // 2] = A * np.sign(qdd[: count // 2])
    tau = arm.inverse_dynamics(q, qd, qdd, p=p).reshape(count, n)
    if not gravity:
        tau = tau - arm.gravity_torque(q, p=p).reshape(count, n)
    return np.abs(Dh * qdd + f * qd - tau).max(axis=0)


@pytest.mark.parametrize(("name", "gravity"), [("planar2r", True), ("scara", False), ("planar2r", False)])
def test_perturbation_enclosure_contains_newton_euler_samples(name, gravity):
    from designkit.models.bounds import perturbation_enclosure

    plant = zoo_plant(name)
    n = plant.n_joints
    lim = [lk.qlim for lk in plant.robot.description.links]
    lo = np.array([max(-1.0, lk[0]) if lk else -1.0 for lk in lim])
    hi = np.array([min(1.0, lk[1]) if lk else 1.0 for lk in lim])
    lo, hi = lo + 0.25 * (hi - lo), hi - 0.25 * (hi - lo)
    V, A = np.full(n, 1.5), np.full(n, 4.0)
    Dh = np.diag(plant.robot.mass_matrix(0.5 * (lo + hi), p=plant.model_parameters()))
    f = np.full(n, 0.5)
    # the friction residual: the model's friction minus f q', at most |viscous - f| V + |Fc|
    visc = np.array([float(lk.viscous) if lk.viscous is not None else 0.0 for lk in plant.robot.description.links]) \
        if name == "scara" else np.array([plant.parameter(f"f{i + 1}").value for i in range(n)])
    coul = np.abs(visc - f) * V + np.array([abs(float(lk.coulomb or 0.0)) for lk in plant.robot.description.links])
    e = perturbation_enclosure(plant.robot, q=(lo, hi), qd_limit=V, qdd_limits=np.tile(A, (n, 1)), inertia=Dh,
                               damping=f, coulomb=coul, gravity=gravity, p=plant.model_parameters(),
                               rel_tol=0.02, max_boxes=200, samples=300)
    worst = _xi_samples(plant, lo, hi, V, A, Dh, f, gravity, 5000, 2)
    assert np.all(worst <= np.array(e.upper)), (worst, e.upper)
    assert np.all(np.array(e.sampled) <= np.array(e.upper))
    for i in range(n):  # the attained point is in the box, and |xi| there is what it says
        at = e.argmax[i]
        assert np.all(np.asarray(at["q"]) >= lo - 1e-12) and np.all(np.asarray(at["q"]) <= hi + 1e-12)
        assert np.all(np.abs(at["qd"]) <= V + 1e-12) and np.all(np.abs(at["qdd"]) <= A + 1e-12)


def test_perturbation_enclosure_refuses_an_inverted_box():
    from designkit.models.bounds import perturbation_enclosure

    plant = zoo_plant("planar2r")
    with pytest.raises(ModelError) as exc:
        perturbation_enclosure(plant.robot, q=([0.5, 0.0], [0.2, 1.0]), qd_limit=[1, 1], qdd_limits=np.ones((2, 2)),
                               inertia=[1, 1], damping=[1, 1], coulomb=[0, 0], gravity=False,
                               p=plant.model_parameters())
    assert exc.value.field == "q[0]"
