"""The ``workspace`` check: each joint loop of a decentralized PID over a box of configurations.

Independent routes: SymPy for the stability conditions (the joint loop's matrix and its Routh
array derived here from the plant equations), the hand-derived closed loops of ``tests/oracles.py``
and NumPy eigenvalues for the verdicts, the SCARA's ``D_11`` written in closed form (checked against
the model, then swept on a dense grid) and brute-force sampling of the PUMA's ``D_ii`` for the
ranges, and the pole-placement identity ``tau_crit = tau* S1 S2 / S3`` for the critical inertia.
"""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest
import sympy as sp
from hypothesis import assume, event, given, settings
from hypothesis import strategies as st

from designkit.cli import main
from designkit.families.decentralized_pid import FAMILY
from designkit.families.decentralized_pid import workspace_check as workspace_certificate
from designkit.families.decentralized_pid.workspace_check import (
    ConditionValue,
    VertexVerdict,
    box_verdict,
    joint_workspace,
    stable_tau_interval,
    workspace_check,
)
from designkit.models.link import LinkPlant
from designkit.models.robot_plant import zoo_plant
from designkit.models.robots.scara import DEFAULTS as SCARA
from designkit.pipeline import design as design_of
from designkit.pipeline import run
from designkit.schema.loader import parse_spec
from designkit.schema.spec import Spec
from designkit.synthesis.pid import servo_conditions, servo_gains
from designkit.verification.suite import applicable
from tests import oracles
from tests.cli_input import assert_bad_input
from tests.tolerances import TOL
from tests.verification.helpers import pole_sets

# The SCARA designed with lightly damped poles at the folded elbow (q2 = pi/2, D_11 = 1.52 kg*m^2):
# tau may grow by a factor S1 S2 / S3 = 1.53 before the loop loses stability, but D_11 reaches
# 2.50 kg*m^2 (1.65 times more) at the stretched elbow q2 = 0, inside the workspace.
FRAGILE = """\
name: scara-fragile
plant: {kind: robot, robot: scara}
controller:
  kind: decentralized_pid
  poles: ['-0.6+5j', '-0.6-5j', -5]
  configuration: [0, 1.5708, 0.1, 0]
  workspace: {low: [-1, -0.5, 0, -1], high: [1, 1.6, 0.21, 1]}
simulation: {duration: 2.0, step: 0.05, initial_position: [0, 1.5708, 0.1, 0]}
"""

ROBUST = """\
name: scara-robust
plant: {kind: robot, robot: scara}
controller:
  kind: decentralized_pid
  poles: [-4, -5, -20]
  zero: -3
  configuration: [0, 1.5708, 0.1, 0]
  workspace: joint_limits
simulation: {duration: 2.0, step: 0.05, initial_position: [0, 1.5708, 0.1, 0]}
"""


def _scara_d11(q2: np.ndarray) -> np.ndarray:
    """``D_11`` of the SCARA in closed form (kg*m^2), written from its description: link 1 a rod about
    its end (m1 a1^2/3), link 2 a rod (m2 a2^2/12) whose centre is |a1 e1 + a2/2 e2| from the axis, the
    quill and the wrist at |a1 e1 + a2 e2|, plus their own moments about the vertical axis."""
    m1, m2, m3, m4, a1, a2 = (SCARA[k] for k in ("m1", "m2", "m3", "m4", "a1", "a2"))
    c = np.cos(q2)
    return (m1 * a1**2 / 3 + m2 * a2**2 / 12 + m2 * (a1**2 + a2**2 / 4 + a1 * a2 * c)
            + (m3 + m4) * (a1**2 + a2**2 + 2 * a1 * a2 * c) + m3 * 0.01**2 / 2 + m4 * 0.04**2 / 2)


def _max_re(gains: dict, Km: float, tau: float) -> float:
    """Spectral abscissa (1/s) of the hand-derived servo loop on the link (Km, tau)."""
    A = oracles.servo_closed_loop({"K4": 0.0, **gains}, LinkPlant(Km=Km, tau=tau)).A
    return float(np.max(np.linalg.eigvals(A).real))


