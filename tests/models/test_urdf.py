"""URDF import: same dynamics as the DH builder and as Pinocchio's own URDF parser; clear errors."""

from __future__ import annotations

import math
from importlib.resources import files

import numpy as np
import pytest

from designkit.errors import ModelError
from designkit.models.robot import robot_from_dh
from designkit.models.robots import robot
from designkit.models.urdf import description_from_urdf, description_to_urdf, robot_from_urdf
from designkit.models.urdf_chain import matrix_to_rpy, rpy_to_matrix
from tests.models.support import TOL_EXACT, random_states, scaled_error
from tests.models.test_base_parameters import random_chain

ROBOT_FILES = files("designkit.models.robots")
GRAVITY = {"planar2r": (0.0, -9.81, 0.0), "puma560": (0.0, 0.0, -9.81)}


def pinocchio_rnea(path, gravity, q, qd, qdd):
    """Inverse dynamics by Pinocchio's URDF parser (continuous joints take (cos, sin))."""
    pin = pytest.importorskip("pinocchio")
    model = pin.buildModelFromUrdf(str(path))
    model.gravity.linear = np.array(gravity, dtype=float)
    data = model.createData()
    out = []
    for qk, qdk, qddk in zip(q, qd, qdd, strict=True):
        config = np.concatenate([[math.cos(v), math.sin(v)] if joint.nq == 2 else [v]
                                 for v, joint in zip(qk, model.joints[1:], strict=True)])
        out.append(pin.rnea(model, data, config, qdk, qddk).copy())
    return np.array(out)


# ------------------------------------------------------------------------------- the zoo files


@pytest.mark.parametrize("name", ["planar2r", "puma560"])
def test_zoo_urdf_matches_dh(name):
    reference = robot(name, friction=True)
    loaded = robot_from_urdf(ROBOT_FILES / f"{name}.urdf", gravity=GRAVITY[name], friction=True)
    assert loaded.description.convention == "modified" and loaded.n == reference.n
    q, qd, qdd = random_states(np.random.default_rng(0), reference.n, 50)
    assert scaled_error(loaded.inverse_dynamics(q, qd, qdd), reference.inverse_dynamics(q, qd, qdd)) < TOL_EXACT
    assert scaled_error(loaded.mass_matrix(q), reference.mass_matrix(q)) < TOL_EXACT


@pytest.mark.parametrize("name", ["planar2r", "puma560"])
def test_zoo_urdf_matches_pinocchio(name):
    path = ROBOT_FILES / f"{name}.urdf"
    loaded = robot_from_urdf(path, gravity=GRAVITY[name])
    q, qd, qdd = random_states(np.random.default_rng(1), loaded.n, 20)
    reference = pinocchio_rnea(path, GRAVITY[name], q, qd, qdd)
    assert scaled_error(loaded.inverse_dynamics(q, qd, qdd), reference) < TOL_EXACT


def test_zoo_urdf_limits_friction_and_tool():
    reference = robot("puma560")
    loaded = robot_from_urdf(ROBOT_FILES / "puma560.urdf", tip_link="tool")
    for ours, theirs in zip(loaded.description.links, reference.description.links, strict=True):
        assert ours.qlim == pytest.approx(theirs.qlim)
        assert (ours.viscous, ours.coulomb, ours.name) == (pytest.approx(theirs.viscous), pytest.approx(theirs.coulomb),
                                                           theirs.name)
    q = random_states(np.random.default_rng(2), 6, 10)[0]
    assert scaled_error(loaded.fkine(q), reference.fkine(q)) < TOL_EXACT


def test_zoo_files_are_current():
    """The shipped files are what the writer produces from the zoo descriptions."""
    for name in GRAVITY:
        text = (ROBOT_FILES / f"{name}.urdf").read_text()
        assert text == description_to_urdf(robot(name).description)


# ------------------------------------------------------------------------------- round trips


