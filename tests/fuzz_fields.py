"""Field-targeted mutations: what a user gets wrong in the robot-facing parts of a spec, and hostile files.

:mod:`tests.fuzz` mutates every leaf of the example specs with type and YAML accidents.  This module aims at
the fields whose *in-range* values cost or break the most, each from a small base spec of its own:

* the robot: built-in names and parameter overrides, DH tables (rows, inertias, joint limits, gear ratios),
  URDF paths (missing, a folder, ``/dev/null``, binary garbage, an entity bomb, a file over 1 MiB, a real URDF
  with wrong link names), payloads, limits;
* the uncertainty box: grids and samples up to their ends, a dozen parameters, unknown names;
* the controllers: the decentralized PID's workspace, computed torque's poles, damping and
  ``friction_layer``, resolved acceleration's orientation, damped least squares and condition limit;
* the references: lines (out of reach, zero length), circles (zero radius, 100 turns), via points
  (a thousand of them, times out of order);
* numerics (integrator, tolerances, compilation) and per-joint lists of every length.

Every mutant is run with ``--budget`` (:data:`CASE_BUDGET` s of estimated work, so an accepted mutant is cheap
and a costly one is refused, exit 2, naming its field) and under a CPU-time alarm (:data:`CASE_CPU` s), so no
case can run away.  :func:`field_mutants` draws them with ``random.Random(seed)``.
"""

from __future__ import annotations

import copy
import random
from collections.abc import Callable
from pathlib import Path
from typing import Any

import yaml

from tests.fuzz import Mutant

ROOT = Path(__file__).resolve().parents[1]
URDF = ROOT / "src" / "designkit" / "models" / "robots" / "planar2r.urdf"

CASE_BUDGET = 4.0
"""Estimated seconds of work a fuzzed spec may ask for (``--budget``)."""
CASE_CPU = 30.0
"""CPU seconds after which a case is stopped and counted as a violation."""

_EXTREME = (0.0, -1.0, 1e-6, 1e6, -1e6, 1e-300, 99.9, 1e4, 0.5)
_DH_ROW = {"a": 0.5, "alpha": 0.0, "d": 0.0, "mass": 5.0, "com": [-0.25, 0, 0], "inertia": [0.01, 0.1, 0.1, 0, 0, 0],
           "viscous": 0.5, "coulomb": 1.0}

BASES: dict[str, dict[str, Any]] = {
    "ct": {"name": "fuzz-ct", "plant": {"kind": "robot", "robot": "planar2r"},
           "controller": {"kind": "computed_torque", "damping": 1.0, "natural_frequency": 10},
           "simulation": {"duration": 1.5,
                          "trajectory": {"kind": "quintic", "amplitude": [0.5, -0.3], "duration": 1.0}}},
    "dh": {"name": "fuzz-dh", "plant": {"kind": "robot", "dh": [dict(_DH_ROW), {**_DH_ROW, "a": 0.4, "mass": 3.0}]},
           "controller": {"kind": "computed_torque", "poles": [-10, -12]},
           "simulation": {"duration": 1.5, "trajectory": {"kind": "quintic", "amplitude": 0.2, "duration": 1.0}}},
    "pid": {"name": "fuzz-pid", "plant": {"kind": "robot", "robot": "planar2r", "uncertainty": {"m2": [2.0, 4.0],
                                                                                               "grid": 5}},
            "controller": {"kind": "decentralized_pid", "poles": [-4, -5, -20], "zero": -3},
            "simulation": {"duration": 3.0, "step": [0.5, -0.2]}},
    "ra": {"name": "fuzz-ra", "plant": {"kind": "robot", "robot": "planar2r"},
           "controller": {"kind": "resolved_acceleration", "damping": 1.0, "natural_frequency": 10},
           "simulation": {"duration": 1.5, "initial_position": [0.3, 1.2],
                          "trajectory": {"kind": "line", "displacement": [0.05, 0.05, 0.0], "duration": 1.0}}},
}
"""The base specs (planar arms: an accepted mutant runs in about a second)."""


