"""The perturbation enclosure over a box of the robot's parameters, against routes that do not use it.

* Pinocchio's RNEA on a model built from the robot's link data *with the sampled parameters* (a new model per
  parameter draw), plus the rotor inertias and the friction read from the link data: at thousands of random points
  of the box of configurations, velocities, accelerations and parameters, |xi_i| never exceeds the proven bound;
* the point where the bound says its attained value is reached, recomputed with Pinocchio;
* a degenerate box (low = high = the nominal values) gives today's bound bit for bit, and a box held at other values
  (without feed-forward) the bound of the robot built with those values.
"""

from __future__ import annotations

import numpy as np
import pytest

from designkit.errors import ModelError
from designkit.models.bounds import perturbation_enclosure
from designkit.models.robot_plant import zoo_plant
from designkit.models.robots import zoo_module

pin = pytest.importorskip("pinocchio")

from tests.models.support import pinocchio_model  # noqa: E402


def _box(plant, ranges: dict) -> tuple[np.ndarray, np.ndarray]:
    p0 = np.array(plant.parameter_vector)
    lo, hi = p0.copy(), p0.copy()
    for name, (a, b) in ranges.items():
        k = plant.parameter_names.index(name)
        lo[k], hi[k] = a, b
    return lo, hi


class _Pinocchio:
    """``xi_i`` by Pinocchio for one parameter vector of a zoo robot: ``D^ q'' + f q' - (tau - g^)`` with ``tau`` the
    RNEA of the model built from the link data at those parameters, plus the rotor inertia ``G^2 Jm`` and the joint
    friction ``Fv q' + Fc sign(q')`` read from the same link data, and ``g^`` the nominal model's gravity."""

    def __init__(self, name: str, plant, values: np.ndarray, motor_inertia: bool) -> None:
        module = zoo_module(name)
        description = module.description(**dict(zip(plant.parameter_names, map(float, values), strict=True)))
        self.model, _ = pinocchio_model(description)
        self.data = self.model.createData()
        links = description.links
        self.rotor = np.array([lk.gear_ratio**2 * lk.motor_inertia for lk in links]) if motor_inertia else 0.0
        self.fv = np.array([float(lk.viscous) for lk in links])
        self.fc = np.array([float(lk.coulomb) for lk in links])

    def torque(self, q, qd, qdd) -> np.ndarray:
        return (pin.rnea(self.model, self.data, q, qd, qdd) + self.rotor * qdd + self.fv * qd
                + self.fc * np.sign(qd))

    def gravity(self, q) -> np.ndarray:
        return pin.rnea(self.model, self.data, q, np.zeros_like(q), np.zeros_like(q))


def _worst(name, plant, lo, hi, V, A, Dh, f, p_lo, p_hi, *, fed, draws, per_draw, seed, motor_inertia=False):
    """Largest |xi_i| by Pinocchio at ``draws`` parameter vectors of the box (the first ones at its vertices) times
    ``per_draw`` random points of the motion box (half on the velocity and acceleration vertices)."""
    rng = np.random.default_rng(seed)
    n = lo.size
    nominal = _Pinocchio(name, plant, plant.parameter_vector, motor_inertia)
    free = np.flatnonzero(p_hi > p_lo)
    worst = np.zeros(n)
    for d in range(draws):
        u = rng.random(free.size) if d >= 2 ** free.size else np.array([(d >> b) & 1 for b in range(free.size)], float)
        p = p_lo.copy()
        p[free] = p_lo[free] + (p_hi[free] - p_lo[free]) * u
        arm = _Pinocchio(name, plant, p, motor_inertia)
        for k in range(per_draw):
            i = k % n  # joint i's acceleration box
            q = lo + (hi - lo) * rng.random(n)
            qd, qdd = V * rng.uniform(-1, 1, n), A[i] * rng.uniform(-1, 1, n)
            if k % 2:
                qd, qdd = V * np.sign(qd), A[i] * np.sign(qdd)
            tau = arm.torque(q, qd, qdd) - (nominal.gravity(q) if fed else 0.0)
            worst[i] = max(worst[i], abs(Dh[i] * qdd[i] + f[i] * qd[i] - tau[i]))
    return worst


SIMNOG = {"q": (np.array([-0.2, -0.8]), np.array([0.8, 0.3])), "V": np.array([2.0, 2.0]),
          "A": np.array([[12.0, 6.0], [12.0, 12.0]])}


