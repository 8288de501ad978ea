"""PID/sliding mode on robots: the hierarchy of control's proven sup|xi_i| against routes that do not use it.

* the SIMNOG arm: xi from the textbook closed form of the two-link arm (written here from the link data, and
  checked against the model's inertia matrix first), at thousands of random points and the box's vertices;
* the PUMA 560: xi from Pinocchio's CRBA and RNEA (built from the DH table with NumPy) plus the rotor inertias and
  friction;
* the hierarchy's acceleration boxes against the closed-form sliding motion (``q'' (0+) = p1 p2 step``);
* the gains against the characteristic polynomial of each joint's simplified link;
* along simulated runs (hypothesis), xi from the run's states with finite-difference accelerations and the
  closed form never exceeds the bound where the run is inside the box, and a run beyond the velocity limit does.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from designkit.models.bounds import perturbation_enclosure
from designkit.models.robot_plant import zoo_plant
from designkit.pipeline import run
from designkit.schema.loader import parse_spec
from tests.models.support import pinocchio_model

SIMNOG = "specs/hierarchy-simnog.yaml"


def _closed_form_2r(P: dict) -> tuple:
    """D(q), c(q, qd) of the planar two-link arm with uniform links (centres at mid-length): the textbook
    Euler-Lagrange form (Spong, Hutchinson & Vidyasagar, sec. 7.4)."""
    m1, m2, l1, l2, I1, I2 = (P[k] for k in ("m1", "m2", "d1", "d2", "I1", "I2"))
    lc1, lc2 = l1 / 2, l2 / 2

    def D(q: np.ndarray) -> np.ndarray:
        c2 = np.cos(q[..., 1])
        d11 = m1 * lc1**2 + m2 * (l1**2 + lc2**2 + 2 * l1 * lc2 * c2) + I1 + I2
        d12 = m2 * (lc2**2 + l1 * lc2 * c2) + I2
        d22 = np.full_like(c2, m2 * lc2**2 + I2)
        return np.stack([np.stack([d11, d12], -1), np.stack([d12, d22], -1)], -2)

    def c(q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        h = -m2 * l1 * lc2 * np.sin(q[..., 1])
        return np.stack([h * qd[..., 1] ** 2 + 2 * h * qd[..., 0] * qd[..., 1], -h * qd[..., 0] ** 2], -1)

    return D, c


def _design(path: str = SIMNOG, **changes):
    data = yaml.safe_load(Path(path).read_text())
    for key, value in changes.items():
        node = data
        *head, last = key.split(".")
        for k in head:
            node = node.setdefault(k, {})
        if value is None:
            node.pop(last, None)
        else:
            node[last] = value
    return parse_spec(yaml.safe_dump(data))


@pytest.fixture(scope="module")
def simnog():
    return run(_design())


def test_the_closed_form_is_the_models_arm():
    plant = zoo_plant("planar2r")
    P = {p.name: p.value for p in plant.parameters}
    D, c = _closed_form_2r(P)
    rng = np.random.default_rng(0)
    q, qd = rng.uniform(-3, 3, (50, 2)), rng.uniform(-3, 3, (50, 2))
    p = plant.model_parameters()
    np.testing.assert_allclose(D(q), plant.robot.mass_matrix(q, p=p).reshape(-1, 2, 2), atol=1e-12)
    Cq = np.einsum("kij,kj->ki", plant.robot.coriolis_matrix(q, qd, p=p).reshape(-1, 2, 2), qd)
    np.testing.assert_allclose(c(q, qd), Cq, atol=1e-12)


def test_simnog_bound_covers_the_closed_form_at_random_points_and_vertices(simnog):
    info = simnog.design.data
    P = {p.name: p.value for p in simnog.design.plant.parameters}
    D, c = _closed_form_2r(P)
    ws = info.workspace
    lo, hi, V = np.array(ws["low"]), np.array(ws["high"]), np.array(ws["velocity"])
    Dh = np.array([lk.inertia for lk in info.links])
    rng = np.random.default_rng(7)
    N = 20000
    for i in range(2):
        A = np.array(info.acceleration_rows[i])
        q = lo + (hi - lo) * rng.random((N, 2))
        qd = V * rng.choice([-1.0, 1.0], (N, 2)) * np.where(rng.random((N, 2)) < 0.5, 1.0, rng.random((N, 2)))
        qdd = A * rng.choice([-1.0, 1.0], (N, 2))
        xi = (np.einsum("kj,kj->k", D(q)[:, i, :], qdd) - Dh[i] * qdd[:, i] + c(q, qd)[:, i])
        worst = float(np.max(np.abs(xi)))
        assert worst <= info.bound[i]
        assert info.sampled[i] <= info.bound[i]
        # on this two-link arm the proven bound is tight: within 5 % of the largest value the closed form finds
        assert info.bound[i] <= 1.05 * max(worst, info.sampled[i])
        assert info.M[i] == pytest.approx(1.2 * info.bound[i])


def test_the_hierarchy_takes_the_later_joint_at_its_sliding_motions_acceleration(simnog):
    """Servo sliding motion a2 q'' + a1 q' + q = qD from rest: q''(0+) = step/a2 = p1 p2 step, its largest value."""
    info = simnog.design.data
    step2 = 0.3
    assert info.sliding_acceleration[1] == pytest.approx(4 * 5 * step2, rel=1e-9)
    assert info.acceleration_rows[0] == pytest.approx([12.0, 6.0])  # joint 1 sees joint 2 sliding
    assert info.acceleration_rows[1] == pytest.approx([12.0, 12.0])  # the last joint: the limits