def _hostile_files(folder: Path) -> dict[str, Path]:
    """Files a URDF path may point at, written into ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    files = {
        "garbage": (folder / "garbage.urdf", bytes(range(256)) * 64),
        "bomb": (folder / "bomb.urdf", ('<?xml version="1.0"?><!DOCTYPE r [<!ENTITY a "aaaaaaaaaa">'
                                        + "".join(f'<!ENTITY {c} "' + f"&{p};" * 10 + '">' for p, c in
                                                  zip("abcdefgh", "bcdefghi", strict=True))
                                        + ']><robot name="r">&i;</robot>').encode()),
        "huge": (folder / "huge.urdf", b"<robot name='h'>" + b"<!-- " + b"x" * (1 << 21) + b" --></robot>"),
        "empty": (folder / "empty.urdf", b""),
        "not-xml": (folder / "plain.urdf", b"this is not a robot\n"),
        "real": (folder / "planar2r.urdf", URDF.read_bytes()),
    }
    for path, data in files.values():
        if not path.exists():
            path.write_bytes(data)
    return {k: p for k, (p, _) in files.items()}


def _set(doc: dict, path: str, value: Any) -> dict:
    out = copy.deepcopy(doc)
    node = out
    keys = path.split(".")
    for key in keys[:-1]:
        node = node.setdefault(key, {}) if not isinstance(node, list) else node[int(key)]
    if isinstance(node, list):
        node[int(keys[-1])] = value
    else:
        node[keys[-1]] = value
    return out


def _robot(rng: random.Random, files: dict[str, Path]) -> tuple[str, dict]:
    name = rng.choice(("puma560", "PUMA560", "", "scara ", "../puma560", "x" * 200, "onelink", "elastic_link", "ïø"))
    doc = _set(BASES["ct"], "plant.robot", name)
    if name in ("onelink", "puma560"):  # a valid robot with the base's two-joint lists: refused per joint
        doc["simulation"]["duration"] = 0.5
    return "plant.robot", doc


def _overrides(rng: random.Random, files: dict[str, Path]) -> tuple[str, dict]:
    names = ("m1", "m2", "d1", "d2", "I1", "I2", "f1", "f2", "g", "m3", "mass", "")
    params = {rng.choice(names): rng.choice(_EXTREME) for _ in range(rng.randint(1, 3))}
    return "plant.parameters", _set(BASES["ct"], "plant.parameters", params)


def _dh(rng: random.Random, files: dict[str, Path]) -> tuple[str, dict]:
    doc = copy.deepcopy(BASES["dh"])
    op = rng.randrange(6)
    if op == 0:
        doc["plant"]["dh"] = [dict(_DH_ROW)] * rng.choice((0, 1, 3, 65))
    elif op == 1:
        row = rng.randrange(2)
        doc["plant"]["dh"][row][rng.choice(("a", "d", "mass", "viscous", "coulomb", "motor_inertia", "gear_ratio",
                                            "offset", "alpha"))] = rng.choice(_EXTREME)
    elif op == 2:
        doc["plant"]["dh"][0]["inertia"] = rng.choice(([-1, 0, 0, 0, 0, 0], [1e4, 1e-6, 1e-6, 0, 0, 0], [0] * 6,
                                                       [1, 2, 3], [0.1] * 7))
    elif op == 3:
        doc["plant"]["dh"][1]["qlim"] = rng.choice(([1, -1], [0, 0], [-100, 100], [0.1, 0.2], [1]))
    elif op == 4:
        del doc["plant"]["dh"][rng.randrange(2)][rng.choice(("mass", "com", "inertia", "a"))]
    else:
        doc["plant"]["convention"] = rng.choice(("modified", "craig", ""))
    return "plant.dh", doc


def _urdf(rng: random.Random, files: dict[str, Path]) -> tuple[str, dict]:
    target = rng.choice((*files, "missing", "folder", "devnull"))
    path = {"missing": str(files["real"].parent / "nope.urdf"), "folder": str(files["real"].parent),
            "devnull": "/dev/null"}.get(target) or str(files[target])
    plant: dict[str, Any] = {"kind": "robot", "urdf": path}
    if target == "real" and rng.random() < 0.6:
        plant[rng.choice(("base_link", "tip_link"))] = rng.choice(("nowhere", "", "link1", "base_link"))
    doc = copy.deepcopy(BASES["ct"])
    doc["plant"] = plant
    return "plant.urdf", doc


def _payload(rng: random.Random, files: dict[str, Path]) -> tuple[str, dict]:
    payload = {"mass": rng.choice(_EXTREME), "link": rng.choice((None, 0, 1, 2, 3, -1, 7))}
    payload = {k: v for k, v in payload.items() if v is not None}
    where = rng.choice(("plant.payload", "controller.model.payload"))
    return where, _set(BASES["ct"], where, payload)


def _limits(rng: random.Random, files: dict[str, Path]) -> tuple[str, dict]:
    key = rng.choice(("velocity", "acceleration", "torque"))
    value = rng.choice((1e-6, 1e6, [1.0], [1.0, 2.0, 3.0], [1e-6, 1e6], 0.5, []))
    return f"plant.limits.{key}", _set(BASES["ct"], f"plant.limits.{key}", value)


def _uncertainty(rng: random.Random, files: dict[str, Path]) -> tuple[str, dict]:
    unc: dict[str, Any] = rng.choice(({"m2": [2.0, 4.0]}, {"m1": [4, 6], "m2": [2, 4], "f1": [1, 3], "f2": [0.5, 2]},
                                      {f"p{k}": [1, 2] for k in range(12)}, {"m2": [4.0, 2.0]}, {"m2": [-1.0, 1.0]},
                                      {"nothing": [1, 2]}, {"m2": [3.0, 3.0]}))
    unc = dict(unc)
    unc["grid"] = rng.choice((2, 21, 1001, 1, 1002))
    unc["samples"] = rng.choice((0, 5, 100000, 100001, -1))
    if rng.random() < 0.3:
        unc["seed"] = rng.choice((0, 2**32 - 1, 2**32))
    return "plant.uncertainty", _set(BASES[rng.choice(("ct", "pid"))], "plant.uncertainty", unc)


def _workspace(rng: random.Random, files: dict[str, Path]) -> tuple[str, dict]:
    ws: dict[str, Any] = {}
    for key in ("low", "high"):
        if rng.random() < 0.8:
            ws[key] = rng.choice((-1.0, 1.0, 0.0, [-1.0, -2.0], [1.0, 2.0], [0.0], 100.0, -100.0))
    if rng.random() < 0.5:
        ws["tolerance"] = rng.choice((1e-9, 0.1, 1e-3, 0.0))
    if rng.random() < 0.5:
        ws["samples"] = rng.choice((2, 101, 1, 1000))
    return "controller.workspace", _set(BASES["pid"], "controller.workspace", rng.choice((ws, "joint_limits")))


def _computed_torque(rng: random.Random, files: dict[str, Path]) -> tuple[str, dict]:
    doc = copy.deepcopy(BASES["ct"])
    ctrl = doc["controller"]
    op = rng.randrange(4)
    if op == 0:
        del ctrl["damping"], ctrl["natural_frequency"]
        ctrl["poles"] = rng.choice(([-10, -12], [[-10, -12], [-5, -6]], [[-10, -12]], ["-3+4j", "-3-4j"],
                                    ["-3+4j", -3], [-1e-12, -1e12], [0, -1], [[-10, -12], -5]))
    elif op == 1:
        ctrl[rng.choice(("damping", "natural_frequency"))] = rng.choice((1e-6, 1e3, [1.0, 2.0], [1.0], 1e12, 1e-12))
    elif op == 2:
        ctrl["friction_layer"] = rng.choice((0, 1e-6, 1e3, 0.05, 1e-7, -0.1))
    else:
        ctrl["model"] = rng.choice(({"parameters": {"m2": 3.3}}, {"friction": False}, {"parameters": {"zz": 1}},
                                    {"payload": {"mass": 1e4}}, {}))
    return "controller", doc


def _resolved_acceleration(rng: random.Random, files: dict[str, Path]) -> tuple[str, dict]:
    doc = copy.deepcopy(BASES["ra"])
    ctrl = doc["controller"]
    op = rng.randrange(3)
    if op == 0:
        ctrl["orientation"] = rng.choice(("held", "none", "free"))
    elif op == 1:
        ctrl["damped_least_squares"] = {"damping": rng.choice((1e-6, 1e3, 0.01, 0, 1e4))}
    else:
        ctrl["max_condition"] = rng.choice((1, 1.0001, 1e12, 1e13, 10))
    return "controller", doc


def _task_path(rng: random.Random, files: dict[str, Path]) -> tuple[str, dict]:
    doc = copy.deepcopy(BASES["ra"])
    kind = rng.choice(("line", "circle"))
    if kind == "line":
        traj = {"kind": "line", rng.choice(("to", "displacement")): rng.choice(
            ([0, 0, 0], [5, 5, 0], [0.05, 0, 0], [0, 0, 1], [100, 100, 100])),
            "duration": rng.choice((1e-3, 1.0, 1e9, 0.5))}
    else:
        traj = {"kind": "circle", "center": rng.choice(([0.5, 0.5, 0], [0.3, 0.9, 0], [0, 0, 0], [10, 0, 0])),
                "normal": rng.choice(([0, 0, 1], [0, 0, 0], [1, 0, 0])), "turns": rng.choice((0.25, 100, -1, 0)),
                "duration": rng.choice((1e-3, 1.0, 2.0))}
    doc["simulation"]["trajectory"] = traj
    return "simulation.trajectory", doc


def _via_points(rng: random.Random, files: dict[str, Path]) -> tuple[str, dict]:
    doc = copy.deepcopy(BASES["ct"])
    n = rng.choice((1, 3, 1000, 1001))
    times = [0.001 * (k + 1) for k in range(n)] if rng.random() < 0.5 else [0.5 * (k + 1) for k in range(n)]
    if rng.random() < 0.3 and n > 1:
        times[0], times[1] = times[1], times[0]
    points = [rng.choice(([0.1, -0.1], [0.2], 0.1, [0.1, 0.1, 0.1])) for _ in range(n)]
    doc["simulation"] = {"trajectory": {"kind": "via_points", "times": times, "points": points}}
    return "simulation.trajectory", doc


def _numerics(rng: random.Random, files: dict[str, Path]) -> tuple[str, dict]:
    numerics = {rng.choice(("integrator", "compile", "rtol", "atol", "solver")): None}
    key = next(iter(numerics))
    numerics[key] = {"integrator": rng.choice(("rk4", "cvodes", "euler", "dopri5")),
                     "compile": rng.choice(("auto", "always", "never", "sometimes")),
                     "rtol": rng.choice((1e-14, 0.1, 1e-15, 0.2)), "atol": rng.choice((1e-20, 1.0, 1e-21, 2.0)),
                     "solver": rng.choice(("CLARABEL", "SCS", "MOSEK"))}[key]
    return f"numerics.{key}", _set(BASES[rng.choice(("ct", "pid"))], "numerics", numerics)


def _per_joint(rng: random.Random, files: dict[str, Path]) -> tuple[str, dict]:
    base = rng.choice(("ct", "pid", "dh"))
    doc = copy.deepcopy(BASES[base])
    length = rng.choice((0, 1, 3, 40))
    value = [0.1] * length
    keys = ["simulation.initial_position", "requirements.max_control", "plant.limits.torque"]
    keys += ["simulation.trajectory.amplitude", "controller.damping"] if base != "pid" else ["simulation.step"]
    key = rng.choice(keys)
    if key == "controller.damping" and "poles" in doc["controller"]:
        key = "simulation.initial_position"
    return key, _set(doc, key, value)


GENERATORS: tuple[Callable[[random.Random, dict[str, Path]], tuple[str, dict]], ...] = (
    _robot, _overrides, _dh, _urdf, _payload, _limits, _uncertainty, _workspace, _computed_torque,
    _resolved_acceleration, _task_path, _via_points, _numerics, _per_joint,
)
"""One generator per field group, each ``(rng, files) -> (key path, spec document)``."""


def field_mutants(seed: int, count: int, folder: Path) -> list[Mutant]:
    """``count`` field-targeted mutants drawn with ``random.Random(seed)``, cycling through :data:`GENERATORS`
    (so every field group is reached once ``count >= len(GENERATORS)``); hostile files go to ``folder``."""
    rng = random.Random(seed)
    files = _hostile_files(folder)
    out = []
    for k in range(count):
        gen = GENERATORS[k % len(GENERATORS)]
        key, doc = gen(rng, files)
        out.append(Mutant(yaml.safe_dump(doc, sort_keys=False, width=10**6), f"base:{gen.__name__[1:]}",
                          gen.__name__[1:], key))
    return out
