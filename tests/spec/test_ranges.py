"""Ranges of the spec's numbers: extreme but finite values are refused with the key path
and the range, or designed; never an internal error.

* extreme inputs outside the ranges through ``designkit synth`` (exit 2, one line naming the key path and the range);
* every declared range (:func:`designkit.schema.ranges_table.declared_ranges`): a value inside is accepted, one just
  outside refused with the key path (hypothesis);
* the poles' own rules (modulus, spread), uncertainty intervals, the README table and the JSON Schema;
* extreme values inside the ranges through ``verify`` and ``synth``: exit 0 or 1, the same from both.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import pytest
import yaml
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from designkit.cli import main
from designkit.errors import SpecError
from designkit.schema import ranges_table as ranges
from designkit.schema.loader import parse_spec
from designkit.schema.ranges_table import declared_ranges
from designkit.schema.spec import Spec
from designkit.spec.ranges import POLE_MODULUS, POLE_SPREAD, Range, fmt_value
from tests.cli_input import assert_bad_input
from tests.problems import discovered

ROOT = Path(__file__).resolve().parents[2]

LINK = """\
name: ranges-link
plant: {kind: link, Km: 2.0, tau: 0.5}
controller: {kind: pid_servo, poles: [-4, -5, -20], zero: -3}
"""
SATURATION = LINK + """\
requirements: {overshoot: 10, settling_time: 2.0, steady_state_error: 0.005}
simulation: {duration: 4.0, nonlinearity: {kind: saturation, limit: 20}}
"""
QUANTIZER = LINK + """\
simulation: {duration: 4.0, nonlinearity: {kind: quantizer, step: 0.25}, sampling_period: 0.005, delay: 0.002,
             noise: {std: 0.0005, seed: 1}}
"""
DERIVED = """\
name: ranges-derived
plant: {kind: link, Km: 2.0, tau: 0.5}
controller: {kind: pid_servo, third_pole_factor: 5}
requirements: {overshoot: 5, settling_time: 1.5}
simulation: {duration: 4.0}
"""
TRACKING = """\
name: ranges-tracking
plant: {kind: link, Km: 2.0, tau: 0.5, uncertainty: {Km: [1.6, 2.4], tau: [0.4, 0.6], grid: 5}}
controller: {kind: pid_tracking, poles: [-10, -12, -15]}
simulation:
  duration: 3.0
  trajectory: {kind: quintic, amplitude: 1.0, duration: 1.0}