def _symmetric(poles) -> tuple[float, float, float]:
    p = np.asarray(poles, complex)
    return (float(p.sum().real), float((p[0] * p[1] + p[0] * p[2] + p[1] * p[2]).real), float(np.prod(p).real))


# ----------------------------------------------------------------------------- the conditions (SymPy)


def test_conditions_are_the_routh_array_of_the_joint_loop_derived_with_sympy():
    s, Km, tau, K1, K2, K3 = sp.symbols("s Km tau K1 K2 K3", real=True)
    # x1' = x2, x2' = -x2/tau + (Km/tau) u, x3' = x1, u = -K1 x1 - K2 x2 - K3 x3 (reference set to zero)
    A = sp.Matrix([[0, 1, 0], [-Km * K1 / tau, -(1 + Km * K2) / tau, -Km * K3 / tau], [1, 0, 0]])
    p = sp.Poly(sp.expand(tau * (s * sp.eye(3) - A).det()), s)
    a3, a2, a1, a0 = p.all_coeffs()
    assert sp.simplify(a3 - tau) == 0
    # Routh first column of a3 s^3 + a2 s^2 + a1 s + a0
    column = [a3, a2, sp.simplify((a2 * a1 - a3 * a0) / a2), a0]
    # the module's conditions, with numbers for the gains, against the symbolic derivation: C1 = a2,
    # C2 = a0/Km, C3 = (a2 a1 - a3 a0)/Km, each affine in (Km, tau)
    expected = [column[1], column[3] / Km, sp.expand(column[2] * column[1] / Km)]
    for gains in ({"K1": 50.0, "K2": 6.75, "K3": 100.0}, {"K1": -3.0, "K2": -0.7, "K3": 2.5}):
        subs = {K1: gains["K1"], K2: gains["K2"], K3: gains["K3"]}
        for cond, expr in zip(servo_conditions(gains), expected, strict=True):
            poly = sp.Poly(sp.expand(expr.subs(subs)), Km, tau)
            assert poly.total_degree() <= 1  # affine in the plant parameters
            assert float(poly.coeff_monomial(1)) == pytest.approx(cond.constant, rel=TOL["algebra"])
            for name, sym in (("Km", Km), ("tau", tau)):
                assert float(poly.coeff_monomial(sym)) == pytest.approx(cond.coefficients.get(name, 0.0),
                                                                         rel=TOL["algebra"], abs=0.0)
    # and a1 = Km K1 > 0 is implied: K1 (1 + Km K2) > tau K3 > 0 with 1 + Km K2 > 0 forces K1 > 0
    assert sp.simplify(a1 - Km * K1) == 0


def test_critical_tau_is_the_pole_placement_identity():
    """For gains placing poles p at tau*, C3 reads tau < tau* S1 S2 / S3: an identity of the poles."""
    for poles, Km, tau0 in (([-4, -5, -20], 2.0, 0.5), ([-0.6 + 5j, -0.6 - 5j, -5], 1.0, 1.52), ([-3] * 3, 0.2, 0.5)):
        gains = servo_gains(LinkPlant(Km=Km, tau=tau0), poles, None)
        S1, S2, S3 = _symmetric(poles)
        low, high = stable_tau_interval(servo_conditions(gains), Km)
        assert low == 0.0
        assert high == pytest.approx(tau0 * S1 * S2 / S3, rel=TOL["algebra"])
        assert _max_re(gains, Km, high * (1 - 1e-6)) < 0 < _max_re(gains, Km, high * (1 + 1e-6))


# ----------------------------------------------------------------------------- the vertex argument against eigenvalues


