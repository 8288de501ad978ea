"""The test cases the shared suites run for the pid_sliding_mode family, found by discovery so that adding the family
edits no shared test: its ranged fields (tests/spec/test_ranges.py), its conformance case (tests/problems.py) and its
example specs' exit codes (tests/test_cli.py)."""

from __future__ import annotations

BASE = """\
name: ranges-pid-sm
plant: {kind: link, Km: 2.0, tau: 0.5, uncertainty: {Km: [1.6, 2.4], tau: [0.4, 0.6]}}
controller: {kind: pid_sliding_mode, poles: [-4, -5, -20], perturbation_bound: 0.5, margin: 0.2, M: 4.0,
             switching_band: 0.0002}
simulation: {duration: 0.5}
"""
LAYER = BASE.replace("switching_band: 0.0002", "epsilon: 0.002")

RANGES = {f"controller.{k}": [(BASE, f"controller.{k}", f"controller.{k}")]
          for k in ("perturbation_bound", "margin", "M", "switching_band")}
RANGES["controller.epsilon"] = [(LAYER, "controller.epsilon", "controller.epsilon")]
ROBOT = """\
name: ranges-pid-sm-robot
plant: {kind: robot, robot: planar2r, limits: {velocity: 2.0, acceleration: 12.0}}
controller: {kind: pid_sliding_mode, poles: [-4, -5, -20], workspace: {low: [-0.2, -0.8], high: [0.8, 0.3]},
             epsilon: 0.002, work_limit: 300}
simulation: {duration: 0.5}
"""
RANGES["controller.work_limit"] = [(ROBOT, "controller.work_limit", "controller.work_limit")]
"""Declared key path -> [(base spec, concrete path to set, the key path the loader names)]."""

CONFORMANCE = {
    # notes §5.3: the PID/sliding-mode servo on the link box, against a 0.5 N*m input perturbation from t = 1 s
    "link": ("{kind: pid_sliding_mode, poles: [-4, -5, -20], perturbation_bound: 0.5}",
             "{duration: 3.0, perturbation: {value: 0.5, time: 1.0}}",
             "{overshoot: 2, settling_time: 1.5, steady_state_error: 0.005}"),
    # ROBEL's elastic joint (families/pid_sliding_mode/elastic.py): the sliding variable on the motor
    "elastic_joint": ("{kind: pid_sliding_mode, poles: [-3, -4, -12]}", "{duration: 3.0}",
                      "{overshoot: 15, settling_time: 2.5, steady_state_error: 0.01}"),
    # the hierarchy of control (robot.py) needs velocity and acceleration limits, which the canonical arms do not
    # carry, so the robots' cases carry their own plant (the canonical arm with limits, as specs/hierarchy-*.yaml)
    "two_link": ("{kind: pid_sliding_mode, poles: [-4, -5, -20], workspace: {low: [-0.2, -0.8], high: [0.8, 0.3]},"
                 " epsilon: 0.002}",
                 "{duration: 2.0, step: [0.5, -0.3]}", None,
                 "{kind: robot, robot: planar2r, limits: {velocity: [2.0, 2.0], acceleration: [12.0, 12.0]}}"),
    "puma560": ("{kind: pid_sliding_mode, poles: [-4, -5, -20], epsilon: 0.005, workspace: "
                "{low: [-0.3, 0.485, -3.4416, -0.3, 0.485, -0.3], high: [0.6, 1.285, -2.8416, 0.6, 1.285, 0.6]}}",
                "{duration: 1.5, initial_position: [0, 0.785, -3.1416, 0, 0.785, 0], "
                "step: [0.3, 0.3, 0.2, 0.3, 0.3, 0.3]}",
                None, "{kind: robot, robot: puma560, motor_inertia: true, limits: {velocity: 1.0, acceleration: 8.0}}"),
}
"""Canonical plant -> (controller, simulation, requirements[, plant]) of the conformance suite (tests/problems.py)."""

EXAMPLES = {
    "pid-sm-link": 0,
    "pid-sm-link-boundary-layer": 0,
    "pid-sm-link-parameter-step": 0,
    "pid-sm-link-weak-relay": 1,  # M below the section 5.4 bound: the certificate says by how much
    "hierarchy-simnog": 0,  # the hierarchy of control on the SIMNOG arm (robot.py)
    "hierarchy-puma560": 0,  # ... on the PUMA 560, six joints
    "hierarchy-simnog-small-M": 1,  # M below the proven sup|xi_i|: the certificate says by how much
    "hierarchy-simnog-payload": 0,  # ... over a box of link 2's mass, the load picked up during the run
    "hierarchy-puma560-payload": 0,  # ... the PUMA 560 with up to its rated 2.5 kg payload
}
"""Example spec -> the exit code of ``designkit synth`` (tests/test_cli.py)."""
