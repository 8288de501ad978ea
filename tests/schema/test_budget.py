"""The work budget (:mod:`designkit.schema.budget`): every example within it, costly in-range specs refused in
well under a second naming the field that drives the cost, ``--budget`` and ``budget=`` letting them through.

The estimate's parts are checked against independent counts: the steps of a run with a given ``dt``
(``duration / dt``), the corners of a box (``2^k``), the lattice (``grid^k``), the joints of a URDF (its
``<joint>`` elements of a moving type, counted with ElementTree) and of a built-in robot (the model built).
"""

from __future__ import annotations

import time
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
import yaml

from designkit.cli import main
from designkit.errors import SpecError
from designkit.pipeline import run
from designkit.schema import budget
from designkit.schema.loader import load_spec, parse_spec
from tests.cli_input import assert_bad_input

ROOT = Path(__file__).resolve().parents[2]
SPECS = sorted((ROOT / "specs").glob("*.yaml"))


def _doc(name: str) -> dict:
    return yaml.safe_load((ROOT / "specs" / f"{name}.yaml").read_text())


def _text(doc: dict) -> str:
    return yaml.safe_dump(doc, sort_keys=False)


def _chain(n: int) -> dict:
    rows = [{"a": 0.2, "alpha": 1.5708 if i % 2 else -1.5708, "d": 0.05, "mass": 1.0, "com": [-0.1, 0, 0],
             "inertia": [0.01, 0.01, 0.01, 0, 0, 0]} for i in range(n)]
    return {"name": f"chain{n}", "plant": {"kind": "robot", "dh": rows},
            "controller": {"kind": "computed_torque", "damping": 1.0, "natural_frequency": 10},
            "simulation": {"duration": 2.0, "trajectory": {"kind": "quintic", "amplitude": 0.1, "duration": 1.0}}}


def _samples() -> dict:
    doc = _doc("puma560-computed-torque")
    doc["plant"]["uncertainty"] = {"m6": [1.9, 2.1], "samples": 100000}
    return doc


def _corners() -> dict:
    doc = _doc("puma560-computed-torque")
    doc["plant"]["uncertainty"] = {f"m{j}": [1.0, 2.0] for j in range(1, 7)} | {"grid": 3, "samples": 0}
    doc["plant"]["uncertainty"].update({f"f{j}": [0.5, 1.0] for j in range(1, 7)})
    return doc


def _scara() -> dict:
    """``grid: 1001`` over all twelve of the SCARA's parameters (each +-10 %)."""
    from designkit.models.robots import zoo_module

    doc = _doc("scara-decentralized-pid")
    values = zoo_module("scara").DEFAULTS
    doc["plant"]["uncertainty"] = {k: [0.9 * v, 1.1 * v] if v > 0 else [v - 0.1, v + 0.1] for k, v in values.items()}
    doc["plant"]["uncertainty"]["grid"] = 1001
    return doc


def _khz() -> dict:
    doc = _doc("puma560-computed-torque")
    doc["simulation"] = {"duration": 20.0, "initial_position": doc["simulation"]["initial_position"],
                         "trajectory": {"kind": "sine", "amplitude": 0.01, "frequency": 1000}}
    return doc


def _cvodes() -> dict:
    doc = _doc("puma560-computed-torque")
    doc["numerics"] = {"integrator": "cvodes", "rtol": 1e-14}
    return doc


def _members():
    for path in SPECS:
        loaded = load_spec(path)
        if loaded.is_comparison:
            yield from ((f"{path.stem}[{label}]", m.spec) for label, m in loaded.members())
        else:
            yield path.stem, loaded.spec


def test_every_example_spec_is_within_the_default_budget():
    over = [f"{name}: {est.seconds:.3g} s ({est.driver.what}, {est.driver.key})"
            for name, spec in _members() for est in [budget.estimate(spec, ROOT / "specs")]
            if est.seconds > budget.DEFAULT_BUDGET]
    assert not over, over


COSTLY = [
    (_samples, "plant.uncertainty.samples", None),  # 10^5 full simulations of the PUMA 560
    (_corners, "plant.uncertainty", None),  # twelve uncertain parameters: 4096 corners re-simulated
    (lambda: _chain(40), "plant.dh", None),  # a 40-joint model
    (_scara, "plant.uncertainty", None),  # 4096 corners of the SCARA's twelve parameters: the common Lyapunov LMI
    (_cvodes, "numerics.rtol", 5.0),  # CVODES at rtol 1e-14: ~9 s estimated, ~6 s measured
    (_khz, "simulation.trajectory.frequency", 10.0),  # a kHz sine: 2e6 steps of the PUMA, ~26 s estimated
]