@st.composite
def gains_and_boxes(draw):
    """Gains placed for a random nominal link (or perturbed away from it) and a (Km, tau) box around it."""
    poles = draw(pole_sets())
    Km0 = draw(st.floats(0.1, 10.0))
    tau0 = draw(st.floats(0.05, 5.0))
    gains = servo_gains(LinkPlant(Km=Km0, tau=tau0), poles, None)
    if draw(st.booleans()):  # also gains no pole placement produces (some destabilising), of comparable sizes
        factor = st.one_of(st.floats(-1.5, -0.05), st.floats(0.05, 1.5))
        gains = {k: v * draw(factor) for k, v in gains.items()}
    Km = sorted([Km0 * draw(st.floats(0.5, 1.0)), Km0 * draw(st.floats(1.0, 2.0))])
    tau = sorted([tau0 * draw(st.floats(0.2, 1.0)), tau0 * draw(st.floats(1.0, 20.0))])
    return gains, tuple(Km), tuple(tau), draw(st.integers(0, 2**31))


@settings(max_examples=150, deadline=None)
@given(case=gains_and_boxes())
def test_box_verdict_agrees_with_eigenvalues_everywhere_in_the_box(case):
    gains, Km, tau, seed = case
    ends = box_verdict(servo_conditions(gains), Km, tau)
    assume(all(abs(c.relative) > 1e-6 for v in ends for c in v.conditions))  # away from the boundary
    rng = np.random.default_rng(seed)
    points = np.column_stack([rng.uniform(*Km, size=40), rng.uniform(*tau, size=40)])
    abscissa = np.array([_max_re(gains, k, t) for k, t in points])
    corner_re = [_max_re(gains, v.Km, v.tau) for v in ends]
    scale = [np.linalg.norm(oracles.servo_closed_loop({"K4": 0.0, **gains}, LinkPlant(Km=v.Km, tau=v.tau)).A)
             for v in ends]
    assume(all(abs(re) > 1e-8 * a for re, a in zip(corner_re, scale, strict=True)))  # eigenvalues resolve the sign
    for v, re in zip(ends, corner_re, strict=True):  # each corner: conditions and eigenvalues agree
        assert v.passed is (re < 0), (v, re)
    if all(v.passed for v in ends):  # certified: every plant of the box is stable
        event("certified over the box")
        assert np.all(abscissa < 0)
    else:  # a failing corner is a real counterexample
        event("counterexample at a corner")
        assert any(re >= 0 for re in corner_re)


def test_box_verdict_corners_and_rounding():
    conds = servo_conditions({"K1": 1.0, "K2": 0.0, "K3": 1.0})  # C3 = 1 - tau
    ends = box_verdict(conds, (1.0, 3.0), (0.5, 1.0))
    assert [(v.Km, v.tau) for v in ends] == [(1.0, 1.0), (3.0, 1.0), (1.0, 0.5), (3.0, 0.5)]
    assert ends[0].passed is None  # C3 exactly zero at tau = 1: zero within rounding, undecided
    assert ends[2].passed is True
    assert box_verdict(conds, (1.0, 1.0), (2.0, 2.0))[0].passed is False
    assert len(box_verdict(conds, (1.0, 1.0), (0.5, 0.5))) == 1
    zero = box_verdict(servo_conditions({"K1": 1.0, "K2": 0.0, "K3": 0.0}), (1.0, 1.0), (0.5, 0.5))[0]
    assert zero.worst.label == "K3 > 0" and zero.passed is False  # a0 = 0: a root at s = 0, not asymptotically stable
    with pytest.raises(ValueError, match="Km_low"):
        box_verdict(conds, (2.0, 1.0), (0.5, 1.0))
    assert ConditionValue("c", "", 0.0, 0.0).status == -1
    unstable = servo_conditions({"K1": 1.0, "K2": -2.0, "K3": 1.0})  # 1 + Km K2 = -1 at Km = 1: no tau helps
    assert stable_tau_interval(unstable, 1.0) == (0.0, 0.0)
    assert _max_re({"K1": 1.0, "K2": -2.0, "K3": 1.0}, 1.0, 0.01) > 0 and _max_re({"K1": 1.0, "K2": -2.0,
                                                                                  "K3": 1.0}, 1.0, 100.0) > 0


# ----------------------------------------------------------------------------- ranges against brute force