@pytest.mark.parametrize("seed", range(8))
def test_round_trip_random_chains(seed, tmp_path):
    """Writer + reader on chains of both conventions, prismatic joints, base and tool transforms."""
    rng = np.random.default_rng(100 + seed)
    base = np.eye(4)
    base[:3, :3] = rpy_to_matrix(rng.uniform(-2, 2, 3))
    base[:3, 3] = rng.uniform(-0.5, 0.5, 3)
    description = random_chain(seed)
    from dataclasses import replace

    description = replace(description, base=tuple(map(tuple, base)), tool=tuple(map(tuple, base @ base)))
    path = tmp_path / "chain.urdf"
    path.write_text(description_to_urdf(description))
    reference = robot_from_dh(description, friction=True)
    loaded = robot_from_urdf(path, gravity=description.gravity, friction=True, tip_link="tool")
    q, qd, qdd = random_states(rng, reference.n, 30)
    assert scaled_error(loaded.inverse_dynamics(q, qd, qdd), reference.inverse_dynamics(q, qd, qdd)) < TOL_EXACT
    assert scaled_error(loaded.fkine(q), reference.fkine(q)) < TOL_EXACT
    assert scaled_error(loaded.jacobian(q), reference.jacobian(q)) < TOL_EXACT


def test_rpy_round_trip():
    rng = np.random.default_rng(3)
    for rpy in [*rng.uniform(-3, 3, (50, 3)), (0.3, math.pi / 2, -1.0), (0.2, -math.pi / 2, 0.5)]:
        R = rpy_to_matrix(rpy)
        np.testing.assert_allclose(rpy_to_matrix(matrix_to_rpy(R)), R, atol=1e-12)


# ------------------------------------------------------------------------------- a non-DH URDF

GENERAL = """<?xml version="1.0"?>
<robot name="general">
  <link name="world"/>
  <link name="pedestal">
    <inertial><mass value="9"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>
  </link>
  <joint name="mount" type="fixed">
    <parent link="world"/><child link="pedestal"/><origin xyz="0.1 -0.2 0.3" rpy="0.1 0.2 0.3"/>
  </joint>
  <link name="a">
    <inertial><origin xyz="0.1 0.02 -0.03" rpy="0.4 -0.2 0.1"/><mass value="2.0"/>
      <inertia ixx="0.02" ixy="0.001" ixz="-0.002" iyy="0.03" iyz="0.0005" izz="0.025"/></inertial>
  </link>
  <joint name="j1" type="continuous">
    <parent link="pedestal"/><child link="a"/><origin xyz="0 0 0.4" rpy="0 0.3 0"/><axis xyz="0 1 0"/>
  </joint>
  <link name="a_cover">
    <inertial><origin xyz="0.05 0 0"/><mass value="0.5"/>
      <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.002" iyz="0" izz="0.002"/></inertial>
  </link>
  <joint name="cover" type="fixed">
    <parent link="a"/><child link="a_cover"/><origin xyz="0.2 0 0.05" rpy="0 0 1.0"/>
  </joint>
  <link name="camera"/>
  <joint name="camera_mount" type="fixed">
    <parent link="a_cover"/><child link="camera"/><origin xyz="0 0.1 0"/>
  </joint>
  <link name="b">
    <inertial><origin xyz="0 0.1 0.02"/><mass value="1.5"/>
      <inertia ixx="0.01" ixy="0" ixz="0.001" iyy="0.012" iyz="0" izz="0.008"/></inertial>
  </link>
  <joint name="j2" type="prismatic">
    <parent link="a"/><child link="b"/><origin xyz="0.3 0.1 0" rpy="0.5 0 -0.4"/><axis xyz="1 1 0"/>
    <limit lower="-0.2" upper="0.3" effort="10" velocity="1"/><dynamics damping="0.7" friction="0.2"/>
  </joint>
  <link name="c">
    <inertial><origin xyz="0.05 0 0.01" rpy="0 0.3 0"/><mass value="0.8"/>
      <inertia ixx="0.004" ixy="0" ixz="0" iyy="0.005" iyz="0" izz="0.003"/></inertial>
  </link>
  <joint name="j3" type="revolute">
    <parent link="b"/><child link="c"/><origin xyz="0 0.25 0.1" rpy="-0.3 0.8 0.2"/><axis xyz="0.2 -0.3 0.9"/>
    <limit lower="-1" upper="1.5" effort="10" velocity="1"/>
  </joint>
  <link name="d">
    <inertial><mass value="0.3"/><inertia ixx="0.0004" ixy="0" ixz="0" iyy="0.0004" iyz="0" izz="0.0002"/></inertial>
  </link>
  <joint name="j4" type="revolute">
    <parent link="c"/><child link="d"/><origin xyz="0.1 0 0" rpy="0 0 0"/><axis xyz="0.2 -0.3 0.9"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/>
  </joint>
  <link name="flange"/>
  <joint name="flange_joint" type="fixed">
    <parent link="d"/><child link="flange"/><origin xyz="0 0 0.05" rpy="0.1 0.2 0.3"/>
  </joint>
</robot>
"""


