"""Shared helpers of the model tests: tolerances, random states and chains, finite differences, Pinocchio."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from hypothesis import strategies as st

from designkit.models.description import ChainDescription, LinkDescription

# One tolerance table, errors scaled as |x - ref| / (1 + |ref|).
TOL_EXACT = 1e-10
"""Two exact routes to the same quantity (RNEA vs Euler--Lagrange, W P vs tau, Pinocchio)."""
TOL_FD = 1e-6
"""Central differences with step ``FD_STEP``: truncation ~h^2 = 1e-10 times third derivatives,
rounding ~eps/h = 2e-11 times the values; 1e-6 leaves margin for derivatives of order 1e3."""
FD_STEP = 1e-5
TOL_REFERENCE = 5e-5
"""Values printed with 4 decimals by a reference (Robotics Toolbox tests): half a unit in the last place."""

ZOO = ("onelink", "planar2r", "scara", "puma560")


def scaled_error(x: np.ndarray, ref: np.ndarray) -> float:
    """Largest ``|x - ref| / (1 + |ref|)``."""
    x, ref = np.asarray(x, dtype=float), np.asarray(ref, dtype=float)
    return float(np.max(np.abs(x - ref) / (1.0 + np.abs(ref)))) if x.size else 0.0


def random_states(rng: np.random.Generator, n: int, count: int, scale: float = 1.0) -> tuple[np.ndarray, ...]:
    """``count`` random ``(q, qd, qdd)`` rows, uniform in ``[-pi, pi]`` and ``[-2, 2] * scale``."""
    q = rng.uniform(-math.pi, math.pi, (count, n))
    qd = rng.uniform(-2, 2, (count, n)) * scale
    qdd = rng.uniform(-2, 2, (count, n)) * scale
    return q, qd, qdd


def central_difference(f: Callable[[np.ndarray], np.ndarray], x: np.ndarray, h: float = FD_STEP) -> np.ndarray:
    """Jacobian of ``f`` at ``x`` by central differences; returns shape ``f(x).shape + (x.size,)``."""
    columns = []
    for k in range(x.size):
        e = np.zeros_like(x)
        e[k] = h
        columns.append((np.asarray(f(x + e)) - np.asarray(f(x - e))) / (2 * h))
    return np.stack(columns, axis=-1)


def rotation_vee(skew: np.ndarray) -> np.ndarray:
    """Vector ``w`` of a (nearly) skew-symmetric matrix ``[w]x``."""
    s = 0.5 * (skew - skew.T)
    return np.array([s[2, 1], s[0, 2], s[1, 0]])


# ----------------------------------------------------------------------------- random chains

_unit = st.floats(-1.0, 1.0, allow_nan=False)
_angle = st.floats(-math.pi, math.pi, allow_nan=False)
_special_angle = st.sampled_from([0.0, math.pi / 2, -math.pi / 2, math.pi])


@st.composite
def links(draw: st.DrawFn) -> LinkDescription:
    """A random link with a physically consistent inertia (a box of random sides)."""
    mass = draw(st.floats(0.1, 5.0))
    sides = [draw(st.floats(0.05, 0.5)) for _ in range(3)]
    ixx = mass * (sides[1] ** 2 + sides[2] ** 2) / 12
    iyy = mass * (sides[0] ** 2 + sides[2] ** 2) / 12
    izz = mass * (sides[0] ** 2 + sides[1] ** 2) / 12
    # rotate the principal inertia by a random rotation about z to get products of inertia
    c, s = math.cos(draw(_angle)), math.sin(draw(_angle))
    rot = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    inertia = rot @ np.diag([ixx, iyy, izz]) @ rot.T
    return LinkDescription(
        joint=draw(st.sampled_from(["revolute", "prismatic"])),
        a=draw(_unit) * 0.5,
        alpha=draw(st.one_of(_angle, _special_angle)),
        d=draw(_unit) * 0.5,
        theta=draw(_angle),
        offset=draw(_unit) * 0.3,
        mass=mass,
        com=tuple(draw(_unit) * 0.3 for _ in range(3)),
        inertia=(inertia[0, 0], inertia[1, 1], inertia[2, 2], inertia[0, 1], inertia[0, 2], inertia[1, 2]),
        viscous=draw(st.floats(0.0, 2.0)),
        coulomb=draw(st.floats(0.0, 1.0)),
        motor_inertia=draw(st.floats(0.0, 1e-3)),
        gear_ratio=draw(st.floats(-50.0, 50.0)),
    )


def _transform(draw: st.DrawFn) -> tuple[tuple[float, ...], ...]:
    a, b = draw(_angle), draw(_angle)
    rz = np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]])
    rx = np.array([[1, 0, 0], [0, math.cos(b), -math.sin(b)], [0, math.sin(b), math.cos(b)]])
    T = np.eye(4)
    T[:3, :3] = rz @ rx
    T[:3, 3] = [draw(_unit) * 0.3 for _ in range(3)]
    return tuple(tuple(float(v) for v in row) for row in T)


@st.composite
def chains(draw: st.DrawFn, max_links: int = 4) -> ChainDescription:
    """A random serial chain: either DH convention, mixed joints, random base, tool and gravity."""
    count = draw(st.integers(1, max_links))
    identity = tuple(tuple(float(i == j) for j in range(4)) for i in range(4))
    return ChainDescription(
        name="random",
        links=tuple(draw(links()) for _ in range(count)),
        convention=draw(st.sampled_from(["standard", "modified"])),
        gravity=tuple(draw(_unit) * 10 for _ in range(3)),
        base=_transform(draw) if draw(st.booleans()) else identity,
        tool=_transform(draw) if draw(st.booleans()) else identity,
    )


# ----------------------------------------------------------------------------- Pinocchio


def _rz(a: float) -> np.ndarray:
    T = np.eye(4)
    T[:2, :2] = [[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]]
    return T


def _rx(a: float) -> np.ndarray:
    T = np.eye(4)
    T[1:3, 1:3] = [[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]]
    return T


def _tz(d: float) -> np.ndarray:
    T = np.eye(4)
    T[2, 3] = d
    return T


def _tx(a: float) -> np.ndarray:
    T = np.eye(4)
    T[0, 3] = a
    return T


def split_dh(link: LinkDescription, convention: str) -> tuple[np.ndarray, np.ndarray]:
    """Fixed parts ``(pre, post)`` of a DH transform ``pre @ motion(q) @ post`` (NumPy, independent of src)."""
    revolute = link.joint == "revolute"
    if convention == "standard":
        if revolute:
            return _rz(link.offset), _tz(link.d) @ _tx(link.a) @ _rx(link.alpha)
        return _rz(link.theta) @ _tz(link.offset), _tx(link.a) @ _rx(link.alpha)
    if revolute:
        return _rx(link.alpha) @ _tx(link.a) @ _rz(link.offset), _tz(link.d)
    return _rx(link.alpha) @ _tx(link.a) @ _rz(link.theta) @ _tz(link.offset), np.eye(4)


def pinocchio_model(description: ChainDescription):  # noqa: ANN201 - pinocchio types
    """A Pinocchio model of a numeric description, built from the DH tables with NumPy.

    Returns the model and the post transforms (DH link frame ``i`` in joint frame ``i``).
    """
    import pinocchio as pin

    model = pin.Model()
    model.gravity.linear = np.array(description.gravity, dtype=float)
    before = np.array(description.base, dtype=float)
    parent = 0
    posts = []
    for i, link in enumerate(description.links):
        pre, post = split_dh(link, description.convention)
        placement = before @ pre
        joint = pin.JointModelRZ() if link.joint == "revolute" else pin.JointModelPZ()
        parent = model.addJoint(parent, joint, pin.SE3(placement[:3, :3], placement[:3, 3]), f"j{i}")
        ixx, iyy, izz, ixy, ixz, iyz = link.inertia
        inertia_c = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]], dtype=float)
        body = pin.Inertia(float(link.mass), np.array(link.com, dtype=float), inertia_c)
        model.appendBodyToJoint(parent, pin.SE3(post[:3, :3], post[:3, 3]).act(body), pin.SE3.Identity())
        posts.append(post)
        before = post
    return model, posts