def test_scara_range_against_a_dense_grid_of_the_closed_form_d11():
    plant = zoo_plant("scara")
    rng = np.random.default_rng(3)
    Q = rng.uniform(-3, 3, size=(50, 4))
    model = plant.robot.mass_matrix(Q, p=plant.model_parameters())[:, 0, 0]
    assert np.allclose(model, _scara_d11(Q[:, 1]), rtol=TOL["algebra"], atol=0)  # the oracle is the model's D_11

    design = design_of(parse_spec(FRAGILE))
    ws = design.data.workspace
    joint = joint_workspace(design, 0, ws["low"], ws["high"], samples=ws["samples"], tolerance=1e-9)
    dense = _scara_d11(np.linspace(ws["low"][1], ws["high"][1], 200_001))
    # proven: every value of the closed form lies inside, and the bounds are within the tolerance of it
    assert joint.inertia[0] <= dense.min() and joint.inertia[1] >= dense.max()
    assert joint.inertia[0] == pytest.approx(dense.min(), rel=2e-9)
    assert joint.inertia[1] == pytest.approx(dense.max(), rel=2e-9)  # the grid's own error is ~1e-11 here
    for k in (0, 1):  # the witnesses: attained where reported, inside the box
        q = joint.configurations[k]
        assert np.all(q >= np.array(ws["low"])) and np.all(q <= np.array(ws["high"]))
        assert _scara_d11(q[1]) == pytest.approx(joint.attained[k], rel=TOL["algebra"])
        assert abs(joint.attained[k] - joint.inertia[k]) <= 1e-9 * abs(joint.attained[k])
    assert joint.tau == pytest.approx(np.array(joint.inertia) / SCARA["f1"], rel=TOL["algebra"])
    assert joint.Km == 1.0 / SCARA["f1"]
    assert joint.sampled[1] <= dense.max() + 1e-12  # the sampled estimate is an inner one


def test_puma_ranges_proven_against_brute_force_sampling():
    plant = zoo_plant("puma560")
    limits = np.array(plant.joint_limits)
    low, high = limits[:, 0] / 2, limits[:, 1] / 2
    spec = parse_spec("name: p\nplant: {kind: robot, robot: puma560}\ncontroller: {kind: decentralized_pid, "
                      f"poles: [-4, -5, -20], workspace: {{low: {low.tolist()}, high: {high.tolist()}}}}}\n"
                      "simulation: {step: 0.01}\n")
    design = design_of(spec)
    check = workspace_check(design)
    rng = np.random.default_rng(11)
    Q = rng.uniform(low, high, size=(60_000, 6))
    D = plant.robot.mass_matrix(Q, p=plant.model_parameters())
    assert check.certificate["rigorous_range"] is True
    for i, row in enumerate(check.certificate["joints"]):
        d_min, d_max = row["inertia_range"]
        sampled = D[:, i, i]
        # proven for the exact model; the only slack is the samples' own floating-point rounding (~1e-15 relative)
        rounding = 1e-13 * np.abs(sampled).max()
        assert d_min <= sampled.min() + rounding and d_max >= sampled.max() - rounding
        for key, value, bound in (("q_at_min", row["inertia_attained"][0], d_min),
                                  ("q_at_max", row["inertia_attained"][1], d_max)):
            q = np.array(row[key])
            assert np.all(q >= low) and np.all(q <= high)
            assert plant.robot.mass_matrix(q, p=plant.model_parameters())[i, i] == pytest.approx(value, rel=1e-12)
            assert abs(bound - value) <= 1e-3 * abs(value) + 1e-15
    assert check.passed is True