"""


# ----------------------------------------------------------------------------- extreme inputs outside the ranges


OUT_OF_RANGE_INPUTS = [
    # (base, replace, by, message: key path and range)
    (LINK, "Km: 2.0", "Km: 1.0e+308", "plant.Km: must be between 1e-6 and 1e6 (rad/s)/(N*m), got 1e+308"),
    (LINK, "Km: 2.0", "Km: 1.0e-308", "plant.Km: must be between 1e-6 and 1e6 (rad/s)/(N*m), got 1e-308"),
    (LINK, "Km: 2.0", "Km: 5.0e-324", "plant.Km: must be between 1e-6 and 1e6 (rad/s)/(N*m), got 5e-324"),
    (LINK, "tau: 0.5", "tau: 1.0e+308", "plant.tau: must be between 1e-6 and 1e6 s, got 1e+308"),
    (LINK, "tau: 0.5", "tau: 1.0e-308", "plant.tau: must be between 1e-6 and 1e6 s, got 1e-308"),
    (LINK, "tau: 0.5", "tau: 5.0e-324", "plant.tau: must be between 1e-6 and 1e6 s, got 5e-324"),
    (LINK, "-20]", "-1.0e+150]", "controller.poles[2]: |p| must be between 1e-12 and 1e12 1/s, got -1e+150"),
    (LINK, "-20]", "-1.0e-308]", "controller.poles[2]: |p| must be between 1e-12 and 1e12 1/s, got -1e-308"),
    (LINK, "-20]", "-4" + "0" * 399 + "]", "controller.poles[2]: "),  # a 400-digit integer (refused at parse)
    (SATURATION, "duration: 4.0", "duration: 1.0e+308", "simulation.duration: must be between 1e-6 and 1e9 s"),
    (SATURATION, "duration: 4.0", "duration: 5.0e-324", "simulation.duration: must be between 1e-6 and 1e9 s"),
    (QUANTIZER, "sampling_period: 0.005", "sampling_period: 1.0e+308",
     "simulation.sampling_period: must be 0 or between 1e-6 and 1e3 s, got 1e+308"),
    (QUANTIZER, "sampling_period: 0.005", "sampling_period: 5.0e-324",
     "simulation.sampling_period: must be 0 or between 1e-6 and 1e3 s, got 5e-324"),
    (QUANTIZER, "delay: 0.002", "delay: 1.0e+308", "simulation.delay: must be 0 or between 1e-6 and 1e3 s"),
    (QUANTIZER, "delay: 0.002", "delay: 5.0e-324", "simulation.delay: must be 0 or between 1e-6 and 1e3 s"),
    (QUANTIZER, "seed: 1", "seed: -1", "simulation.noise.seed: must be non-negative, got -1"),
    (QUANTIZER, "seed: 1", "seed: 4294967296", "simulation.noise.seed: must be between 0 and 4294967295"),
    (SATURATION, "settling_time: 2.0", "settling_time: 1.0e+308",
     "requirements.settling_time: must be between 1e-6 and 1e9 s, got 1e+308"),
    (DERIVED, "third_pole_factor: 5", "third_pole_factor: 1.0e-308",
     "controller.third_pole_factor: must be between 1 and 100, got 1e-308"),
    (TRACKING, "duration: 1.0}", "duration: 1.0e-308}",
     "simulation.trajectory.duration: must be between 1e-3 and 1e9 s, got 1e-308"),
    (TRACKING, "Km: [1.6, 2.4]", "Km: [1.0, 1.0e+308]",
     "plant.uncertainty.Km: interval bounds must be between 1e-6 and 1e6 (rad/s)/(N*m)"),
    # outside the element's and the requirement's ranges (the report's figures draw any finite value:
    # tests/report/test_extreme_values.py)
    (SATURATION, "limit: 20", "limit: 1.0e+308", "simulation.nonlinearity.limit: must be between 1e-6 and 1e6 N*m"),
    (SATURATION, "steady_state_error: 0.005", "steady_state_error: 1.0e+308",
     "requirements.steady_state_error: must be between 0 and 100 rad or m"),
]


@pytest.mark.parametrize(("base", "replace", "by", "message"), OUT_OF_RANGE_INPUTS,
                         ids=[f"{m.split(':')[0]}={b.split(': ')[-1][:12]}" for _, _, b, m in OUT_OF_RANGE_INPUTS])
def test_an_out_of_range_input_is_refused_with_the_key_path_and_the_range(tmp_path, capsys, base, replace, by, message):
    text = base.replace(replace, by)
    assert text != base
    assert_bad_input(tmp_path, capsys, text, message)


def test_an_out_of_range_input_is_refused_the_same_way_by_verify(tmp_path, capsys):
    spec = tmp_path / "spec.yaml"
    spec.write_text(LINK.replace("Km: 2.0", "Km: 1.0e+308"))
    assert main(["verify", str(spec), "--json"]) == 2
    err = capsys.readouterr().err
    assert err == "designkit: error: plant.Km: must be between 1e-6 and 1e6 (rad/s)/(N*m), got 1e+308\n"


# ----------------------------------------------------------------------------- every declared range

ROBOT_DH = """\
name: ranges-dh
plant:
  kind: robot
  dh:
    - {a: 0.5, mass: 5, com: [-0.25, 0, 0], inertia: [0, 0, 0.1, 0, 0, 0], viscous: 2, qlim: [-3, 3]}
    - {a: 0.4, mass: 3, com: [-0.2, 0, 0], inertia: [0, 0, 0.04, 0, 0, 0], viscous: 1, qlim: [-3, 3]}
  gravity: [0, -9.81, 0]
  payload: {mass: 1}
  limits: {velocity: 10, acceleration: 100, torque: 1000}
controller: {kind: decentralized_pid, poles: [-4.4, -5.5, -20.2], zero: -3.3, configuration: [0, 0],
             workspace: {low: [-1, -1], high: [1, 1], samples: 5}}
"""
ROBOT = """\
name: ranges-robot
plant: {kind: robot, robot: planar2r, parameters: {m2: 3.0}, uncertainty: {m2: [2.0, 4.0], grid: 5, samples: 1,
        seed: 1}}
controller: {kind: computed_torque, damping: 1.0, natural_frequency: 20, model: {parameters: {m2: 3.3},
             payload: {mass: 0.1}}}
simulation: {trajectory: {kind: quintic, amplitude: [1.0, -0.5], duration: 1.0}}
"""
TASK = """\
name: ranges-task
plant: {kind: robot, robot: puma560}
controller: {kind: resolved_acceleration, damping: 1.0, natural_frequency: 10, orientation: held,
             damped_least_squares: {damping: 0.025}, max_condition: 100}
