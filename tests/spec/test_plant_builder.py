"""The spec's ``plant`` section, through ``parse_spec`` and ``plant_from_spec``.

Good sections must give the plant they describe. The check uses routes outside the spec layer:
the numeric zoo robots (``robots.robot(name, **values, friction=True)``) for a zoo robot with
overrides, a DH table and the packaged URDF, and the elastic link's ``DEFAULTS`` for the omitted
parameters. Bad sections must raise one ``SpecError`` with the exact key path and a one-line message.

Tolerance: ``TOL_EXACT`` (1e-10, scaled ``|x - ref| / (1 + |ref|)``), because these are two exact
routes to the same forward dynamics.
"""

from __future__ import annotations

import shutil
import textwrap
from importlib.resources import files
from pathlib import Path

import numpy as np
import pytest
import yaml
from pydantic import TypeAdapter

from designkit.errors import SpecError
from designkit.models.elastic import ElasticJointPlant
from designkit.models.link import LinkPlant
from designkit.models.plant import PlantBase
from designkit.models.robot_plant import RobotPlant
from designkit.models.robots import robot
from designkit.models.robots.elastic_link import DEFAULTS as ELASTIC_DEFAULTS
from designkit.schema.loader import parse_spec
from designkit.spec.plant_builder import plant_from_spec
from designkit.spec.plants import PlantSpec
from tests.models.support import scaled_error

TOL_EXACT = 1e-10

PLANAR2R_URDF = files("designkit.models.robots") / "planar2r.urdf"
LINK_CONTROLLER = "{kind: pid_servo, poles: [-4, -5, -20], zero: -3}"
ROBOT_CONTROLLER = "{kind: decentralized_pid, poles: [-4, -5, -20], zero: -3}"

# The planar2r zoo robot written as a DH table (values from its module docstring: uniform links
# 5 kg x 0.5 m and 3 kg x 0.4 m, I = m d^2 / 12 about the centre of mass, friction 2 and 1).
PLANAR2R_DH = """\
  kind: robot
  gravity: [0.0, -9.81, 0.0]
  dh:
    - {a: 0.5, mass: 5.0, com: [-0.25, 0.0, 0.0], inertia: [0.0, 0.10416666666666667, 0.10416666666666667,
       0.0, 0.0, 0.0], viscous: 2.0}
    - {a: 0.4, mass: 3.0, com: [-0.2, 0.0, 0.0], inertia: [0.0, 0.04, 0.04, 0.0, 0.0, 0.0], viscous: 1.0}
"""


def _spec_text(plant: str, controller: str = ROBOT_CONTROLLER) -> str:
    """A complete spec: ``plant`` is the YAML of the section, flow style or an indented block."""
    body = plant.strip("\n")
    block = f" {body}" if body.lstrip().startswith("{") else "\n" + textwrap.indent(textwrap.dedent(body), "  ")
    return f"name: plant-test\nplant:{block}\ncontroller: {controller}\n"


def _build(plant: str, *, controller: str = ROBOT_CONTROLLER, base_dir: Path | None = None) -> PlantBase:
    loaded = parse_spec(_spec_text(plant, controller))
    return plant_from_spec(loaded.spec.plant, base_dir)


def _states(count: int, seed: int) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    rng = np.random.default_rng(seed)
    return [(rng.uniform(-3.0, 3.0, 2), rng.uniform(-2.0, 2.0, 2), rng.uniform(-5.0, 5.0, 2)) for _ in range(count)]


def _same_dynamics_as(plant: PlantBase, arm, seed: int) -> None:  # noqa: ANN001 - a numeric Robot
    """``plant.rhs`` equals ``(qd, arm.forward_dynamics(q, qd, u))`` at random states (d = 0)."""
    for q, qd, u in _states(4, seed):
        ref = np.concatenate([qd, arm.forward_dynamics(q, qd, u)])
        assert scaled_error(plant.rhs(np.concatenate([q, qd]), u), ref) < TOL_EXACT


# ------------------------------------------------------------------------------------- good input