def test_a_peak_between_coarse_grid_points_is_failed_with_its_witness():
    """Gains whose critical inertia lies between the largest ``D_11`` of a 7-point grid (the ``samples``
    default, without its local polish) and the true maximum at the stretched elbow, which the grid steps
    over: the grid would call every loop stable, the proven check fails with the configuration."""
    low_q2, high_q2 = -0.5, 1.6
    grid = _scara_d11(np.linspace(low_q2, high_q2, 7))
    assert not np.any(np.isclose(np.linspace(low_q2, high_q2, 7), 0.0))
    target = 0.5 * (grid.max() + _scara_d11(0.0))  # the critical inertia we want
    S1, S2, S3 = _symmetric([complex("-0.6+5j"), complex("-0.6-5j"), -5])
    d_star = target / (S1 * S2 / S3)  # D_crit = D_11(q*) S1 S2 / S3 (test_critical_tau_is_the_pole_placement_identity)
    c = (d_star - _scara_d11(np.pi / 2)) / (_scara_d11(0.0) - _scara_d11(np.pi / 2))
    q2_star = float(np.arccos(c))
    spec = FRAGILE.replace("configuration: [0, 1.5708, 0.1, 0]", f"configuration: [0, {q2_star!r}, 0.1, 0]")
    design = design_of(parse_spec(spec))
    check = workspace_check(design)
    row = check.certificate["joints"][0]
    assert grid.max() < row["inertia_critical"] < _scara_d11(0.0)  # the grid says stable, the true max is not
    assert check.passed is False
    ev = check.certificate["evidence"]
    assert ev["joint"] == 1 and ev["inertia"] >= row["inertia_critical"]
    gains = {k: float(design.gains[k][0]) for k in ("K1", "K2", "K3")}
    assert _max_re(gains, 1 / SCARA["f1"], _scara_d11(ev["configuration"][1]) / SCARA["f1"]) > 0
    assert abs(ev["configuration"][1]) < 0.5 * (high_q2 - low_q2) / 6  # between the grid points around 0


# ----------------------------------------------------------------------------- the check on the SCARA


def test_gains_stable_at_the_nominal_configuration_fail_over_the_box_with_the_breaking_configuration():
    loaded = parse_spec(FRAGILE)
    result = run(loaded, simulate=False)
    checks = {c.name: c for c in result.checks}
    design = result.design
    gains = {k: float(design.gains[k][0]) for k in ("K1", "K2", "K3")}
    q_star = np.array(design.data.configuration)
    f1 = SCARA["f1"]
    # stable at the nominal configuration: the joint's own checks pass, and independently
    assert checks["pole_placement[joint1]"].passed and checks["routh_hurwitz[joint1]"].passed
    assert _max_re(gains, 1 / f1, _scara_d11(q_star[1]) / f1) < 0

    ws = checks["workspace"]
    assert ws.passed is False and ws.margin < 0
    ev = ws.certificate["evidence"]
    assert ev["joint"] == 1 and ev["condition"] == "K1 (1 + Km K2) - tau K3 > 0" and ev["value"] < 0
    q_bad = np.array(ev["configuration"])
    assert "joint 1 unstable at q = [" in ws.detail
    # the breaking configuration is in the box, and the loop is really unstable there (independent route)
    low, high = np.array(design.data.workspace["low"]), np.array(design.data.workspace["high"])
    assert np.all(q_bad >= low) and np.all(q_bad <= high)
    re_bad = _max_re(gains, 1 / f1, _scara_d11(q_bad[1]) / f1)
    assert re_bad > 0
    assert ev["spectral_abscissa"] == pytest.approx(re_bad, rel=TOL["eigenvalues"] ** 0.5)
    assert ev["inertia"] == pytest.approx(_scara_d11(q_bad[1]), rel=TOL["algebra"])
    # it is the worst configuration (stretched elbow, q2 = 0), and the other joints are fine
    assert q_bad[1] == pytest.approx(0.0, abs=1e-6)
    rows = ws.certificate["joints"]
    assert [r["passed"] for r in rows] == [False, True, True, True]
    json.dumps(ws.to_dict())