def _simnog_kw(plant):
    lo, hi = SIMNOG["q"]
    Dh = np.diag(plant.robot.mass_matrix(0.5 * (lo + hi), p=plant.model_parameters()))
    f = np.array([plant.parameter("f1").value, plant.parameter("f2").value])
    return dict(q=(lo, hi), qd_limit=SIMNOG["V"], qdd_limits=SIMNOG["A"], inertia=Dh, damping=f, coulomb=[0.0, 0.0],
                p=plant.model_parameters()), Dh, f


@pytest.mark.parametrize(("ranges", "fed", "gap"), [
    ({"m2": (2.0, 4.0)}, True, 0.05),  # the payload example's box, gravity fed forward: g(q, p) - g(q, p0)
    ({"m2": (2.0, 4.0), "f2": (0.6, 1.4), "I2": (0.03, 0.05)}, True, 0.05),  # a friction and an inertia too
    # a length: D is not affine in it, so its side is bisected, not split at its ends: slower to tighten
    ({"m2": (2.5, 3.5), "d2": (0.35, 0.45)}, True, 0.10),
    ({"m1": (4.0, 6.0), "m2": (2.0, 4.0)}, False, 0.05),  # no feed-forward: the whole gravity torque
])
def test_simnog_bound_over_a_parameter_box_covers_pinocchio(ranges, fed, gap):
    plant = zoo_plant("planar2r")
    kw, Dh, f = _simnog_kw(plant)
    p_lo, p_hi = _box(plant, ranges)
    e = perturbation_enclosure(plant.robot, p_box=(p_lo, p_hi), gravity=not fed, rel_tol=1e-3, max_boxes=300,
                               samples=1000, **kw)
    lo, hi = SIMNOG["q"]
    worst = _worst("planar2r", plant, lo, hi, SIMNOG["V"], SIMNOG["A"], Dh, f, p_lo, p_hi, fed=fed, draws=40,
                   per_draw=100, seed=3)
    upper, sampled = np.array(e.upper), np.array(e.sampled)
    assert np.all(worst <= upper), (worst, upper)
    assert np.all(sampled <= upper)
    # the attained point is in the box, Pinocchio finds the value it reports there, and the bound is within ``gap``
    # of the largest value Pinocchio met (there or at the random points): not vacuous
    for i, at in enumerate(e.argmax):
        p = np.asarray(at["p"])
        assert np.all((p >= p_lo) & (p <= p_hi))
        q, qd, qdd = (np.asarray(at[k]) for k in ("q", "qd", "qdd"))
        assert np.all((q >= lo - 1e-12) & (q <= hi + 1e-12)) and np.all(np.abs(qd) <= SIMNOG["V"] + 1e-12)
        assert np.all(np.abs(qdd) <= SIMNOG["A"][i] + 1e-12)
        tau = _Pinocchio("planar2r", plant, p, False).torque(q, qd, qdd)
        if fed:
            tau -= _Pinocchio("planar2r", plant, plant.parameter_vector, False).gravity(q)
        there = abs(Dh[i] * qdd[i] + f[i] * qd[i] - tau[i])
        assert there == pytest.approx(sampled[i], rel=1e-9)
        assert upper[i] <= (1 + gap) * max(there, worst[i]), (i, upper[i], there, worst[i])