simulation: {trajectory: {kind: circle, center: [0.5, 0.1, 0.4], normal: [0, 0, 1], turns: 0.25, duration: 2.0}}
"""
LINE = TASK.replace("{kind: circle, center: [0.5, 0.1, 0.4], normal: [0, 0, 1], turns: 0.25, duration: 2.0}",
                    "{kind: line, to: [0.5, 0.1, 0.4], duration: 2.0}")
ELASTIC = LINK.replace("{kind: link, Km: 2.0, tau: 0.5}", "{kind: elastic_joint, J1: 5.0e-5, tau1: 0.05, Km: 2.0, "
                       "KR: 200.0, R1: 0.02, R2: 1.0, J2: 0.5, tau2: 2.0, mgl: 0.0}")
SERVO = """\
name: ranges-servo
plant: {kind: link, Km: 2.0, tau: 0.5, uncertainty: {Km: [1.6, 2.4], tau: [0.4, 0.6], grid: 5, samples: 1, seed: 1}}
controller: {kind: pid_servo, poles: [-4.4, -5.5, -20.2], zero: -3.3}
requirements: {overshoot: 10, settling_time: 2.0, rise_time: 1.0, steady_state_error: 0.005, tracking_error: 0.1,
               max_control: 40, settling_band: 0.02}
simulation: {duration: 4.0, step: 1.0, initial_position: 0.0, dt: 0.001, delay: 0.002, sampling_period: 0.004,
             nonlinearity: {kind: saturation, limit: 20}, noise: {std: 0.001, seed: 1},
             perturbation: {value: 1.0, time: 1.0}, anti_windup: {kind: saturation, value: 25}}