def test_link_section():
    plant = _build("{kind: link, Km: 2.5, tau: 0.4, uncertainty: {Km: [2, 3], tau: [0.3, 0.5]}}",
                   controller=LINK_CONTROLLER)
    assert isinstance(plant, LinkPlant)
    assert (plant.Km, plant.tau) == (2.5, 0.4)
    # the section's numbers are the plant's: steady speed per unit torque Km, x2' = Km/tau at rest for u = 1
    assert scaled_error(plant.rhs([0.0, 0.0], [1.0]), [0.0, 2.5 / 0.4]) < TOL_EXACT


def test_zoo_robot_with_parameter_overrides_reaches_the_plant():
    plant = _build("{kind: robot, robot: planar2r, parameters: {m2: 4.0, f1: 0.5}, uncertainty: {m2: [3.0, 5.0]}}")
    assert isinstance(plant, RobotPlant)
    assert plant.parameter("m2").value == 4.0 and plant.parameter("f1").value == 0.5
    assert plant.parameter("m1").value == 5.0  # not overridden: the default
    assert plant.robot.friction and not plant.robot.motor_inertia  # the section's defaults
    _same_dynamics_as(plant, robot("planar2r", m2=4.0, f1=0.5, friction=True), seed=0)


def test_zoo_robot_options_reach_the_plant():
    plant = _build("{kind: robot, robot: puma560, friction: false, motor_inertia: true}")
    assert not plant.robot.friction and plant.robot.motor_inertia
    arm = robot("puma560", motor_inertia=True)
    rng = np.random.default_rng(1)
    q, qd, u = rng.uniform(-1, 1, 6), rng.uniform(-1, 1, 6), rng.uniform(-1, 1, 6)
    assert scaled_error(plant.rhs(np.concatenate([q, qd]), u)[6:], arm.forward_dynamics(q, qd, u)) < TOL_EXACT


def test_dh_table_gives_the_dynamics_of_the_equivalent_zoo_robot():
    plant = _build(PLANAR2R_DH + "  uncertainty: {m2: [2.0, 4.0]}\n")
    assert isinstance(plant, RobotPlant) and plant.n_joints == 2
    assert plant.parameter_names == ("m1", "f1", "m2", "f2")
    assert scaled_error(plant.parameter_vector, [5.0, 2.0, 3.0, 1.0]) == 0.0
    _same_dynamics_as(plant, robot("planar2r", friction=True), seed=2)
    # the table's masses are the plant's parameters: changing m2 is the zoo robot with another m2
    # (its inertia about the centre of mass stays the table's, as in the zoo's I2 = 0.04)
    _same_dynamics_as(plant.with_params(m2=4.0), robot("planar2r", m2=4.0, friction=True), seed=3)


def test_urdf_path_is_relative_to_the_spec_folder(tmp_path, monkeypatch):
    folder = tmp_path / "specs"
    (folder / "arms").mkdir(parents=True)
    shutil.copyfile(PLANAR2R_URDF, folder / "arms" / "planar2r.urdf")
    section = "{kind: robot, urdf: arms/planar2r.urdf, gravity: [0.0, -9.81, 0.0]}"
    spec_file = folder / "arm.yaml"
    spec_file.write_text(_spec_text(section))
    loaded = parse_spec(spec_file.read_text(), path=str(spec_file))
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)  # the working directory must not matter
    plant = plant_from_spec(loaded.spec.plant, base_dir=spec_file.parent)
    assert isinstance(plant, RobotPlant) and plant.n_joints == 2
    assert "planar2r.urdf" in plant.source
    _same_dynamics_as(plant, robot("planar2r", friction=True), seed=4)
    # without the spec's folder the relative path is looked up from the working directory: not found
    with pytest.raises(SpecError) as info:
        plant_from_spec(loaded.spec.plant)
    assert info.value.path == "plant.urdf" and "not found" in info.value.message


def _elastic_section(text: str):  # noqa: ANN202 - a pydantic section
    """The ``plant`` section validated by the spec's own union type.

    ``parse_spec`` cannot carry an elastic joint yet: no registered controller family accepts the
    plant kind ``elastic_joint`` (every full spec is refused at ``controller.kind``).
    """
    return TypeAdapter(PlantSpec).validate_python(yaml.safe_load(text))


