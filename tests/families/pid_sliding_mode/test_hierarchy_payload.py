"""The hierarchy of control over a box of the arm's parameters (the SIMNOG arm whose link 2 mass is anywhere in
[2, 4] kg), against routes that do not use the enclosure:

* xi from the textbook closed form of the two-link arm with the sampled mass, and the residual of the nominal
  gravity feed-forward written from the link data (both checked against the model first);
* along simulated runs of the designed (nominal) loop on random interior arms of the box (hypothesis), xi from the
  run's states, finite-difference accelerations and the closed form never exceeds the bound where the run is inside
  the motion box; an arm outside the box leaves the run check undecided;
* a degenerate box at the nominal mass gives the example's bound without a box, bit for bit.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from designkit.families import check_rules
from designkit.models.robot_plant import zoo_plant
from designkit.pipeline import design, run
from designkit.schema.loader import LoadedSpec, parse_spec
from designkit.simulation.run import build
from designkit.verification.suite import run_checks
from tests.families.pid_sliding_mode.test_hierarchy import _closed_form_2r

PAYLOAD = "specs/hierarchy-simnog-payload.yaml"


def _spec(path: str = PAYLOAD, **changes) -> LoadedSpec:
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


def _gravity_2r(P: dict):
    """g(q) of the two-link arm (base -y gravity, uniform links): the derivative of m g y_c over both links."""
    m1, m2, l1, l2, g = (P[k] for k in ("m1", "m2", "d1", "d2", "g"))

    def grav(q: np.ndarray) -> np.ndarray:
        c1, c12 = np.cos(q[..., 0]), np.cos(q[..., 0] + q[..., 1])
        return np.stack([g * ((m1 / 2 + m2) * l1 * c1 + m2 * l2 / 2 * c12), g * m2 * l2 / 2 * c12], -1)

    return grav


def _xi(P_true: dict, P_nom: dict, Dh, f, q, qd, qdd) -> np.ndarray:
    """xi by the closed form: D^ q'' + f q' - (tau - g^) with the true arm's tau and the nominal g^."""
    D, c = _closed_form_2r(P_true)
    fv = np.array([P_true["f1"], P_true["f2"]])
    tau = np.einsum("...ij,...j->...i", D(q), qdd) + c(q, qd) + _gravity_2r(P_true)(q) + fv * qd
    return Dh * qdd + f * qd - (tau - _gravity_2r(P_nom)(q))


@pytest.fixture(scope="module")
def payload():
    return run(_spec())


def test_the_gravity_closed_form_is_the_models():
    plant = zoo_plant("planar2r").with_params(m2=3.7, g=9.7)
    P = {p.name: p.value for p in plant.parameters}
    q = np.random.default_rng(1).uniform(-3, 3, (40, 2))
    np.testing.assert_allclose(_gravity_2r(P)(q), plant.robot.gravity_torque(q, p=plant.model_parameters()),
                               atol=1e-12)


def test_the_bound_covers_the_closed_form_at_every_mass_of_the_box(payload):
    info = payload.design.data
    nominal = {p.name: p.value for p in payload.design.plant.parameters}
    assert list(info.parameter_box) == [{"name": "m2", "index": 1, "low": 2.0, "high": 4.0, "nominal": 3.0,
                                      "unit": "kg", "meaning": "link 2 mass"}]
    ws = info.workspace
    lo, hi, V = np.array(ws["low"]), np.array(ws["high"]), np.array(ws["velocity"])
    Dh = np.array([lk.inertia for lk in info.links])
    f = np.array([lk.damping for lk in info.links])
    rng = np.random.default_rng(11)
    N = 4000
    for i in range(2):
        A = np.array(info.acceleration_rows[i])
        worst = 0.0
        for m2 in np.concatenate([[2.0, 4.0], rng.uniform(2.0, 4.0, 8)]):
            q = lo + (hi - lo) * rng.random((N, 2))
            qd = V * rng.choice([-1.0, 1.0], (N, 2)) * np.where(rng.random((N, 2)) < 0.5, 1.0, rng.random((N, 2)))
            qdd = A * rng.choice([-1.0, 1.0], (N, 2))
            xi = _xi({**nominal, "m2": m2}, nominal, Dh, np.array(f), q, qd, qdd)[:, i]
            worst = max(worst, float(np.max(np.abs(xi))))
        assert worst <= info.bound[i]
        # where the bound says it is attained: in the box, and the closed form gives the value there
        at = info.enclosure.argmax[i]
        m2 = at["p"][1]
        assert 2.0 <= m2 <= 4.0
        there = abs(_xi({**nominal, "m2": m2}, nominal, Dh, f, *(np.array(at[k]) for k in ("q", "qd", "qdd")))[i])
        assert there == pytest.approx(info.sampled[i], rel=1e-9)
        assert info.bound[i] <= 1.05 * max(worst, there)  # not vacuous on this arm
        # the heavier arm sets it: more inertia, coupling and gravity residual than the nominal arm's bound
        assert m2 == 4.0 and info.bound[i] > [5.892, 5.723][i]


def test_a_degenerate_box_at_the_nominal_mass_gives_the_examples_bound():
    today = design(_spec("specs/hierarchy-simnog.yaml")).data
    held = design(_spec("specs/hierarchy-simnog.yaml", **{"plant.uncertainty": {"m2": [3.0, 3.0]}}))
    held = held.data
    assert held.bound == today.bound and held.sampled == today.sampled and held.M == today.M
    assert held.enclosure.boxes == today.enclosure.boxes


def test_the_example_verifies_through_the_load_change_and_says_over_which_box(payload):
    checks = {c.name: c for c in payload.checks}
    assert all(c.passed for c in payload.checks if c.required)
    assert "m2 ∈ [2, 4] kg (link 2 mass; nominal 3)" in checks["pid_sm_hierarchy"].detail
    assert "m2 = 3 kg until 1.5 s, then 4 kg" in checks["pid_sm_robot_xi"].detail
    # the re-check drew the mass from the box too
    assert all(2.0 <= at["p"][1] <= 4.0 for at in checks["pid_sm_hierarchy"].certificate["recheck_at"])


def test_json_names_the_box_and_the_mass_where_the_bound_is_attained(capsys):
    from designkit.cli import main

    assert main(["verify", PAYLOAD, "--json", "--jobs", "1"]) == 0
    obj = json.loads(capsys.readouterr().out)["pid_sliding_mode"]
    assert obj["bound"]["parameter_box"] == {"m2": {"low": 2.0, "high": 4.0, "nominal": 3.0, "unit": "kg"}}
    for j in obj["joints"]:
        assert set(j["attained_at"]) == {"q", "qd", "qdd", "parameters"}
        assert 2.0 <= j["attained_at"]["parameters"]["m2"] <= 4.0


def _true_run(spec: LoadedSpec, m2: float):
    dsn = design(spec)
    arm = dsn.plant.with_params(m2=m2)
    sim = build(spec.spec, dsn, plant=arm).run()
    checks = run_checks(spec.spec, dsn, sim, plant=arm, rules=check_rules(dsn.kind))
    return dsn, arm, sim, {c.name: c for c in checks}


def _xi_along(dsn, arm, sim) -> tuple[np.ndarray, np.ndarray]:
    info = dsn.data
    nominal = {p.name: p.value for p in dsn.plant.parameters}
    t, x = np.asarray(sim.time), np.asarray(sim.state)
    q, qd = x[:, :2], x[:, 2:]
    qdd = np.gradient(qd, t, axis=0)
    Dh = np.array([lk.inertia for lk in info.links])
    f = np.array([lk.damping for lk in info.links])
    xi = _xi({p.name: p.value for p in arm.parameters}, nominal, Dh, f, q, qd, qdd)
    ws = info.workspace
    state_in = (np.all((q >= np.array(ws["low"])) & (q <= np.array(ws["high"])), axis=1)
                & np.all(np.abs(qd) <= np.array(ws["velocity"]), axis=1))
    inside = np.column_stack([state_in & np.all(np.abs(qdd) <= np.array(info.acceleration_rows[i]), axis=1)
                              for i in range(2)])
    inside[:3] = False  # the step's instant: a finite difference across it is no acceleration of the run
    return xi, inside


@settings(max_examples=4, deadline=None, phases=(Phase.explicit, Phase.generate),
          suppress_health_check=[HealthCheck.too_slow])
@given(m2=st.floats(2.0, 4.0), s1=st.floats(0.1, 0.55), s2=st.floats(-0.6, -0.15))
def test_runs_of_interior_arms_stay_below_the_bound_inside_the_box(m2, s1, s2):
    spec = _spec(**{"simulation.step": [s1, s2], "simulation.duration": 1.2, "simulation.plant_change": None})
    dsn, arm, sim, checks = _true_run(spec, m2)
    info = dsn.data
    xi, inside = _xi_along(dsn, arm, sim)
    for i in range(2):
        assert inside[:, i].mean() > 0.5
        peak = float(np.max(np.abs(xi[inside[:, i], i])))
        assert peak <= info.bound[i] * (1 + 1e-3) + 1e-3, (i, peak, info.bound[i])
    assert checks["pid_sm_robot_xi"].passed is True and checks["pid_sm_robot_in_band"].passed is True
    assert f"m2 = {m2:.4g} kg" in checks["pid_sm_robot_xi"].detail


def test_an_arm_outside_the_box_leaves_the_run_check_undecided():
    """m2 = 5 kg is outside [2, 4]: the certificate does not describe that arm, whatever its run meets."""
    spec = _spec(**{"simulation.duration": 1.0, "simulation.plant_change": None})
    _, _, _, checks = _true_run(spec, 5.0)
    xi_check = checks["pid_sm_robot_xi"]
    assert xi_check.passed is None and list(xi_check.certificate["inside_fraction"]) == [0.0, 0.0]