def test_puma_bound_over_a_payload_and_a_link_mass_box_covers_pinocchio():
    plant = zoo_plant("puma560", motor_inertia=True)
    r, p0, n = plant.robot, plant.model_parameters(), 6
    c0 = np.array([0, 0.785, -3.1416, 0, 0.785, 0])
    lo, hi = c0 - 0.2, c0 + 0.2
    V, A = np.full(n, 1.0), np.full((n, n), 6.0)
    Dh = np.diag(r.mass_matrix(c0, p=p0))
    f = np.array([float(lk.viscous) for lk in r.description.links])
    Fc = np.array([float(lk.coulomb) for lk in r.description.links])
    p_lo, p_hi = _box(plant, {"m6": (0.09, 2.59), "m3": (4.3, 5.3)})
    e = perturbation_enclosure(r, q=(lo, hi), qd_limit=V, qdd_limits=A, inertia=Dh, damping=f, coulomb=Fc,
                               gravity=False, p=p0, p_box=(p_lo, p_hi), rel_tol=0.05, max_boxes=20, samples=200)
    worst = _worst("puma560", plant, lo, hi, V, A, Dh, f, p_lo, p_hi, fed=True, draws=30, per_draw=120, seed=5,
                   motor_inertia=True)
    assert np.all(worst <= np.array(e.upper)), (worst, e.upper)
    assert np.all(np.array(e.sampled) <= np.array(e.upper))
    nominal = _Pinocchio("puma560", plant, plant.parameter_vector, True)
    met = worst.copy()
    for i, at in enumerate(e.argmax):  # the attained points: in the box, and Pinocchio finds the value there
        p = np.asarray(at["p"])
        assert np.all((p >= p_lo) & (p <= p_hi))
        q, qd, qdd = (np.asarray(at[k]) for k in ("q", "qd", "qdd"))
        tau = _Pinocchio("puma560", plant, p, True).torque(q, qd, qdd) - nominal.gravity(q)
        there = abs(Dh[i] * qdd[i] + f[i] * qd[i] - tau[i])
        assert there == pytest.approx(e.sampled[i], rel=1e-9)
        met[i] = max(met[i], there)
    # the joints whose xi is more than their Coulomb friction: within 1.5x of the largest value Pinocchio met at this
    # small work limit (20 boxes per joint)
    assert np.all(np.array(e.upper)[:3] <= 1.5 * met[:3]), (met, e.upper)


@pytest.mark.parametrize("gravity", [True, False])
def test_a_degenerate_box_at_the_nominal_values_gives_todays_bound(gravity):
    plant = zoo_plant("planar2r")
    kw, _, _ = _simnog_kw(plant)
    p0 = np.array(plant.parameter_vector)
    today = perturbation_enclosure(plant.robot, gravity=gravity, rel_tol=1e-3, max_boxes=150, **kw)
    held = perturbation_enclosure(plant.robot, gravity=gravity, p_box=(p0, p0), rel_tol=1e-3, max_boxes=150, **kw)
    assert held.upper == today.upper and held.sampled == today.sampled and held.boxes == today.boxes
    assert held.terms == today.terms and held.converged == today.converged
    for a, b in zip(held.argmax, today.argmax, strict=True):
        assert {k: a[k] for k in ("q", "qd", "qdd")} == b and a["p"] == p0.tolist()


def test_a_degenerate_box_on_the_puma_gives_todays_bound():
    plant = zoo_plant("puma560", motor_inertia=True)
    r, p0 = plant.robot, np.array(plant.parameter_vector)
    c0 = np.array([0, 0.785, -3.1416, 0, 0.785, 0])
    kw = dict(q=(c0 - 0.2, c0 + 0.2), qd_limit=np.ones(6), qdd_limits=np.full((6, 6), 6.0),
              inertia=np.diag(r.mass_matrix(c0, p=p0)), damping=[float(lk.viscous) for lk in r.description.links],
              coulomb=[float(lk.coulomb) for lk in r.description.links], gravity=False, p=p0, rel_tol=0.05,
              max_boxes=15, samples=100)
    today, held = perturbation_enclosure(r, **kw), perturbation_enclosure(r, p_box=(p0, p0), **kw)
    assert held.upper == today.upper and held.sampled == today.sampled and held.boxes == today.boxes


def test_a_box_held_at_other_values_without_feed_forward_is_the_bound_of_that_arm():
    """Without feed-forward xi depends on the true parameters only: a box held at m2 = 4 kg gives the bound of the
    arm built with m2 = 4 kg (the held parameters are constants of the enclosure, as the nominal ones are)."""
    plant = zoo_plant("planar2r")
    kw, _, _ = _simnog_kw(plant)
    heavy = plant.with_params(m2=4.0)
    p1 = np.array(heavy.parameter_vector)
    held = perturbation_enclosure(plant.robot, gravity=True, p_box=(p1, p1), rel_tol=1e-3, max_boxes=150, **kw)
    kw["p"] = heavy.model_parameters()
    built = perturbation_enclosure(plant.robot, gravity=True, rel_tol=1e-3, max_boxes=150, **kw)
    np.testing.assert_allclose(held.upper, built.upper, rtol=1e-12)
    np.testing.assert_allclose(held.sampled, built.sampled, rtol=1e-12)


