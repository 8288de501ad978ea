"""URDF import and export for serial chains.

:func:`robot_from_urdf` reads a URDF file with :mod:`xml.etree.ElementTree`,
extracts the serial chain from ``base_link`` to ``tip_link``, merges links
attached by ``fixed`` joints into their parent, and converts the chain to a
modified-DH :class:`~designkit.models.description.ChainDescription`
(:func:`designkit.models.urdf_chain.to_modified_dh`), so the same kinematics,
dynamics, regressor and code generation apply.

Supported: ``revolute``, ``continuous`` and ``prismatic`` joints with any
``origin`` and ``axis``; ``fixed`` joints (merged); ``<limit>`` (joint limits)
and ``<dynamics damping friction>`` (viscous and Coulomb friction).
Refused with a one-line :class:`~designkit.errors.ModelError`: malformed XML,
``floating`` and ``planar`` joints, branched trees with movable joints off the
chain, moving links without ``<inertial>``, ``<mimic>`` joints.  Ignored:
visual, collision, transmission and gazebo elements.

:func:`description_to_urdf` writes a numeric description as URDF (the files
``models/robots/planar2r.urdf`` and ``puma560.urdf`` were written with it).
"""

from __future__ import annotations

import math
import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np

from designkit import arguments
from designkit.errors import ModelError
from designkit.models.description import ChainDescription
from designkit.models.robot import Robot, robot_from_dh
from designkit.models.urdf_chain import (
    Body,
    SerialChain,
    UrdfJoint,
    matrix_to_rpy,
    merge_bodies,
    rpy_to_matrix,
    to_modified_dh,
    transform,
)

__all__ = ["description_from_urdf", "description_to_urdf", "robot_from_urdf"]

_MOVABLE = {"revolute": "revolute", "continuous": "revolute", "prismatic": "prismatic"}


@dataclass(frozen=True)
class _Joint:
    name: str
    kind: str
    parent: str
    child: str
    origin: np.ndarray
    axis: np.ndarray
    qlim: tuple[float, float] | None
    damping: float
    friction: float


def _floats(text: str | None, count: int, where: str, default: tuple[float, ...]) -> np.ndarray:
    if text is None:
        return np.array(default, dtype=float)
    try:
        values = [float(v) for v in text.split()]
    except ValueError:
        raise ModelError(f"URDF {where}: expected {count} numbers, got {text!r}") from None
    if len(values) != count or not all(math.isfinite(v) for v in values):
        raise ModelError(f"URDF {where}: expected {count} finite numbers, got {text!r}")
    return np.array(values)


def _float(element: ET.Element, key: str, where: str, default: float | None = None) -> float:
    text = element.get(key)
    if text is None:
        if default is None:
            raise ModelError(f"URDF {where}: missing attribute {key!r}")
        return default
    return float(_floats(text, 1, f"{where} {key}", (default or 0.0,))[0])


def _origin(element: ET.Element | None, where: str) -> np.ndarray:
    if element is None:
        return np.eye(4)
    xyz = _floats(element.get("xyz"), 3, f"{where} origin xyz", (0.0, 0.0, 0.0))
    rpy = _floats(element.get("rpy"), 3, f"{where} origin rpy", (0.0, 0.0, 0.0))
    return transform(rpy_to_matrix(rpy), xyz)