J4 = '<origin xyz="0.1 0 0" rpy="0 0 0"/><axis xyz="0.2 -0.3 0.9"/>'
VARIANTS = {
    "parallel": GENERAL,  # axes 3 and 4 parallel, 0.1 m apart
    "collinear": GENERAL.replace(J4, '<origin xyz="0.02 -0.03 0.09" rpy="0 0 0"/><axis xyz="0.2 -0.3 0.9"/>'),
    "intersecting": GENERAL.replace(J4, '<origin xyz="0.02 -0.03 0.09" rpy="0 0 0"/><axis xyz="1 0 0"/>'),
    # j2 hangs from the fixed-jointed cover: a fixed joint inside the chain
    "fixed in chain": GENERAL.replace('<parent link="a"/><child link="b"/>',
                                      '<parent link="a_cover"/><child link="b"/>'),
}


@pytest.mark.parametrize("variant", sorted(VARIANTS))
def test_general_urdf_matches_pinocchio(variant, tmp_path):
    """Odd axes, rpy origins, a prismatic joint along (1, 1, 0), merged fixed links; axes 3-4 in three layouts."""
    assert J4 in GENERAL and len(set(VARIANTS.values())) == len(VARIANTS)
    path = tmp_path / "general.urdf"
    path.write_text(VARIANTS[variant])
    gravity = (0.5, -1.0, -9.7)
    loaded = robot_from_urdf(path, gravity=gravity)
    assert [link.joint for link in loaded.description.links] == ["revolute", "prismatic", "revolute", "revolute"]
    assert loaded.description.links[1].qlim == (-0.2, 0.3)
    assert loaded.description.links[1].viscous == 0.7 and loaded.description.links[1].coulomb == 0.2
    q, qd, qdd = random_states(np.random.default_rng(4), 4, 30)
    assert scaled_error(loaded.inverse_dynamics(q, qd, qdd), pinocchio_rnea(path, gravity, q, qd, qdd)) < TOL_EXACT


def test_general_urdf_tool_frame(tmp_path):
    pin = pytest.importorskip("pinocchio")
    path = tmp_path / "general.urdf"
    path.write_text(GENERAL)
    loaded = robot_from_urdf(path, tip_link="flange")
    model = pin.buildModelFromUrdf(str(path))
    data = model.createData()
    frame = model.getFrameId("flange")
    for qk in random_states(np.random.default_rng(5), 4, 10)[0]:
        config = np.concatenate([[math.cos(qk[0]), math.sin(qk[0])], qk[1:]])
        pin.framesForwardKinematics(model, data, config)
        assert scaled_error(loaded.fkine(qk), data.oMf[frame].homogeneous) < TOL_EXACT