def test_an_inverted_parameter_box_is_refused_with_its_index():
    plant = zoo_plant("planar2r")
    kw, _, _ = _simnog_kw(plant)
    lo, hi = _box(plant, {"m2": (4.0, 2.0)})
    with pytest.raises(ModelError) as exc:
        perturbation_enclosure(plant.robot, gravity=False, p_box=(lo, hi), **kw)
    assert exc.value.field == f"p_box[{plant.parameter_names.index('m2')}]" and "m2" in exc.value.message


def test_a_friction_box_on_the_one_link_covers_its_closed_form():
    """The one-link rod with uncertain viscous and Coulomb friction and mass, gravity fed forward at the nominal
    values: xi = -(I_O(m) - D^) q'' - (g(q, p) - g(q, p0)) - (f(p) - f0) q' - fc(p) sign(q') in closed form
    (I_O = m l^2/4 + I about the joint, g = m g l/2 cos q, the rod's centre at l/2)."""
    plant = zoo_plant("onelink")
    P0 = {p.name: p.value for p in plant.parameters}
    p_lo, p_hi = _box(plant, {"m": (0.8, 1.5), "f": (0.3, 0.7), "fc": (0.0, 0.2)})
    Dh, f0, V, A = 0.1, P0["f"], 3.0, 10.0
    e = perturbation_enclosure(plant.robot, q=([-1.0], [1.2]), qd_limit=[V], qdd_limits=[[A]], inertia=[Dh],
                               damping=[f0], coulomb=[0.0], gravity=False, p=plant.model_parameters(),
                               p_box=(p_lo, p_hi), rel_tol=1e-4, max_boxes=400)
    rng = np.random.default_rng(2)
    N = 200000
    m, f, fc = (rng.uniform(a, b, N) for a, b in ((0.8, 1.5), (0.3, 0.7), (0.0, 0.2)))
    corner = rng.random(N) < 0.5
    for x, a, b in ((m, 0.8, 1.5), (f, 0.3, 0.7), (fc, 0.0, 0.2)):
        x[corner] = np.where(rng.random(corner.sum()) < 0.5, a, b)
    q = rng.uniform(-1.0, 1.2, N)
    qd = V * rng.choice([-1.0, 1.0], N) * np.where(rng.random(N) < 0.5, 1.0, rng.random(N))
    qdd = A * rng.choice([-1.0, 1.0], N)
    l, g, I = P0["l"], P0["g"], P0["I"]
    xi = ((m * l**2 / 4 + I - Dh) * qdd + (m - P0["m"]) * g * l / 2 * np.cos(q) + (f - f0) * qd
          + fc * np.sign(qd))
    worst = float(np.max(np.abs(xi)))
    assert worst <= e.upper[0] and e.sampled[0] <= e.upper[0]
    assert e.upper[0] <= 1.01 * max(worst, e.sampled[0]) and e.converged == (True,)
    assert e.terms[0]["friction"] == pytest.approx(0.2 * V + 0.2, rel=1e-6)  # |f - f0| V + fc at the box's top


def test_the_joints_an_entry_cannot_depend_on_stay_so_with_other_parameters():
    """What the enclosure holds fixed (D_ij and Gamma_ijk do not depend on q_1..q_min(i,j,k)) holds for any inertial
    parameters, not only the nominal ones: the PUMA 560 with a 2.5 kg payload and a heavier forearm."""
    plant = zoo_plant("puma560", motor_inertia=True).with_params(m6=2.59, m3=5.3)
    arm, p = plant.robot, plant.model_parameters()
    rng = np.random.default_rng(8)
    q = rng.uniform(-2, 2, size=(20, arm.n))
    D, G = arm.mass_matrix(q, p=p), arm.christoffel(q, p=p)
    for m in range(arm.n):
        moved = q.copy()
        moved[:, :m + 1] = rng.uniform(-3, 3, size=(20, m + 1))
        D2, G2 = arm.mass_matrix(moved, p=p), arm.christoffel(moved, p=p)
        assert np.allclose(D2[:, m:, m:], D[:, m:, m:], rtol=1e-11, atol=1e-11 * np.abs(D).max())
        assert np.allclose(G2[:, m:, m:, m:], G[:, m:, m:, m:], rtol=1e-11, atol=1e-11 * np.abs(G).max())