def test_elastic_joint_with_some_parameters_and_the_rest_defaulted():
    section = _elastic_section("{kind: elastic_joint, KR: 150.0, mgl: 2.0, uncertainty: {mgl: [0.0, 4.0]}}")
    plant = plant_from_spec(section)
    assert isinstance(plant, ElasticJointPlant)
    given = {"KR": 150.0, "mgl": 2.0}
    for par in plant.parameters:
        assert par.value == given.get(par.name, getattr(ELASTIC_DEFAULTS, par.name)), par.name
    # the given stiffness acts: the locked-link natural frequency is sqrt(KR R1^2 / J1)
    lin = plant.linearize(np.zeros(4), [0.0])
    p = ELASTIC_DEFAULTS
    assert scaled_error(lin.A[1, 0], -150.0 * p.R1**2 / p.J1) < TOL_EXACT


def test_elastic_joint_refuses_an_uncertainty_bound_the_model_refuses():
    section = _elastic_section("{kind: elastic_joint, uncertainty: {KR: [0.0, 100.0]}}")
    with pytest.raises(SpecError) as info:
        plant_from_spec(section)
    assert info.value.path == "plant.uncertainty.KR"
    assert "\n" not in str(info.value)


# ------------------------------------------------------------------------------------- bad input

BRANCHING_URDF = """\
<?xml version="1.0"?>
<robot name="two_fingers">
  <link name="palm"/>
  <joint name="finger_a" type="revolute">
    <parent link="palm"/><child link="a"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/>
  </joint>
  <link name="a"><inertial><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/>
  </inertial></link>
  <joint name="finger_b" type="revolute">
    <parent link="{parent_b}"/><child link="b"/><origin xyz="0.2 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/>
  </joint>
  <link name="b"><inertial><mass value="1"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/>
  </inertial></link>
</robot>
"""


def _bad(plant: str, path: str, words: str, *, controller: str = ROBOT_CONTROLLER,
         base_dir: Path | None = None) -> SpecError:
    with pytest.raises(SpecError) as info:
        _build(plant, controller=controller, base_dir=base_dir)
    error = info.value
    assert error.path == path, str(error)
    assert words in error.message, str(error)
    assert error.message.strip() and "\n" not in str(error)
    assert str(error) == f"{path}: {error.message}"
    return error


@pytest.mark.parametrize(
    ("plant", "path", "words"),
    [
        ("{kind: robot, robot: planar3r}", "plant.robot", "unknown robot 'planar3r'"),
        ("{kind: robot, robot: planar2r, parameters: {m7: 1.0}}", "plant.parameters.m7", "no parameter 'm7'"),
        ("{kind: robot, robot: planar2r, uncertainty: {m7: [1.0, 2.0]}}", "plant.uncertainty.m7",
         "unknown parameter"),
        ("{kind: robot, robot: planar2r, uncertainty: {m2: [-1.0, 4.0]}}", "plant.uncertainty.m2", "got -1"),
        ("{kind: robot, robot: planar2r, uncertainty: {d2: [0.0, 0.5]}}", "plant.uncertainty.d2", "positive"),
        ("{kind: robot, dh: [{a: 1.0, mass: 1.0}], uncertainty: {f1: [-0.5, 1.0]}}", "plant.uncertainty.f1",
         "non-negative"),
        ("{kind: robot, dh: [{a: 1.0, mass: 1.0}], uncertainty: {m2: [1.0, 2.0]}}", "plant.uncertainty.m2",
         "unknown parameter"),
        ("{kind: robot, dh: [{a: 1.0, com: [0.0, 0.0]}, {a: 1.0}]}", "plant.dh[0].com[2]", "missing"),
        ("{kind: robot, dh: [{a: 1.0}, {a: 1.0, com: [0.0, 0.0, 0.0, 0.0]}]}", "plant.dh[1].com", "at most 3"),
        ("{kind: robot, dh: [{a: 1.0}, {a: 1.0, inertia: [1.0, 1.0, 1.0]}]}", "plant.dh[1].inertia[3]", "missing"),
        ("{kind: robot, dh: [{a: 1.0, mass: -2.0}]}", "plant.dh[0].mass", "greater than or equal to 0"),
        ("{kind: robot, urdf: no/such/arm.urdf}", "plant.urdf", "not found"),
        ("{kind: robot, robot: planar2r, dh: [{a: 1.0}]}", "plant", "exactly one of robot"),
        ("{kind: robot, dh: [{a: 1.0}], urdf: arm.urdf}", "plant", "exactly one of robot"),
        ("{kind: robot}", "plant", "exactly one of robot"),
        ("{kind: robot, dh: [{a: 1.0, mass: 1.0}], parameters: {m1: 2.0}}", "plant.parameters",
         "only a built-in robot"),
        ("{kind: robot, robot: planar2r, masses: {m1: 2.0}}", "plant.masses", "unknown key"),
        ("{kind: robot, dh: [{a: 1.0, mas: 1.0}]}", "plant.dh[0].mas", "unknown key"),
    ],
)
def test_bad_robot_section_names_the_key_path(plant, path, words):
    assert _bad(plant, path, words)


