"""The test cases the shared suites run for the sliding-mode identification family (found by discovery): the
ranged fields of its section (tests/spec/test_ranges.py), its conformance case (tests/problems.py) and its example
specs' exit codes (tests/test_cli.py)."""

from __future__ import annotations

BASE = """\
name: ranges-smid
plant: {kind: link, Km: 2.0, tau: 0.5}
controller: {kind: sliding_mode_identification, initial_estimates: [1.0, 1.0], error_bounds: {a: 3.0, b: 5.0},
             servo: {K1: 5.0, K2: 0.5}, c: 9.0, d: 9.0, window: 0.25, sampling_period: 0.002}
simulation: {duration: 2.0, trajectory: {kind: square, amplitude: 0.5, period: 2}}
"""

RANGES = {
    path: [(BASE, path, path)] for path in (
        "controller.servo.K1", "controller.servo.K2", "controller.error_bounds.a", "controller.error_bounds.b",
        "controller.c", "controller.d", "controller.window", "controller.sampling_period")
}
_GAINS = BASE.replace("window: 0.25,", "window: 0.25, adaptation_gains: [1.0, 1.0],")
RANGES["controller.adaptation_gains[]"] = [(_GAINS, "controller.adaptation_gains.1", "controller.adaptation_gains[1]")]
ROBOT = """\
name: ranges-smid-robot
plant: {kind: robot, robot: planar2r}
controller: {kind: sliding_mode_identification, servo: {K1: [200, 60], K2: [30, 8]}, switching_gain: [20, 60],
             adaptation_gains: {mcx1R: 0.04, Izz1R: 0.07}, identify: [mcx1R, Izz1R], window: 0.1}
simulation: {duration: 2.0, trajectory: {kind: multisine, amplitude: [1.0, 1.2], period: 5, harmonics: 3}}
"""
RANGES["controller.switching_gain"] = [(ROBOT, "controller.switching_gain", "controller.switching_gain")]
RANGES["controller.adaptation_gains.<name>"] = [(ROBOT, "controller.adaptation_gains.Izz1R",
                                                 "controller.adaptation_gains.Izz1R")]
RANGES["simulation.trajectory.harmonics"] = [(ROBOT, "simulation.trajectory.harmonics",
                                              "simulation.trajectory.harmonics")]
"""Declared key path -> [(base spec, concrete path to set, the key path the loader names)]."""

CONFORMANCE = {
    # notes §5.5: a and b of the link identified while a PD servo follows a square wave
    "link": ("{kind: sliding_mode_identification, initial_estimates: [1.0, 1.0], error_bounds: {a: 3.0, b: 5.0}}",
             "{duration: 10.0, trajectory: {kind: square, amplitude: 0.5, period: 2}}",
             "{max_control: 50}"),
    # the generalisation to a robot: four of the SIMNOG arm's base parameters along a multisine (the others known);
    # without the canonical plant's box on m2, which moves base parameters the law takes as known (its run at the
    # box's corners fails the identification, as it should)
    "two_link": ("{kind: sliding_mode_identification, servo: {K1: [200, 60], K2: [30, 8]}, switching_gain: [40, 120], "
                 "identify: [Izz1R, Izz2R, fv1, fv2], window: 0.1}",
                 "{duration: 6.0, initial_position: [0.3, 0.4], "
                 "trajectory: {kind: multisine, amplitude: [1.0, 1.2], period: 5, harmonics: 3}}",
                 "{max_control: 500}", "{kind: robot, robot: planar2r}"),
    # the PUMA 560 without friction (its Coulomb frictions of up to 26 N*m reverse inside a sample, a residual the
    # sampled reconstruction cannot follow; its wrist frictions are stiffer than the 2 ms sample): a PD per joint
    # tuned to each joint's inertia (10 rad/s, damping 1), three base parameters from 80 % of their values
    "puma560": ("{kind: sliding_mode_identification, servo: {K1: [290, 210, 36, 0.17, 0.064, 0.004], "
                "K2: [58, 42, 7.2, 0.035, 0.013, 0.0008]}, switching_gain: 2000, identify: [Iyy1R, mcx2R, mcz3R], "
                "initial_estimates: {Iyy1R: 0.16, mcx2R: 3.0, mcz3R: 0.7}, window: 0.05}",
                "{duration: 3.0, initial_position: [0, 0.785, -3.14, 0, 0.785, 0], "
                "trajectory: {kind: multisine, amplitude: 0.3, period: 2, harmonics: 2}}",
                "{max_control: 1000}", "{kind: robot, robot: puma560, friction: false}"),
}
"""Canonical plant -> (controller, simulation, requirements) of the conformance suite (tests/problems.py)."""

EXAMPLES = {
    "smid-link": 0,
    "smid-link-parameter-step": 0,
    "smid-link-single-step": 1,  # one step and nothing after it: the determinant vanishes, no convergence
    "smid-simnog": 0,
    "smid-simnog-single-step": 1,  # at rest after one step: no window excites every direction
}
"""Example spec -> the exit code of ``designkit synth`` (tests/test_cli.py)."""