def test_each_joints_gains_place_its_poles_and_the_zero_on_p3(simnog):
    info = simnog.design.data
    for lk, g in zip(info.links, info.gains, strict=True):
        Km, tau = 1.0 / lk.damping, lk.inertia / lk.damping
        roots = np.sort(np.roots([tau, 1 + Km * g["K2"], Km * g["K1"], Km * g["K3"]]).real)
        np.testing.assert_allclose(roots, [-20, -5, -4], rtol=1e-9)
        assert -g["K3"] / (g["K1"] + g["K3"] * g["K4"]) == pytest.approx(-20.0, rel=1e-9)


def test_puma_bound_covers_pinocchio_at_random_points():
    pin = pytest.importorskip("pinocchio")
    from designkit.models.robots import robot

    plant = zoo_plant("puma560", motor_inertia=True)
    r, p, n = plant.robot, plant.model_parameters(), 6
    c0 = np.array([0, 0.785, -3.1416, 0, 0.785, 0])
    lo, hi = c0 - 0.3, c0 + 0.3
    V, A = np.full(n, 1.0), np.full((n, n), 6.0)
    from designkit.models.link import simplified_link

    links = [simplified_link(r, i, c0, p=p) for i in range(n)]
    Fc = np.array([float(lk.coulomb) for lk in r.description.links])
    e = perturbation_enclosure(r, q=(lo, hi), qd_limit=V, qdd_limits=A, inertia=[lk.inertia for lk in links],
                               damping=[lk.damping for lk in links], coulomb=Fc, gravity=False, p=p,
                               rel_tol=0.05, max_boxes=30, samples=200)
    model, _ = pinocchio_model(robot("puma560").description)
    data = model.createData()
    Ia = np.diag(r.mass_matrix(c0, p=p)) - np.diag(pin.crba(model, data, c0))
    fv = np.array([lk.damping for lk in links])
    rng = np.random.default_rng(3)
    worst = np.zeros(n)
    for _ in range(3000):
        q = lo + (hi - lo) * rng.random(n)
        qd = V * rng.choice([-1.0, 1.0], n)
        qdd = A[0] * rng.choice([-1.0, 1.0], n)
        tau = pin.rnea(model, data, q, qd, qdd) + Ia * qdd + fv * qd + Fc * np.sign(qd)
        tau -= pin.rnea(model, data, q, np.zeros(n), np.zeros(n))  # gravity fed forward
        xi = np.array([lk.inertia for lk in links]) * qdd + fv * qd - tau
        worst = np.maximum(worst, np.abs(xi))
    assert np.all(worst <= np.array(e.upper))
    assert np.all(np.array(e.sampled) <= np.array(e.upper))
    # the bound is not vacuous: the joints whose xi is more than their Coulomb friction are within 2x of it
    assert np.all(worst[:3] > 0.5 * np.array(e.upper)[:3]), (worst, e.upper)