@pytest.mark.parametrize(("make", "key", "seconds"), COSTLY, ids=[k for _, k, _ in COSTLY])
def test_a_costly_in_range_spec_is_refused_in_under_a_second_naming_its_field(tmp_path, capsys, make, key, seconds):
    text = _text(make())
    parse_spec(text)  # inside every range: the spec itself is valid
    main(["verify", str(ROOT / "specs" / "posspeed-link.yaml"), "--jobs", "1", "--budget", "0.001"])  # warm imports
    capsys.readouterr()
    start = time.process_time()
    assert_bad_input(tmp_path, capsys, text, f"{key}: the run needs ~",
                     extra=[] if seconds is None else ["--budget", f"{seconds:g}"])
    assert time.process_time() - start < 1.0


def test_the_refusal_states_the_estimate_the_budget_and_the_flag(tmp_path, capsys):
    spec = tmp_path / "spec.yaml"
    spec.write_text(_text(_samples()))
    assert main(["verify", str(spec), "--jobs", "1"]) == 2
    err = capsys.readouterr().err
    assert "model evaluations (~" in err and "over the budget of 60 s" in err and "raise it with --budget " in err
    assert "100000 samples" in err
    suggested = float(err.split("--budget ")[1].split()[0])
    assert suggested > budget.estimate(parse_spec(_text(_samples())).spec).seconds


def test_budget_lets_a_spec_through_and_a_tight_one_refuses_it(tmp_path, capsys):
    path = ROOT / "specs" / "posspeed-link.yaml"
    est = budget.estimate(load_spec(path).spec)
    tight = est.seconds / 2
    assert main(["verify", str(path), "--jobs", "1", "--budget", f"{tight:g}"]) == 2
    err = capsys.readouterr().err
    assert f"over the budget of {tight:g} s" in err and err.count("\n") == 1
    assert main(["verify", str(path), "--jobs", "1", "--budget", f"{2 * est.seconds:g}"]) == 0
    out = tmp_path / "out"
    assert main(["synth", str(path), "--jobs", "1", "--no-report", "--out", str(out), "--budget",
                 f"{tight:g}"]) == 2
    assert not out.exists()


def test_budget_in_python(tmp_path):
    loaded = load_spec(ROOT / "specs" / "posspeed-link.yaml")
    est = budget.estimate(loaded.spec)
    with pytest.raises(SpecError) as info:
        run(loaded, budget=est.seconds / 2)
    assert "over the budget" in info.value.message
    assert run(loaded, budget=2 * est.seconds).verified
    for bad in (0, -1, float("nan"), "60", True):
        with pytest.raises(SpecError) as info:
            run(loaded, budget=bad)
        assert info.value.path == "budget"


@pytest.mark.parametrize("value", ["0", "-5", "nan", "inf", "soon"])
def test_a_bad_budget_flag_exits_2(capsys, value):
    with pytest.raises(SystemExit) as info:
        main(["verify", str(ROOT / "specs" / "posspeed-link.yaml"), "--budget", value])
    assert info.value.code == 2
    assert "--budget" in capsys.readouterr().err


def test_a_comparison_is_judged_on_its_members_together():
    loaded = load_spec(ROOT / "specs" / "mrac-vs-selftune.yaml")
    members = [m.spec for _, m in loaded.members()]
    total = sum(budget.estimate(s).seconds for s in members)
    one = max(budget.estimate(s).seconds for s in members)
    assert one < total
    with pytest.raises(SpecError) as info:
        run(loaded, budget=(one + total) / 2)  # each member fits alone, not together
    assert "controllers need ~" in info.value.message


# ----------------------------------------------------------------------------- the estimate's parts


def test_the_steps_of_a_given_dt_are_duration_over_dt():
    doc = _doc("posspeed-link")
    doc["simulation"] = {"dt": 1e-4, "duration": 3.0}
    steps = budget.steps_of(parse_spec(_text(doc)).spec)
    assert steps.count == pytest.approx(3.0 / 1e-4)
    assert steps.key == "simulation.dt"


def test_the_default_step_follows_the_fastest_rate_the_spec_shows():
    doc = _khz()
    steps = budget.steps_of(parse_spec(_text(doc)).spec)
    # the simulator's rule: 0.02 / (2 pi 1000 Hz) = 3.18e-6 s, rounded down to 2.5e-6 s
    assert steps.dt == pytest.approx(2.5e-6)
    assert steps.count == pytest.approx(min(20.0 / 2.5e-6, budget.MAX_STEPS))


def test_runs_count_the_box_corners_and_the_samples():
    spec = parse_spec(_text(_corners())).spec
    k = len(spec.plant.uncertainty.intervals)
    runs, key, words = budget._runs(spec, budget._family(spec))
    assert runs == 2 + 2**k  # the nominal and small-signal runs, and every corner (tracking_bounds)
    assert key == "plant.uncertainty" and f"{2**k} corners" in words
    _, _, lattice = budget._uncertainty(spec)
    per_axis = max(g for g in range(2, 4) if g**k <= 100_000)  # grid 3, capped at 100,000 plants: 2 per axis
    assert lattice == per_axis**k == 4096


