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
"""Declared key path -> [(base spec, concrete path to set, the key path the loader names)]."""

CONFORMANCE = {
    # notes §5.5: a and b of the link identified while a PD servo follows a square wave
    "link": ("{kind: sliding_mode_identification, initial_estimates: [1.0, 1.0], error_bounds: {a: 3.0, b: 5.0}}",
             "{duration: 10.0, trajectory: {kind: square, amplitude: 0.5, period: 2}}",
             "{max_control: 50}"),
}
"""Canonical plant -> (controller, simulation, requirements) of the conformance suite (tests/problems.py)."""

EXAMPLES = {
    "smid-link": 0,
    "smid-link-parameter-step": 0,
    "smid-link-single-step": 1,  # one step and nothing after it: the determinant vanishes, no convergence
}
"""Example spec -> the exit code of ``designkit synth`` (tests/test_cli.py)."""