def _xi_closed_form(result) -> tuple[np.ndarray, np.ndarray]:
    """xi along a run from its states alone (finite-difference accelerations, the closed form), and whether each
    sample is inside each joint's box (the same accelerations)."""
    d = result.design
    info = d.data
    P = {p.name: p.value for p in d.plant.parameters}
    D, c = _closed_form_2r(P)
    sim = result.simulation
    t, x = np.asarray(sim.time), np.asarray(sim.state)
    q, qd = x[:, :2], x[:, 2:]
    qdd = np.gradient(qd, t, axis=0)
    Dh = np.array([lk.inertia for lk in info.links])
    xi = np.einsum("kij,kj->ki", D(q), qdd) - Dh * qdd + c(q, qd)
    ws = info.workspace
    tol = 1e-9
    state_in = (np.all((q >= np.array(ws["low"]) - tol) & (q <= np.array(ws["high"]) + tol), axis=1)
                & np.all(np.abs(qd) <= np.array(ws["velocity"]), axis=1))
    inside = np.column_stack([state_in & np.all(np.abs(qdd) <= np.array(info.acceleration_rows[i]), axis=1)
                              for i in range(2)])
    inside[:3] = False  # the step's instant: a finite difference across it is no acceleration of the run
    return xi, inside


@settings(max_examples=4, deadline=None, phases=(Phase.explicit, Phase.generate),
          suppress_health_check=[HealthCheck.too_slow])
@given(s1=st.floats(0.1, 0.55), s2=st.floats(-0.6, -0.15), eps=st.sampled_from([0.001, 0.002, 0.005]))
def test_along_runs_inside_the_box_xi_never_exceeds_the_bound(s1, s2, eps):
    spec = _design(**{"simulation.step": [s1, s2], "simulation.duration": 1.5, "controller.epsilon": eps})
    result = run(spec)
    info = result.design.data
    xi, inside = _xi_closed_form(result)
    for i in range(2):
        assert inside[:, i].mean() > 0.5
        peak = float(np.max(np.abs(xi[inside[:, i], i])))
        assert peak <= info.bound[i] * (1 + 1e-3) + 1e-3, (i, peak, info.bound[i])
    names = {c.name: c.passed for c in result.checks}
    assert names["pid_sm_robot_xi"] is True and names["pid_sm_hierarchy"] is True


def test_a_later_joint_held_still_leaves_the_run_outside_the_box_and_the_check_undecided():
    """Joint 2 not moving: its sliding motion's acceleration is 0, so joint 1's box allows q2'' = 0 only, which the
    boundary layer's approximate sliding never meets exactly: the run check is undecided, not a vacuous pass."""
    result = run(_design(**{"simulation.step": [0.5, 0.0], "simulation.duration": 1.0}))
    info = result.design.data
    assert info.acceleration_rows[0][1] == 0.0
    check = next(c for c in result.checks if c.name == "pid_sm_robot_xi")
    assert check.passed is None and "does not describe it" in check.detail


def test_a_run_beyond_the_velocity_limit_exceeds_the_bound():
    """Limits of 0.2 rad/s and 3 rad/s^2 (the bound is small), and a step of 0.5 rad on both joints that the
    sliding motion runs at up to 0.82 rad/s and 10 rad/s^2: beyond the limits |xi| exceeds the bound, as it may."""
    spec = _design(**{"plant.limits.velocity": [0.2, 0.2], "plant.limits.acceleration": [3.0, 3.0],
                      "simulation.step": [0.5, -0.5], "simulation.duration": 1.5,
                      "controller.workspace": {"low": [-0.2, -0.8], "high": [0.8, 0.3]}})
    result = run(spec)
    info = result.design.data
    xi, inside = _xi_closed_form(result)
    qd = np.asarray(result.simulation.state)[:, 2:]
    beyond = np.any(np.abs(qd) > 0.2, axis=1)
    beyond[:3] = False
    assert beyond.any()
    exceeded = [float(np.max(np.abs(xi[beyond, i]))) - info.bound[i] for i in range(2)]
    assert max(exceeded) > 0, exceeded
    for i in range(2):  # and where the run is inside the box, it does not
        if inside[:, i].any():
            assert float(np.max(np.abs(xi[inside[:, i], i]))) <= info.bound[i] * (1 + 1e-3) + 1e-3