def _inertial(link: ET.Element) -> Body | None:
    """The link's inertial data in the link frame, or None when it has no ``<inertial>``."""
    name = link.get("name")
    element = link.find("inertial")
    if element is None:
        return None
    where = f"link {name!r} inertial"
    mass_el, inertia_el = element.find("mass"), element.find("inertia")
    if mass_el is None or inertia_el is None:
        raise ModelError(f"URDF {where}: needs <mass> and <inertia>")
    mass = _float(mass_el, "value", where)
    if mass < 0:
        raise ModelError(f"URDF {where}: negative mass {mass}")
    i = {k: _float(inertia_el, k, where) for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")}
    tensor = np.array([[i["ixx"], i["ixy"], i["ixz"]], [i["ixy"], i["iyy"], i["iyz"]], [i["ixz"], i["iyz"], i["izz"]]])
    return Body(mass, np.zeros(3), tensor).moved(_origin(element.find("origin"), where))


def _parse_joint(element: ET.Element) -> _Joint:
    name = element.get("name", "?")
    kind = element.get("type")
    where = f"joint {name!r}"
    if kind in ("floating", "planar"):
        raise ModelError(f"URDF {where} is {kind}: only revolute, continuous, prismatic and fixed joints are supported")
    if kind not in (*_MOVABLE, "fixed"):
        raise ModelError(f"URDF {where} has unknown type {kind!r}")
    if element.find("mimic") is not None:
        raise ModelError(f"URDF {where} is a mimic joint, not supported")
    parent, child = element.find("parent"), element.find("child")
    if parent is None or child is None or parent.get("link") is None or child.get("link") is None:
        raise ModelError(f"URDF {where}: needs <parent link=...> and <child link=...>")
    axis = _floats(element.find("axis").get("xyz") if element.find("axis") is not None else None, 3,
                   f"{where} axis", (1.0, 0.0, 0.0))
    if kind in _MOVABLE:
        if np.linalg.norm(axis) < 1e-12:
            raise ModelError(f"URDF {where}: zero axis")
        axis = axis / np.linalg.norm(axis)
    limit = element.find("limit")
    qlim = None
    if kind in ("revolute", "prismatic") and limit is not None and "lower" in limit.attrib and "upper" in limit.attrib:
        qlim = (_float(limit, "lower", where), _float(limit, "upper", where))
    dynamics = element.find("dynamics")
    damping = _float(dynamics, "damping", where, 0.0) if dynamics is not None else 0.0
    friction = _float(dynamics, "friction", where, 0.0) if dynamics is not None else 0.0
    return _Joint(name, kind, parent.get("link"), child.get("link"), _origin(element.find("origin"), where),
                  axis, qlim, damping, friction)


def _path(joints: dict[str, _Joint], base: str, tip: str) -> list[_Joint]:
    """Joints from ``base`` down to ``tip`` (child link -> joint map)."""
    path = []
    link = tip
    while link != base:
        joint = joints.get(link)
        if joint is None:
            raise ModelError(f"URDF link {tip!r} is not below base link {base!r}")
        path.append(joint)
        link = joint.parent
    return path[::-1]


def _read(path: str | os.PathLike[str]) -> ET.Element:
    if not isinstance(path, str | os.PathLike):
        raise ModelError("path", f"must be a file path (str or os.PathLike), got {type(path).__name__}")
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as exc:
        raise ModelError(f"malformed URDF {os.fspath(path)!r}: {exc}") from None
    except OSError as exc:
        raise ModelError(f"cannot read URDF {os.fspath(path)!r}: {exc.strerror}") from None
    if root.tag != "robot":
        raise ModelError(f"URDF {os.fspath(path)!r}: root element is <{root.tag}>, expected <robot>")
    return root


def _serial_chain(root: ET.Element, base_link: str | None, tip_link: str | None) -> SerialChain:
    links = {el.get("name"): el for el in root.findall("link")}
    for element in links.values():  # every link's numbers are checked, those of links off the chain too
        _inertial(element)
    by_child: dict[str, _Joint] = {}
    children: dict[str, list[_Joint]] = {name: [] for name in links}
    for element in root.findall("joint"):
        joint = _parse_joint(element)
        for end in (joint.parent, joint.child):
            if end not in links:
                raise ModelError(f"URDF joint {joint.name!r} refers to unknown link {end!r}")
        if joint.child in by_child:
            raise ModelError(f"URDF link {joint.child!r} is the child of two joints")
        by_child[joint.child] = joint
        children[joint.parent].append(joint)
    roots = [name for name in links if name not in by_child]
    if base_link is None:
        if len(roots) != 1:
            raise ModelError(f"URDF must have one root link, found {roots}")
        base_link = roots[0]
    elif base_link not in links:
        raise ModelError("base_link", f"URDF has no link {base_link!r}")

    def movable_below(link: str) -> str | None:
        for joint in children[link]:
            if joint.kind in _MOVABLE:
                return joint.name
            found = movable_below(joint.child)
            if found:
                return found
        return None

    if tip_link is None:  # follow the unique branch with movable joints
        tip_link = base_link
        while True:
            moving = [j for j in children[tip_link] if j.kind in _MOVABLE or movable_below(j.child)]
            if not moving:
                break
            if len(moving) > 1:
                names = ", ".join(repr(j.child) for j in moving)
                raise ModelError(f"URDF tree branches at link {tip_link!r} (to {names}): "
                                 "only serial chains are supported")
            tip_link = moving[0].child
    elif tip_link not in links:
        raise ModelError("tip_link", f"URDF has no link {tip_link!r}")
    chain = _path(by_child, base_link, tip_link)
    on_chain = {base_link, *(j.child for j in chain)}

    def rigid_group(link: str, pose: np.ndarray) -> list[tuple[str, np.ndarray]]:
        """Links rigidly attached to ``link`` (off the chain), with their poses relative to it."""
        group = [(link, pose)]
        for joint in children[link]:
            if joint.child in on_chain:
                continue
            if joint.kind in _MOVABLE or movable_below(joint.child):
                moving = joint.name if joint.kind in _MOVABLE else movable_below(joint.child)
                raise ModelError(f"URDF tree branches at link {link!r}: movable joint {moving!r} is off the chain "
                                 f"{base_link!r} -> {tip_link!r}; only serial chains are supported")
            group += rigid_group(joint.child, pose @ joint.origin)
        return group

    joints: list[UrdfJoint] = []
    pose = np.eye(4)  # pose of the current link frame in the base link at q = 0
    current: tuple[_Joint, np.ndarray, list[tuple[str, np.ndarray]]] | None = None
    rigid_group(base_link, np.eye(4))  # checks for moving branches at the base

    def close(entry: tuple[_Joint, np.ndarray, list[tuple[str, np.ndarray]]]) -> None:
        joint, joint_pose, group = entry
        bodies = [(name, _inertial(links[name]), rel) for name, rel in group]
        present = [b.moved(rel) for _, b, rel in bodies if b is not None]
        if not present:
            raise ModelError(f"URDF link {joint.child!r} (moved by joint {joint.name!r}) has no <inertial>; "
                             "add one (a zero mass is allowed)")
        joints.append(UrdfJoint(joint.name, _MOVABLE[joint.kind], joint_pose, joint.axis, merge_bodies(present),
                                joint.qlim, joint.damping, joint.friction))

    anchor = np.eye(4)
    for joint in chain:
        pose = pose @ joint.origin
        if joint.kind in _MOVABLE:
            if current is not None:
                close(current)
            current = (joint, pose, [])
            anchor = pose
        group = rigid_group(joint.child, np.eye(4))  # also refuses movable side branches
        if current is not None:  # links before the first movable joint belong to the fixed base
            current[2].extend((name, np.linalg.solve(anchor, pose) @ rel) for name, rel in group)
    if current is not None:
        close(current)
    return SerialChain(root.get("name", "urdf"), tuple(joints), pose)


def description_from_urdf(path: str | os.PathLike[str], *, base_link: str | None = None,
                          tip_link: str | None = None,
                          gravity: tuple[float, float, float] = (0.0, 0.0, -9.81)) -> ChainDescription:
    """Modified-DH description of the serial chain of a URDF file.

    Parameters
    ----------
    path : path-like
        URDF file.
    base_link : str, optional
        Fixed base of the chain; default the URDF root link.
    tip_link : str, optional
        Last link; its frame is the tool frame.  Default: follow the tree from the
        base while exactly one branch holds movable joints, to the last movable link.
    gravity : tuple of 3
        Gravitational acceleration in the base link (m/s^2); URDF has none.

    Returns
    -------
    ChainDescription
        Joint variables and their signs are the URDF ones.

    Raises
    ------
    ModelError
        Malformed or unsupported URDF (one line, naming the joint or link), or an argument of the wrong type
        (naming it).
    """
    path = arguments.path(path, "path", error=ModelError, what="a URDF file path")
    base_link, tip_link = (None if v is None else arguments.text(v, k, error=ModelError)
                           for k, v in (("base_link", base_link), ("tip_link", tip_link)))
    gravity = _gravity(gravity)
    chain = _serial_chain(_read(path), base_link, tip_link)
    description = to_modified_dh(chain, gravity=gravity)
    return description


def _gravity(value: object) -> tuple[float, float, float]:
    """``gravity`` as three finite numbers (m/s^2)."""
    if isinstance(value, str | bytes) or not hasattr(value, "__len__") or len(value) != 3:
        raise ModelError("gravity", f"must be three numbers (m/s^2), got {type(value).__name__}")
    x, y, z = (arguments.number(v, f"gravity[{k}]", error=ModelError) for k, v in enumerate(value))
    return x, y, z


def robot_from_urdf(path: str | os.PathLike[str], *, base_link: str | None = None, tip_link: str | None = None,
                    gravity: tuple[float, float, float] = (0.0, 0.0, -9.81), friction: bool = False) -> Robot:
    """A :class:`~designkit.models.robot.Robot` from a URDF file (see :func:`description_from_urdf`).

    Parameters
    ----------
    path, base_link, tip_link, gravity
        As in :func:`description_from_urdf`.
    friction : bool
        Include the URDF ``damping`` / ``friction`` as viscous / Coulomb joint friction.

    Examples
    --------
    >>> from importlib.resources import files
    >>> arm = robot_from_urdf(files("designkit.models.robots") / "planar2r.urdf", gravity=(0.0, -9.81, 0.0))
    >>> arm.n
    2
    """
    friction = arguments.flag(friction, "friction", error=ModelError)
    description = description_from_urdf(path, base_link=base_link, tip_link=tip_link, gravity=gravity)
    return robot_from_dh(description, friction=friction)


# ------------------------------------------------------------------------------------------ export


def _fmt(values: np.ndarray | tuple[float, ...]) -> str:
    return " ".join(repr(float(v)) if abs(float(v)) > 1e-15 else "0.0" for v in values)


def _origin_xml(T: np.ndarray) -> str:
    return f'<origin xyz="{_fmt(T[:3, 3])}" rpy="{_fmt(matrix_to_rpy(T[:3, :3]))}"/>'


def _rz(theta: float) -> np.ndarray:
    c, s = math.cos(theta), math.sin(theta)
    return transform(np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]))