numerics: {rtol: 1.0e-8, atol: 1.0e-10}
"""
LINEAR_TF = """\
name: ranges-transfer-function
plant: {kind: transfer_function, num: [1, 2], den: [1, 1, 0], parameters: {a: 1.0}}
controller: {kind: state_regulator, poles: [-6, -8]}
"""
LINEAR_SS = """\
name: ranges-state-space
plant: {kind: state_space, A: [[0, 1], [0, 0]], B: [[0], [1]], C: [[1, 0], [0, 1]], D: [[0], [0]]}
controller: {kind: state_regulator, poles: [-6, -8]}
"""
SLIDING = """\
name: ranges-sliding
plant: {kind: link, Km: 2.0, tau: 0.5, uncertainty: {Km: [1.4, 2.6], tau: [0.35, 0.65]}}
controller: {kind: sliding_mode, sliding_poles: [-5]}
requirements: {max_chatter_amplitude: 1.0}
simulation: {duration: 0.5, perturbation: {value: 1.0, time: 0.2}}
"""
IMPLEMENTED = SERVO + ("implementation: {sampling_period: 0.004, delay: 0.002, quantization: 0.001, "
                       "actuator: {limit: 20, bandwidth: 300}}\n")
SERVO_DERIVED = SERVO.replace("poles: [-4.4, -5.5, -20.2], zero: -3.3", "third_pole_factor: 5, design_margin: 0.1")


def _with(text: str, path: str, value: object) -> str:
    """``text`` (YAML) with the value at ``path`` (dots, list indices as numbers) replaced."""
    data = yaml.safe_load(text)
    node = data
    keys = path.split(".")
    for key in keys[:-1]:
        node = node[int(key)] if key.isdigit() else node[key]
    last = keys[-1]
    if last.isdigit():
        node[int(last)] = value
    else:
        node[last] = value
    return yaml.safe_dump(data, sort_keys=False)


def _trajectory(kind: str) -> str:
    trajectories = {
        "sine": "{kind: sine, amplitude: 1.0, frequency: 1.0}",
        "trapezoidal": "{kind: trapezoidal, amplitude: 1.0, max_velocity: 2.0, max_acceleration: 4.0, duration: 2.0}",
        "via_points": "{kind: via_points, times: [1.0], points: [1.0]}",
    }
    return TRACKING.replace("{kind: quintic, amplitude: 1.0, duration: 1.0}", trajectories[kind])


def _element(kind: str) -> str:
    elements = {"dead_zone": "{kind: dead_zone, width: 0.5}", "relay": "{kind: relay, amplitude: 20, hysteresis: 0.5}",
                "quantizer": "{kind: quantizer, step: 0.25}"}
    return SERVO.replace("{kind: saturation, limit: 20}", elements[kind])


# declared key path -> [(base spec, concrete path to set, the key path the loader names)]
WHERE: dict[str, list[tuple[str, str, str]]] = {
    "plant.Km": [(SERVO, "plant.Km", "plant.Km"), (ELASTIC, "plant.Km", "plant.Km")],
    "plant.tau": [(SERVO, "plant.tau", "plant.tau")],
    "plant.uncertainty.grid": [(SERVO, "plant.uncertainty.grid", "plant.uncertainty.grid")],
    "plant.uncertainty.samples": [(SERVO, "plant.uncertainty.samples", "plant.uncertainty.samples")],
    "plant.uncertainty.seed": [(SERVO, "plant.uncertainty.seed", "plant.uncertainty.seed")],
    "plant.parameters.<name>": [(ROBOT, "plant.parameters.m2", "plant.parameters.m2"),
                                (LINEAR_TF, "plant.parameters.a", "plant.parameters.a")],
    "plant.num[]": [(LINEAR_TF, "plant.num.1", "plant.num[1]")],
    "plant.den[]": [(LINEAR_TF, "plant.den.2", "plant.den[2]")],
    "plant.A[][]": [(LINEAR_SS, "plant.A.1.0", "plant.A[1][0]")],
    "plant.B[][]": [(LINEAR_SS, "plant.B.0.0", "plant.B[0][0]")],
    "plant.C[][]": [(LINEAR_SS, "plant.C.1.1", "plant.C[1][1]")],
    "plant.D[][]": [(LINEAR_SS, "plant.D.1.0", "plant.D[1][0]")],
    "plant.dh[].a": [(ROBOT_DH, "plant.dh.1.a", "plant.dh[1].a")],
    "plant.dh[].alpha": [(ROBOT_DH, "plant.dh.1.alpha", "plant.dh[1].alpha")],
    "plant.dh[].d": [(ROBOT_DH, "plant.dh.0.d", "plant.dh[0].d")],
    "plant.dh[].theta": [(ROBOT_DH, "plant.dh.0.theta", "plant.dh[0].theta")],
    "plant.dh[].offset": [(ROBOT_DH, "plant.dh.1.offset", "plant.dh[1].offset")],
    "plant.dh[].mass": [(ROBOT_DH, "plant.dh.1.mass", "plant.dh[1].mass")],
    "plant.dh[].com[]": [(ROBOT_DH, "plant.dh.1.com.2", "plant.dh[1].com[2]")],
    "plant.dh[].inertia[0..2]": [(ROBOT_DH, "plant.dh.0.inertia.1", "plant.dh[0].inertia[1]")],
    "plant.dh[].inertia[3..5]": [(ROBOT_DH, "plant.dh.0.inertia.4", "plant.dh[0].inertia[4]")],
    "plant.dh[].viscous": [(ROBOT_DH, "plant.dh.0.viscous", "plant.dh[0].viscous")],
    "plant.dh[].coulomb": [(ROBOT_DH, "plant.dh.0.coulomb", "plant.dh[0].coulomb")],
    "plant.dh[].motor_inertia": [(ROBOT_DH, "plant.dh.0.motor_inertia", "plant.dh[0].motor_inertia")],
    "plant.dh[].gear_ratio": [(ROBOT_DH, "plant.dh.0.gear_ratio", "plant.dh[0].gear_ratio")],
    "plant.dh[].qlim[]": [(ROBOT_DH, "plant.dh.0.qlim.0", "plant.dh[0].qlim[0]")],
    "plant.gravity[]": [(ROBOT_DH, "plant.gravity.1", "plant.gravity[1]")],
    "plant.payload.mass": [(ROBOT_DH, "plant.payload.mass", "plant.payload.mass")],
    "plant.limits.velocity": [(ROBOT_DH, "plant.limits.velocity", "plant.limits.velocity")],
    "plant.limits.acceleration": [(ROBOT_DH, "plant.limits.acceleration", "plant.limits.acceleration")],
    "plant.limits.torque": [(ROBOT_DH, "plant.limits.torque", "plant.limits.torque")],
    **{f"plant.{k}": [(ELASTIC, f"plant.{k}", f"plant.{k}")] for k in ("J1", "tau1", "KR", "R1", "R2", "J2", "tau2",
                                                                       "mgl")},
    "controller.model.parameters.<name>": [(ROBOT, "controller.model.parameters.m2",
                                            "controller.model.parameters.m2")],
    "controller.model.payload.mass": [(ROBOT, "controller.model.payload.mass", "controller.model.payload.mass")],
    "controller.third_pole_factor": [(SERVO_DERIVED, "controller.third_pole_factor", "controller.third_pole_factor")],
    "controller.design_margin": [(SERVO_DERIVED, "controller.design_margin", "controller.design_margin")],
    "controller.zero": [(SERVO, "controller.zero", "controller.zero"),
                        (ROBOT_DH, "controller.zero", "controller.zero")],
    "controller.configuration": [(ROBOT_DH, "controller.configuration", "controller.configuration")],
    "controller.workspace.low": [(ROBOT_DH, "controller.workspace.low", "controller.workspace.low")],
    "controller.workspace.high": [(ROBOT_DH, "controller.workspace.high", "controller.workspace.high")],
    "controller.workspace.samples": [(ROBOT_DH, "controller.workspace.samples", "controller.workspace.samples")],
    "controller.workspace.tolerance": [(ROBOT_DH, "controller.workspace.tolerance",
                                        "controller.workspace.tolerance")],
    "controller.damping": [(ROBOT, "controller.damping", "controller.damping")],
    "controller.natural_frequency": [(ROBOT, "controller.natural_frequency", "controller.natural_frequency")],
    "controller.damped_least_squares.damping": [(TASK, "controller.damped_least_squares.damping",
                                                 "controller.damped_least_squares.damping")],
    "controller.max_condition": [(TASK, "controller.max_condition", "controller.max_condition")],
    "controller.friction_layer": [(ROBOT, "controller.friction_layer", "controller.friction_layer"),
                                  (TASK, "controller.friction_layer", "controller.friction_layer")],
    **{f"requirements.{k}": [(SERVO, f"requirements.{k}", f"requirements.{k}")] for k in (
        "overshoot", "settling_time", "rise_time", "steady_state_error", "tracking_error", "max_control",
        "settling_band", "gain_margin", "phase_margin", "modulus_margin", "max_reversal_rate",
        "max_command_variation")},
    "requirements.max_chatter_amplitude": [(SLIDING, "requirements.max_chatter_amplitude",
                                            "requirements.max_chatter_amplitude")],
    **{f"simulation.{k}": [(SERVO, f"simulation.{k}", f"simulation.{k}")] for k in (
        "duration", "step", "initial_position", "dt", "delay", "sampling_period")},
    "simulation.nonlinearity.limit": [(SERVO, "simulation.nonlinearity.limit", "simulation.nonlinearity.limit")],
    **{f"simulation.nonlinearity.{k}": [(_element(kind), f"simulation.nonlinearity.{k}",
                                         f"simulation.nonlinearity.{k}")]
       for k, kind in (("width", "dead_zone"), ("amplitude", "relay"), ("hysteresis", "relay"), ("step", "quantizer"))},
    "simulation.noise.std": [(SERVO, "simulation.noise.std", "simulation.noise.std")],
    "simulation.noise.seed": [(SERVO, "simulation.noise.seed", "simulation.noise.seed")],
    "simulation.perturbation.value": [(SERVO, "simulation.perturbation.value", "simulation.perturbation.value")],
    "simulation.perturbation.time": [(SERVO, "simulation.perturbation.time", "simulation.perturbation.time")],
    "simulation.anti_windup.value": [(SERVO, "simulation.anti_windup.value", "simulation.anti_windup.value")],
    "simulation.trajectory.amplitude": [(TRACKING, "simulation.trajectory.amplitude",
                                         "simulation.trajectory.amplitude"),
                                        (_trajectory("sine"), "simulation.trajectory.amplitude",
                                         "simulation.trajectory.amplitude")],
    "simulation.trajectory.duration": [(TRACKING, "simulation.trajectory.duration", "simulation.trajectory.duration"),
                                       (_trajectory("trapezoidal"), "simulation.trajectory.duration",
                                        "simulation.trajectory.duration"),
                                       (TASK, "simulation.trajectory.duration", "simulation.trajectory.duration"),
                                       (LINE, "simulation.trajectory.duration", "simulation.trajectory.duration")],
    "simulation.trajectory.frequency": [(_trajectory("sine"), "simulation.trajectory.frequency",
                                         "simulation.trajectory.frequency")],
    "simulation.trajectory.offset": [(_trajectory("sine"), "simulation.trajectory.offset",
                                      "simulation.trajectory.offset")],
    "simulation.trajectory.phase": [(_trajectory("sine"), "simulation.trajectory.phase",
                                     "simulation.trajectory.phase")],
    **{f"simulation.trajectory.{k}": [(_trajectory("trapezoidal"), f"simulation.trajectory.{k}",
                                       f"simulation.trajectory.{k}")] for k in ("max_velocity", "max_acceleration")},
    "simulation.trajectory.times[]": [(_trajectory("via_points"), "simulation.trajectory.times.0",
                                       "simulation.trajectory.times[0]")],
    "simulation.trajectory.points[]": [(_trajectory("via_points"), "simulation.trajectory.points.0",
                                        "simulation.trajectory.points[0]")],
    "simulation.trajectory.to[]": [(LINE, "simulation.trajectory.to.1", "simulation.trajectory.to[1]")],
    "simulation.trajectory.displacement[]": [(LINE.replace("to:", "displacement:"), "simulation.trajectory."
                                              "displacement.2", "simulation.trajectory.displacement[2]")],
    "simulation.trajectory.center[]": [(TASK, "simulation.trajectory.center.0", "simulation.trajectory.center[0]")],
    "simulation.trajectory.normal[]": [(TASK, "simulation.trajectory.normal.0", "simulation.trajectory.normal[0]")],
    "simulation.trajectory.turns": [(TASK, "simulation.trajectory.turns", "simulation.trajectory.turns")],
    **{f"implementation.{k}": [(IMPLEMENTED, f"implementation.{k}", f"implementation.{k}")] for k in (
        "sampling_period", "delay", "quantization", "actuator.limit", "actuator.bandwidth")},
    "numerics.rtol": [(SERVO, "numerics.rtol", "numerics.rtol")],
    "numerics.atol": [(SERVO, "numerics.atol", "numerics.atol")],
    "studies.budget": [(SERVO + "studies: {budget: 30}\n", "studies.budget", "studies.budget")],
}

SQUARE = SERVO.replace("anti_windup: {kind: saturation, value: 25}}", "anti_windup: {kind: saturation, value: 25}, "
                       "trajectory: {kind: square, amplitude: 0.5, period: 2.0}, "
                       "plant_change: {time: 2.0, values: {Km: 2.5}}}")
PRBS = SQUARE.replace("{kind: square, amplitude: 0.5, period: 2.0}", "{kind: prbs, amplitude: 0.5, bit: 0.5, order: 5, "
                      "seed: 3}")
WHERE.update({
    "simulation.trajectory.period": [(SQUARE, "simulation.trajectory.period", "simulation.trajectory.period")],
    **{f"simulation.trajectory.{k}": [(PRBS, f"simulation.trajectory.{k}", f"simulation.trajectory.{k}")]
       for k in ("bit", "order", "seed")},
    "simulation.plant_change.time": [(SQUARE, "simulation.plant_change.time", "simulation.plant_change.time")],
    "simulation.plant_change.values.<name>": [(SQUARE, "simulation.plant_change.values.Km",
                                               "simulation.plant_change.values.Km")],
})
for _ranges in discovered("RANGES").values():  # a family's own section: the cases its tests declare
    WHERE.update(_ranges)

ROWS = {(row.path, row.range) for row in declared_ranges()}
CASES = [(path, rng, base, where, key) for path, rng in sorted(ROWS, key=lambda r: r[0])
         for base, where, key in WHERE.get(path, [])]


def test_every_declared_range_is_exercised():
    """A new ranged field must be added to WHERE (and so to the property tests below)."""
    assert {path for path, _ in ROWS} == set(WHERE)


def _is_int(rng: Range) -> bool:
    return isinstance(rng.low, int) and isinstance(rng.high, int)


def inside(rng: Range) -> st.SearchStrategy:
    """Values in the range: its ends (closed ends), then uniform, log-uniform over positive ranges spanning
    decades, and 0 where 0 means none; never a subnormal number (refused everywhere, see
    ``test_loose_types.py``)."""
    if _is_int(rng):
        return st.integers(int(rng.low), int(rng.high))
    options = [st.floats(rng.low, rng.high, exclude_min=rng.low_open, exclude_max=rng.high_open,
                         allow_subnormal=False)]
    if rng.low > 0 and rng.high / rng.low > 1e3:
        options.append(st.floats(math.log10(rng.low), math.log10(rng.high)).map(lambda e: 10.0**e).filter(
            rng.contains))
    ends = [v for v, open_ in ((rng.low, rng.low_open), (rng.high, rng.high_open)) if not open_]
    if ends:
        options.append(st.sampled_from(ends))
    if rng.zero:
        options.append(st.just(0.0))
    return st.one_of(options)


def just_outside(rng: Range) -> list[float]:
    """The nearest refused values on either side: the next float (or integer) beyond a closed end, an open end
    itself, and, where 0 is also accepted, the largest value between 0 and the low end."""
    if _is_int(rng):
        return [int(rng.low) - 1, int(rng.high) + 1]
    out = [rng.low if rng.low_open else math.nextafter(rng.low, -math.inf),
           rng.high if rng.high_open else math.nextafter(rng.high, math.inf)]
    if rng.zero:
        out.append(math.nextafter(rng.low, 0.0))
    return out


def _parse(text: str) -> SpecError | None:
    try:
        parse_spec(text)
    except SpecError as exc:
        return exc
    return None


def _accepted(text: str, key: str) -> None:
    error = _parse(text)
    if "elastic_joint" in text:
        # a base whose controller does not take an elastic joint is refused there, after the plant (pid_servo takes
        # it: the link-position PID from the rigid approximation)
        assert error is None or error.path == "controller.kind", error
        return
    assert error is None, f"{key}: {error}"


@pytest.mark.parametrize(("path", "rng", "base", "where", "key"), CASES, ids=[f"{c[4]}@{c[2].split()[1]}"
                                                                             for c in CASES])
@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data())
def test_a_value_inside_the_range_is_accepted_one_just_outside_refused(data, path, rng, base, where, key):
    value = data.draw(inside(rng), label="inside")
    if key == "controller.zero":
        assume(all(abs(value - p) > 1e-6 for p in (-4.4, -5.5, -20.2)))  # a zero on a pole is refused otherwise
    _accepted(_with(base, where, value), key)
    for bad in just_outside(rng):
        error = _parse(_with(base, where, bad))
        assert error is not None, (key, bad)
        assert error.path == key, (key, bad, str(error))
        # the range's message, or the base type's for the sign (``Input should be greater than 0``)
        assert re.search(r"must be|should be", error.message) and fmt_value(bad) in error.message, str(error)


@pytest.mark.parametrize("key", ["simulation.step", "requirements.max_control", "simulation.nonlinearity.limit"])
def test_a_per_joint_entry_outside_its_range_is_named_by_its_index(key):
    text = _with(SERVO, key, [1.0, 1.0e7])
    error = _parse(text)
    assert error is not None and error.path == f"{key}[1]", error
    assert "got 10000000.0" in error.message


# ----------------------------------------------------------------------------- poles


@pytest.mark.parametrize(("poles", "key", "words"), [
    ("[-4, -5, -1.0e+13]", "controller.poles[2]", "|p| must be between 1e-12 and 1e12 1/s"),
    ("[-1.0e-13, -5, -20]", "controller.poles[0]", "|p| must be between 1e-12 and 1e12 1/s"),
    ("['-1.0e-300+1j', '-1.0e-300-1j', -20]", "controller.poles", "max |p| / min |Re p|"),
    ("[-1.0e-9, -5, -1.0e+6]", "controller.poles", "max |p| / min |Re p| = 1e+15 > 1e12"),
])
def test_poles_beyond_double_precision_are_refused(poles, key, words):
    error = _parse(LINK.replace("[-4, -5, -20]", poles))
    assert error is not None and error.path == key, error
    assert words in error.message


@pytest.mark.parametrize("poles", ["[-1, -2, -1.0e+6]", "[-1.0e-9, -2, -4]", "[-4, -5, -1.0e+12]",
                                   "['-1.0e-3+1.0e+9j', '-1.0e-3-1.0e+9j', -1]"])
def test_stiff_and_slow_poles_within_the_spread_are_accepted(poles):
    assert _parse(LINK.replace("[-4, -5, -20]", poles)) is None


@given(fast=st.floats(1.0, 12.0), slow=st.floats(-12.0, 0.0))
@settings(max_examples=50, deadline=None)
def test_the_spread_rule_is_max_modulus_over_min_decay(fast, slow):
    poles = [-(10.0**slow), -2.0 * 10.0**slow, -(10.0**fast)]
    spread = max(abs(p) for p in poles) / min(abs(p) for p in poles)
    text = LINK.replace("[-4, -5, -20]", json.dumps(poles)).replace("zero: -3", "zero: -3.3")
    error = _parse(text)
    if spread <= POLE_SPREAD and all(POLE_MODULUS.contains(abs(p)) for p in poles):
        assert error is None, error
    else:
        assert error is not None and error.path.startswith("controller.poles"), error


@pytest.mark.parametrize(("controller", "key", "words"), [
    ("{kind: computed_torque, poles: [-20, -1.0e+13]}", "controller.poles[1]", "|p| must be between"),
    ("{kind: computed_torque, poles: [[-20, -20], [-1.0e-6, -1.0e+7]]}", "controller.poles[1]", "max |p| / min |Re p|"),
    ("{kind: computed_torque, poles: [[-1.0e-6, -1.0e-6], [-1.0e+7, -1.0e+7]]}", "controller.poles", "max |p|"),
    ("{kind: computed_torque, damping: 1000, natural_frequency: 1.0e+10}", "controller.natural_frequency",
     "|p| must be between 1e-12 and 1e12 1/s"),
    ("{kind: computed_torque, damping: [1, 1], natural_frequency: [1.0e-6, 1.0e+7]}", "controller.natural_frequency",
     "max |p| / min |Re p|"),
    ("{kind: decentralized_pid, poles: [[-4, -5, -20], [-4, -5, -1.0e+13]]}", "controller.poles[1][2]", "|p| must"),
    ("{kind: decentralized_pid, poles: [[-1.0e-6, -2.0e-6, -3.0e-6], [-4, -5, -1.0e+7]]}", "controller.poles",
     "max |p| / min |Re p|"),
])
def test_robot_controllers_check_every_pole_and_the_spread_over_the_joints(controller, key, words):
    text = f"name: r\nplant: {{kind: robot, robot: planar2r}}\ncontroller: {controller}\n"
    error = _parse(text)
    assert error is not None and error.path == key, error
    assert words in error.message


# ----------------------------------------------------------------------------- uncertainty intervals


@pytest.mark.parametrize(("plant", "key", "words"), [
    ("{kind: link, Km: 2.0, tau: 0.5, uncertainty: {tau: [0.4, 1.0e+7]}}", "plant.uncertainty.tau",
     "interval bounds must be between 1e-6 and 1e6 s (the range of plant.tau), got [0.4, 10000000.0]"),
    ("{kind: link, Km: 2.0, tau: 0.5, uncertainty: {Km: [1.0e-7, 2.0]}}", "plant.uncertainty.Km", "1e-6 and 1e6"),
    ("{kind: robot, robot: planar2r, uncertainty: {m2: [2.0, 1.0e+300]}}", "plant.uncertainty.m2",
     "between -1e6 and 1e6 (in the parameter's SI unit)"),
])
def test_uncertainty_intervals_lie_in_the_range_of_their_parameter(plant, key, words):
    controller = "{kind: decentralized_pid, poles: [-4, -5, -20]}" if "robot" in plant else \
        "{kind: pid_servo, poles: [-4, -5, -20]}"
    error = _parse(f"name: u\nplant: {plant}\ncontroller: {controller}\n")
    assert error is not None and error.path == key, error
    assert words in error.message


# ----------------------------------------------------------------------------- documentation and schema


def test_readme_table_is_generated_from_the_declarations():
    readme = (ROOT / "README.md").read_text()
    assert ranges.markdown_table() in readme


def test_json_schema_carries_the_bounds():
    schema = json.dumps(Spec.model_json_schema())
    assert '"minimum": 1e-06' in schema and '"maximum": 1000000.0' in schema
    assert '"maximum": 4294967295' in schema


def test_range_messages():
    rng = Range(1e-6, 1e6, "s")
    assert rng.problem(1e308) == "must be between 1e-6 and 1e6 s, got 1e+308"
    assert rng.problem(-1.0) == "must be positive, got -1.0"
    assert Range(0, 100, "rad").problem(-1e-9) == "must be non-negative, got -1e-09"
    assert Range(-1e12, -1e-12, "1/s").problem(3.0) == "must be negative, got 3.0"
    assert Range(1e-6, 1e3, "s", zero=True).problem(5e-324) == "must be 0 or between 1e-6 and 1e3 s, got 5e-324"
    assert Range(0, 1, low_open=True, high_open=True).problem(1.0) == "must be strictly between 0 and 1, got 1.0"
    assert Range(1, 1e12, low_open=True).problem(1.0) == "must be above 1 and at most 1e12, got 1.0"
    assert not Range(0, 1).contains(float("nan"))
    assert re.fullmatch(r"\[1e-6, 1e6\]", rng.interval())


# ----------------------------------------------------------------------------- extreme values inside the ranges


EXTREME_INSIDE = [
    # the corners of the link's ranges with the posspeed-link poles
    (LINK.replace("Km: 2.0, tau: 0.5", "Km: 1.0e-6, tau: 1.0e+6")),
    (LINK.replace("Km: 2.0, tau: 0.5", "Km: 1.0e+6, tau: 1.0e-6")),
    # the fastest and the slowest poles the ranges allow
    (LINK.replace("[-4, -5, -20]", "[-4, -5, -1.0e+12]")),
    (LINK.replace("[-4, -5, -20]", "[-1.0e-9, -5, -20]")),
    # derived poles from the widest requirements and factor
    # (without the 4 s duration: 4 s at a 1e-6 s settling time is a resource-bound refusal, tested below)
    (DERIVED.replace("overshoot: 5, settling_time: 1.5", "overshoot: 0, settling_time: 1.0e-6").replace(
        "third_pole_factor: 5", "third_pole_factor: 100, design_margin: 0.9").replace(
        "simulation: {duration: 4.0}\n", "")),
    # the saturation limit and the steady-state error requirement at the top of their ranges
    (SATURATION.replace("limit: 20", "limit: 1.0e+6").replace("steady_state_error: 0.005", "steady_state_error: 100")),
]


@pytest.mark.slow
@pytest.mark.parametrize("text", EXTREME_INSIDE, ids=range(len(EXTREME_INSIDE)))
def test_extreme_values_inside_the_ranges_are_designed_and_reported(tmp_path, capsys, text):
    spec = tmp_path / "spec.yaml"
    spec.write_text(text)
    verify = main(["verify", str(spec), "--json"])
    capsys.readouterr()
    synth = main(["synth", str(spec), "--out", str(tmp_path / "out"), "--json", "--no-studies"])
    captured = capsys.readouterr()
    assert verify in (0, 1) and synth == verify, captured.err
    payload = json.loads(captured.out)
    assert (Path(payload["report"]["html"])).read_text().count("<svg") >= 3