def test_the_lattice_is_capped_as_the_robustness_check_caps_it():
    from designkit.pipeline import plant
    from designkit.verification.robustness import box_from_uncertainty

    doc = _doc("scara-decentralized-pid")
    doc["plant"]["uncertainty"] = {f"m{j}": [1.0, 2.0] for j in range(1, 5)} | {"grid": 1001}
    loaded = parse_spec(_text(doc))
    box = box_from_uncertainty(plant(loaded), loaded.spec.plant.uncertainty)
    assert budget._uncertainty(loaded.spec)[2] == box.points_per_axis ** 4 == 17 ** 4


def test_the_joint_count_of_a_urdf_is_its_moving_joints(tmp_path):
    from designkit.schema.joint_count import joint_count

    urdf = ROOT / "src" / "designkit" / "models" / "robots" / "puma560.urdf"
    moving = [j for j in ET.parse(urdf).getroot().iter("joint") if j.get("type") in ("revolute", "prismatic",
                                                                                      "continuous")]
    doc = {"kind": "robot", "urdf": str(urdf)}
    from designkit.spec.plants import RobotPlantSpec

    assert joint_count(RobotPlantSpec.model_validate(doc)) == len(moving) == 6


@pytest.mark.parametrize("name", ["onelink", "planar2r", "scara", "puma560"])
def test_the_joint_count_of_a_built_in_robot_is_its_models(name):
    from designkit.models.robots import robot
    from designkit.schema.joint_count import joint_count
    from designkit.spec.plants import RobotPlantSpec

    assert joint_count(RobotPlantSpec.model_validate({"kind": "robot", "robot": name})) == robot(name).n


def test_a_wrong_per_joint_list_is_refused_before_the_model_is_built(tmp_path, capsys, monkeypatch):
    import designkit.spec.plant_builder as builder

    def never(*args, **kwargs):
        raise AssertionError("the model was built")

    monkeypatch.setattr(builder, "plant_from_spec", never)
    doc = _chain(40)
    doc["simulation"]["initial_position"] = [0.0] * 39
    assert_bad_input(tmp_path, capsys, _text(doc), "simulation.initial_position: needs one value per joint (40), "
                     "got 39")
    doc = _chain(40)
    doc["simulation"]["trajectory"]["amplitude"] = [0.1] * 41
    assert_bad_input(tmp_path, capsys, _text(doc), "simulation.trajectory.amplitude: needs one value per joint (40)")
    doc = _chain(3)
    doc["controller"]["damping"] = [1.0, 1.0]
    assert_bad_input(tmp_path, capsys, _text(doc), "controller.damping: needs one value per joint (3), got 2")


def test_the_box_runs_and_the_refinement_are_counted():
    """A family judging the box by its own run counts its whole run (trials included) at up to 16 corners and 16
    samples; every lattice counts the plants its refinement may add."""
    from designkit.schema.loader import parse_spec as parse
    from designkit.verification.checks.box_runs import MAX_CORNERS, MAX_SAMPLES
    from designkit.verification.refine import MAX_REFINED_PLANTS

    assert (budget.BOX_CORNERS, budget.BOX_SAMPLES, budget.REFINED_CAP) == (MAX_CORNERS, MAX_SAMPLES,
                                                                            MAX_REFINED_PLANTS)
    text = ("name: b\nplant: {kind: link, Km: 2.0, tau: 0.5%s}\n"
            "controller: {kind: self_tuning, sampling_period: 0.01, "
            "poles: [-4, -5], nominal: {Km: 1.0, tau: 1.0}}\n"
            "simulation: {duration: 8, trajectory: {kind: square, amplitude: 0.5, period: 2}}\n")
    bare = parse(text % "").spec
    boxed = parse(text % ", uncertainty: {Km: [1.5, 2.5], tau: [0.4, 0.6], samples: 3}").spec
    fam = budget._family(bare)
    runs_bare = budget._runs(bare, fam)[0]
    runs_boxed = budget._runs(boxed, fam)[0]
    # own count: 4 corners (also counted once for the arm's answers) and 3 samples, each the nominal run and the
    # small-signal run
    assert runs_boxed - runs_bare == 4 + (4 + 3) * 2
    lattice = parse("name: l\nplant: {kind: link, Km: 2.0, tau: 0.5, uncertainty: {Km: [1.5, 2.5], grid: 3}}\n"
                    "controller: {kind: pid_servo, poles: [-4, -5, -20], zero: -3}\n").spec
    term = next(t for t in budget.estimate(lattice, joints=1).terms if t.what == "lattice")
    assert term.evaluations == (3 + MAX_REFINED_PLANTS) * budget.LINEARIZATION * budget.size(1)