@pytest.mark.parametrize(
    ("plant", "path", "words"),
    [
        ("{kind: link, Km: 2.0, tau: 0.5, uncertainty: {Km: [0.0, 3.0]}}", "plant.uncertainty.Km", "positive"),
        ("{kind: link, Km: 2.0, tau: 0.5, uncertainty: {m2: [1.0, 2.0]}}", "plant.uncertainty.m2",
         "unknown parameter"),
        ("{kind: link, Km: 2.0, tau: 0.5, damping: 1.0}", "plant.damping", "unknown key"),
    ],
)
def test_bad_link_section_names_the_key_path(plant, path, words):
    assert _bad(plant, path, words, controller=LINK_CONTROLLER)


@pytest.mark.parametrize(("name", "value"), [("m2", -4.0), ("d2", 0.0)])
def test_override_value_the_model_refuses_names_plant_parameters(name, value):
    assert _bad(f"{{kind: robot, robot: planar2r, parameters: {{{name}: {value}}}}}", f"plant.parameters.{name}",
         "must be")


def test_override_value_the_model_refuses_is_a_spec_error():
    """Refused, on one line, naming the parameter."""
    with pytest.raises(SpecError) as info:
        _build("{kind: robot, robot: planar2r, parameters: {m2: -4.0}}")
    assert info.value.path.endswith("m2") and "non-negative" in info.value.message
    assert "\n" not in str(info.value)


@pytest.mark.parametrize(("parent_b", "extra"), [("palm", ""), ("palm", ", tip_link: a")],
                         ids=["branch-at-root", "branch-off-the-chosen-chain"])
def test_urdf_that_is_not_a_serial_chain(tmp_path, parent_b, extra):
    (tmp_path / "fingers.urdf").write_text(BRANCHING_URDF.format(parent_b=parent_b))
    error = _bad(f"{{kind: robot, urdf: fingers.urdf{extra}}}", "plant.urdf", "only serial chains are supported",
                 base_dir=tmp_path)
    assert "palm" in error.message  # names the link where the tree branches


def test_the_same_urdf_made_serial_builds(tmp_path):
    """Control for the test above: the file is otherwise valid (finger b hung on finger a: two joints)."""
    (tmp_path / "fingers.urdf").write_text(BRANCHING_URDF.format(parent_b="a"))
    plant = _build("{kind: robot, urdf: fingers.urdf}", base_dir=tmp_path)
    assert plant.n_joints == 2 and plant.parameter_names == ("m1", "f1", "m2", "f2")


@pytest.mark.parametrize(
    ("content", "words"),
    [("<robot name='x'><link name='a'></robot>", "malformed URDF"),
     (BRANCHING_URDF.format(parent_b="a").replace('<mass value="1"/>', '<mass value="-1"/>', 1), "negative mass")],
    ids=["malformed-xml", "negative-mass"],
)
def test_urdf_the_parser_refuses_is_reported_at_plant_urdf(tmp_path, content, words):
    (tmp_path / "arm.urdf").write_text(content)
    assert _bad("{kind: robot, urdf: arm.urdf}", "plant.urdf", words, base_dir=tmp_path)