@pytest.mark.parametrize(("change", "remove", "path"), [
    ({}, "controller.workspace", "controller.workspace"),
    ({}, "plant.limits.velocity", "plant.limits.velocity"),
    ({}, "plant.limits.acceleration", "plant.limits.acceleration"),
    ({"controller.M": 0.0}, None, "controller.M"),
    ({"controller.M": -1.0}, None, "controller.M"),
    ({"controller.workspace": {"low": [0.5, -0.8], "high": [0.2, 0.3]}}, None, "controller.workspace.high[0]"),
    ({"plant.limits.velocity": [1.0, 1.0, 1.0]}, None, "plant.limits.velocity"),
    ({"plant.uncertainty": {"m2": [-1.0, 4.0]}}, None, "plant.uncertainty.m2"),  # a negative mass
    ({"plant.uncertainty": {"m2": [4.0, 2.0]}}, None, "plant.uncertainty"),
    ({"plant.uncertainty": {"m7": [1.0, 2.0]}}, None, "plant.uncertainty.m7"),  # no such parameter
    ({"controller.work_limit": 0}, None, "controller.work_limit"),
    ({"controller.perturbation_bound": 0.5}, None, "controller.perturbation_bound"),
    ({"simulation.perturbation": {"value": 0.5, "time": 1.0}}, None, "simulation.perturbation"),
])
def test_bad_input_exits_2_naming_the_key(tmp_path, capsys, change, remove, path):
    from designkit.cli import main

    data = yaml.safe_load(Path(SIMNOG).read_text())
    for key, value in change.items():
        node = data
        *head, last = key.split(".")
        for k in head:
            node = node[k]
        node[last] = value
    if remove:
        *head, last = remove.split(".")
        node = data
        for k in head:
            node = node[k]
        del node[last]
    spec = tmp_path / "bad.yaml"
    spec.write_text(yaml.safe_dump(data))
    out = tmp_path / "out"
    code = main(["synth", str(spec), "--out", str(out), "--no-report"])
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert err.count("\n") == 0 and path in err, err
    assert not out.exists()


def test_json_contract_gains_and_M_per_joint_with_the_bound(tmp_path, capsys):
    from designkit.cli import main

    code = main(["verify", SIMNOG, "--json"])
    assert code == 0
    obj = json.loads(capsys.readouterr().out)["pid_sliding_mode"]
    assert len(obj["joints"]) == 2 and len(obj["M"]) == 2
    for j in obj["joints"]:
        assert set(j["gains"]) == {"K1", "K2", "K3", "K4"}
        assert j["M"] > j["bound"] >= j["sampled_lower_bound"] > 0
        assert set(j["attained_at"]) == {"q", "qd", "qdd"}


def test_small_M_fails_and_says_by_how_much(capsys):
    from designkit.cli import main

    code = main(["verify", "specs/hierarchy-simnog-small-M.yaml", "--json"])
    assert code == 1
    obj = json.loads(capsys.readouterr().out)
    check = next(c for c in obj["checks"] if c["name"] == "pid_sm_hierarchy")
    assert check["passed"] is False
    bound = obj["pid_sliding_mode"]["bound"]["per_joint"]
    assert f"below the bound by {bound[0] - 4.0:.4g} N·m" in check["detail"]


def test_tracking_form_takes_the_later_joint_at_the_trajectorys_acceleration():
    """Figure 3.2 per joint: on slm = 0 the joint follows its quintic, whose largest acceleration is
    (10 sqrt(3)/3) A/T^2 (at t = T (3 -+ sqrt(3))/6): joint 1's box has joint 2 there; the loop stays in its layers."""
    spec = _design(**{"controller.form": "tracking", "simulation.step": None,
                      "simulation.trajectory": {"kind": "quintic", "amplitude": [0.5, -0.3], "duration": 2.0}})
    result = run(spec)
    info = result.design.data
    assert info.acceleration_rows[0][1] == pytest.approx(10 * np.sqrt(3) / 3 * 0.3 / 2.0**2, rel=1e-4)
    assert all(c.passed for c in result.checks if c.required)


def test_report_section_has_one_row_per_joint_from_the_last_to_the_first(simnog):
    from designkit.families.pid_sliding_mode.robot_family import section

    info = simnog.design.data
    sec = section(simnog)
    (table,) = sec.questions[0].tables
    assert [row[0] for row in table.rows] == ["joint 2", "joint 1"]
    for row, i in zip(table.rows, (1, 0), strict=True):
        assert row[2] == f"{info.bound[i]:.4g} N·m" and row[3] == f"{info.sampled[i]:.4g} N·m"
        assert "rad/s²" in row[1] and "q =" in row[4]
    assert "pid_sm" not in " ".join(sec.questions[0].sentences)  # words, not identifiers