def _rx(alpha: float) -> np.ndarray:
    c, s = math.cos(alpha), math.sin(alpha)
    return transform(np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]))


def _tz(d: float) -> np.ndarray:
    return transform(None, np.array([0.0, 0.0, d]))


def _tx(a: float) -> np.ndarray:
    return transform(None, np.array([a, 0.0, 0.0]))


def description_to_urdf(description: ChainDescription) -> str:
    """URDF text of a numeric chain description (links ``base_link, link1..linkn, tool``).

    Joint ``i`` rotates or slides along the ``z`` axis of URDF link ``i``'s frame.
    Standard DH: URDF link ``i`` is DH frame ``i-1`` turned by the joint
    (``Rz(theta_i) Tz(d_i)``), and the DH frame ``i`` is ``Tx(a_i) Rx(alpha_i)`` further;
    modified DH: URDF link ``i`` is DH frame ``i``.  Inertial data are written in
    DH-frame axes.  Rotor inertia and gear ratios have no URDF element and are dropped.  A header comment
    states the physical consistency of the inertial parameters (:func:`designkit.models.physical.check_inertia`):
    an inconsistent link, which condition and by how much.

    Raises
    ------
    ModelError
        For a symbolic description.
    """
    if description.symbols:
        raise ModelError("description_to_urdf needs a numeric description (this one has symbols)")
    from designkit.models.physical import check_inertia

    modified = description.convention == "modified"
    consistency = " ".join(check_inertia(description).sentences()).replace("--", "- -")
    lines = ['<?xml version="1.0"?>', f'<robot name="{description.name}">',
             f"  <!-- written by designkit.models.urdf.description_to_urdf; source: {description.source} -->",
             f"  <!-- {consistency} -->",
             '  <link name="base_link"/>']
    before = np.array(description.base, dtype=float)  # transform from the previous URDF link to the next joint
    for i, link in enumerate(description.links, start=1):
        fixed = before @ _rx(link.alpha) @ _tx(link.a) if modified else before
        if link.joint == "revolute":
            fixed = fixed @ _rz(link.offset) @ _tz(link.d)
        else:
            fixed = fixed @ _rz(link.theta) @ _tz(link.offset)
        after = np.eye(4) if modified else _tx(link.a) @ _rx(link.alpha)  # URDF link frame -> DH frame
        Ixx, Iyy, Izz, Ixy, Ixz, Iyz = (float(v) for v in link.inertia)
        com = after @ np.array([*map(float, link.com), 1.0])
        kind = link.joint if (link.joint == "prismatic" or link.qlim is not None) else "continuous"
        if link.joint == "prismatic" and link.qlim is None:
            limit = '<limit lower="-1000.0" upper="1000.0" effort="0.0" velocity="0.0"/>'
        elif link.qlim is not None:
            lower, upper = (float(v) for v in link.qlim)
            limit = f'<limit lower="{lower!r}" upper="{upper!r}" effort="0.0" velocity="0.0"/>'
        else:
            limit = ""
        dynamics = (f'<dynamics damping="{float(link.viscous)!r}" friction="{float(link.coulomb)!r}"/>'
                    if float(link.viscous) or float(link.coulomb) else "")
        parent = "base_link" if i == 1 else f"link{i - 1}"
        lines += [
            f'  <joint name="{link.name or f"joint{i}"}" type="{kind}">',
            f'    <parent link="{parent}"/>', f'    <child link="link{i}"/>',
            f"    {_origin_xml(fixed)}", '    <axis xyz="0 0 1"/>',
            *(f"    {x}" for x in (limit, dynamics) if x),
            "  </joint>",
            f'  <link name="link{i}">', "    <inertial>",
            f'      <origin xyz="{_fmt(com[:3])}" rpy="{_fmt(matrix_to_rpy(after[:3, :3]))}"/>',
            f'      <mass value="{float(link.mass)!r}"/>',
            f'      <inertia ixx="{Ixx!r}" ixy="{Ixy!r}" ixz="{Ixz!r}" iyy="{Iyy!r}" iyz="{Iyz!r}" izz="{Izz!r}"/>',
            "    </inertial>", "  </link>",
        ]
        before = after
    tool = before @ np.array(description.tool, dtype=float)
    lines += ['  <joint name="tool_joint" type="fixed">', f'    <parent link="link{description.n}"/>',
              '    <child link="tool"/>', f"    {_origin_xml(tool)}", "  </joint>", '  <link name="tool"/>',
              "</robot>", ""]
    return "\n".join(lines)