def test_base_link_and_tip_link_select_a_sub_chain(tmp_path):
    path = tmp_path / "general.urdf"
    path.write_text(GENERAL)
    sub = description_from_urdf(path, base_link="pedestal", tip_link="d")
    full = description_from_urdf(path)
    assert sub.n == full.n == 4
    mount = np.eye(4)
    mount[:3, :3] = rpy_to_matrix((0.1, 0.2, 0.3))
    mount[:3, 3] = (0.1, -0.2, 0.3)
    np.testing.assert_allclose(np.array(full.base), mount @ np.array(sub.base), atol=1e-12)
    for a, b in zip(sub.links, full.links, strict=True):
        assert (a.joint, a.name, a.qlim) == (b.joint, b.name, b.qlim)
        numbers = ("a", "alpha", "d", "theta", "offset", "mass")
        np.testing.assert_allclose([getattr(a, k) for k in numbers], [getattr(b, k) for k in numbers], atol=1e-12)
        np.testing.assert_allclose([*a.com, *a.inertia], [*b.com, *b.inertia], atol=1e-12)


# ------------------------------------------------------------------------------- errors


def _minimal(joint_type: str = "revolute", extra: str = "", inertial: bool = True) -> str:
    body = '<inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>'
    return f"""<robot name="r"><link name="base"/><link name="l1">{body if inertial else ""}</link>
      <joint name="j1" type="{joint_type}"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/>
      <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>{extra}</robot>"""


BRANCHED = _minimal(extra="""<link name="l2"><inertial><mass value="1"/>
  <inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
  <joint name="j2" type="revolute"><parent link="base"/><child link="l2"/><axis xyz="0 1 0"/>
  <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>""")

ERRORS = {
    "malformed": ("<robot name='r'><link name='a'></robot>", "malformed URDF"),
    "not a robot": ("<model/>", "expected <robot>"),
    "floating": (_minimal("floating"), "is floating"),
    "planar": (_minimal("planar"), "is planar"),
    "unknown type": (_minimal("ball"), "unknown type"),
    "branched": (BRANCHED, "branches at link 'base'"),
    "no inertial": (_minimal(inertial=False), "link 'l1' .* has no <inertial>"),
    "unknown link": (_minimal(extra='<joint name="j9" type="fixed"><parent link="l1"/><child link="nope"/></joint>'),
                     "unknown link 'nope'"),
    "mimic": (_minimal(extra="").replace("</joint>", '<mimic joint="j0"/></joint>'), "mimic"),
    "bad number": (_minimal().replace('xyz="0 0 1"', 'xyz="0 zero 1"'), "axis: expected 3 numbers"),
    "zero axis": (_minimal().replace('xyz="0 0 1"', 'xyz="0 0 0"'), "zero axis"),
    "negative mass": (_minimal().replace('value="1"', 'value="-1"'), "negative mass"),
}


@pytest.mark.parametrize("case", sorted(ERRORS))
def test_errors_are_one_line_model_errors(case, tmp_path):
    text, pattern = ERRORS[case]
    path = tmp_path / "bad.urdf"
    path.write_text(text)
    with pytest.raises(ModelError, match=pattern) as info:
        robot_from_urdf(path)
    assert "\n" not in str(info.value)


def test_branch_off_the_chain_is_refused_even_with_tip(tmp_path):
    path = tmp_path / "branched.urdf"
    path.write_text(BRANCHED)
    with pytest.raises(ModelError, match="movable joint 'j2' is off the chain"):
        robot_from_urdf(path, tip_link="l1")


def test_missing_file_and_unknown_links(tmp_path):
    with pytest.raises(ModelError, match="cannot read URDF"):
        robot_from_urdf(tmp_path / "absent.urdf")
    path = tmp_path / "ok.urdf"
    path.write_text(_minimal())
    with pytest.raises(ModelError, match="no link 'nowhere'"):
        robot_from_urdf(path, tip_link="nowhere")
    with pytest.raises(ModelError, match="not below base link 'l1'"):
        robot_from_urdf(path, base_link="l1", tip_link="base")


def test_symbolic_description_cannot_be_written():
    with pytest.raises(ModelError, match="numeric"):
        description_to_urdf(robot("planar2r", symbolic=("m1",)).description)