def test_robust_gains_pass_with_the_margin_of_the_critical_inertia():
    result = run(parse_spec(ROBUST), simulate=False)
    ws = next(c for c in result.checks if c.name == "workspace")
    assert ws.passed is True
    design = result.design
    S1, S2, S3 = _symmetric([-4, -5, -20])
    q2_limit = zoo_plant("scara").joint_limits[1]
    d_max = _scara_d11(0.0)  # cos q2 = 1 is inside the joint limits
    d_min = _scara_d11(max(abs(v) for v in q2_limit))
    rows = ws.certificate["joints"]
    for i, row in enumerate(rows):
        tau0 = design.data.links[i].tau
        f = design.data.links[i].damping
        assert row["tau_stable_s"][0] == 0.0
        assert row["tau_stable_s"][1] == pytest.approx(tau0 * S1 * S2 / S3, rel=TOL["algebra"])
        assert row["inertia_critical"] == pytest.approx(f * tau0 * S1 * S2 / S3, rel=TOL["algebra"])
        assert row["smallest_margin"] == pytest.approx(1 - row["inertia_range"][1] / (f * tau0 * S1 * S2 / S3),
                                                       rel=TOL["algebra"])
    lo, hi = rows[0]["inertia_range"]
    assert lo <= d_min and hi >= d_max and hi - d_max <= 1e-3 * d_max and d_min - lo <= 1e-3 * d_min
    assert rows[0]["q_at_smallest_margin"][1] == pytest.approx(0.0, abs=1e-6)
    assert [r["inertia_range"][1] - r["inertia_range"][0] <= 1e-12 * r["inertia_range"][1] for r in rows] == [
        False, True, True, True]
    ends = ws.certificate["ends"]
    assert len(ends) == 8 and all(e["spectral_abscissa"] < 0 and e["passed"] for e in ends)
    assert ws.margin == min(r["smallest_margin"] for r in rows)
    assert ws.certificate["rigorous_range"] is True and "ball arithmetic" in ws.certificate["range_method"]
    assert ws.certificate["workspace"]["source"] == {"low": "joint limits", "high": "joint limits"}


def test_joint_verdict_needs_both_routes():
    design = design_of(parse_spec(ROBUST))
    ws = design.data.workspace
    joint = joint_workspace(design, 0, ws["low"], ws["high"])
    assert joint.passed is True
    assert dataclasses.replace(joint, route_status=(1, 0)).passed is None
    assert dataclasses.replace(joint, route_status=(1, -1)).passed is None  # conditions say stable, eigenvalues not
    bad = VertexVerdict(joint.Km, joint.tau[1], (ConditionValue("C3", "", -1.0, 3.0),))
    # a failure is judged at the witness (an attained configuration), never at the proven bound alone
    assert dataclasses.replace(joint, ends=(joint.ends[0], bad), route_status=(1, -1)).passed is None
    assert dataclasses.replace(joint, attained_ends=(joint.ends[0], bad), attained_status=(1, -1)).passed is False
    assert dataclasses.replace(joint, attained_ends=(joint.ends[0], bad), attained_status=(1, 1)).passed is None


def test_the_check_runs_only_with_a_workspace():
    without = parse_spec(ROBUST.replace("  workspace: joint_limits\n", ""))
    design = design_of(without)
    assert design.data.workspace is None
    assert "workspace" not in applicable(design, without.spec, rules=FAMILY.checks)
    loaded = parse_spec(ROBUST)
    assert "workspace" in applicable(design_of(loaded), loaded.spec, rules=FAMILY.checks)


# ----------------------------------------------------------------------------- the spec


def test_workspace_spec_round_trips_through_the_json_schema():
    import jsonschema

    schema = Spec.model_json_schema()
    for text in (ROBUST, FRAGILE):
        loaded = parse_spec(text)
        data = json.loads(loaded.spec.model_dump_json())
        jsonschema.validate(data, schema)
        assert Spec.model_validate(data) == loaded.spec
    raw = {"name": "x", "plant": {"kind": "robot", "robot": "scara"},
           "controller": {"kind": "decentralized_pid", "poles": [-4, -5, -20], "workspace": "joint_limits"}}
    jsonschema.validate(raw, schema)  # the schema documents the string form too
    assert Spec.model_validate(raw).controller.workspace.low is None


def test_omitted_side_defaults_to_the_joint_limits():
    design = design_of(parse_spec(FRAGILE.replace("low: [-1, -0.5, 0, -1], ", "")))
    ws = design.data.workspace
    assert list(ws["low"]) == [lim[0] for lim in zoo_plant("scara").joint_limits]
    assert ws["source"] == {"low": "joint limits", "high": "spec"}


@pytest.mark.parametrize(
    ("replace", "by", "message"),
    [
        ("low: [-1, -0.5, 0, -1]", "low: [-1, -0.5, 0]",
         "controller.workspace.low: needs one value per joint (4), got 3"),
        ("high: [1, 1.6, 0.21, 1]", "high: [1, -0.5, 0.21, 1]",
         "controller.workspace.high[1]: must be greater than low (-0.5) for joint 2, got -0.5"),
        ("high: [1, 1.6, 0.21, 1]", "high: [1, 1.6, 0.3, 1]",
         "controller.workspace.high[2]: outside joint 3's limits [0, 0.21], got 0.3"),
        ("low: [-1, -0.5, 0, -1]", "low: -0.5",
         "controller.workspace.low: outside joint 3's limits [0, 0.21], got -0.5"),
        ("workspace: {low: [-1, -0.5, 0, -1], high: [1, 1.6, 0.21, 1]}", "workspace: everywhere",
         "controller.workspace: must be 'joint_limits' or a mapping {low, high, samples, tolerance}, got 'everywhere'"),
        ("high: [1, 1.6, 0.21, 1]", "high: [1, 1.6, 0.21, 1], hgih: 1", "controller.workspace.hgih: unknown key"),
        ("high: [1, 1.6, 0.21, 1]", "high: [1, 1.6, 0.21, .nan]", "controller.workspace.high: entry 3: must be finite"),
        ("high: [1, 1.6, 0.21, 1]}", "high: [1, 1.6, 0.21, 1], samples: 1}", "controller.workspace.samples:"),
        ("workspace: {low: [-1, -0.5, 0, -1], high: [1, 1.6, 0.21, 1]}", "workspace: [-1, 1]",
         "controller.workspace: Input should be a valid dictionary"),
    ],
)
def test_bad_workspace_exits_2_with_the_key_path(tmp_path, capsys, replace, by, message):
    text = FRAGILE.replace(replace, by)
    assert text != FRAGILE
    assert_bad_input(tmp_path, capsys, text, message)


def test_joint_limits_on_a_robot_without_limits_is_bad_input(tmp_path, capsys):
    spec = tmp_path / "spec.yaml"
    spec.write_text("name: w\nplant: {kind: robot, robot: planar2r}\n"
                    "controller: {kind: decentralized_pid, poles: [-4, -5, -20], workspace: joint_limits}\n")
    assert main(["synth", str(spec), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "controller.workspace.low: needed: joint 1 has no joint limits (qlim)" in err


def test_margin_sign_matches_verdict_across_damping():
    """Sweeping the damping of the dominant pair moves the critical inertia across D_11's range."""
    for sigma in (0.3, 0.6, 1.0, 2.0):
        text = FRAGILE.replace("'-0.6+5j', '-0.6-5j'", f"'-{sigma}+5j', '-{sigma}-5j'")
        design = design_of(parse_spec(text))
        check = workspace_check(design)
        S1, S2, S3 = _symmetric([complex(-sigma, 5), complex(-sigma, -5), -5])
        allowed = _scara_d11(1.5708) * S1 * S2 / S3  # critical D_11 from the poles alone
        expected_fail = bool(_scara_d11(0.0) > allowed)
        assert check.passed is (not expected_fail)
        assert bool(check.margin < 0) is expected_fail
        assert math.isfinite(check.margin)


def test_report_figure_draws_the_ranges_against_the_limits():
    from designkit.families.decentralized_pid.figures import workspace_figure

    result = run(parse_spec(FRAGILE), simulate=False)
    check = next(c for c in result.checks if c.name == "workspace")
    assert workspace_certificate.RULE.figures  # the report finds the figure through the family's rule
    figure = workspace_figure(result, check)
    assert figure.svg.lstrip().startswith("<?xml") and figure.filename == "fig-workspace.svg"
    assert f"{check.margin:.3g} on joint 1" in figure.caption
    assert workspace_figure(result, dataclasses.replace(check, data={})) is None
