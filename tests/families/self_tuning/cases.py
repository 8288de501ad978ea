"""The test cases the shared suites run for the self_tuning family, found by discovery so that adding the family edits
no shared test: the ranged fields of its section (tests/spec/test_ranges.py), its conformance cases (tests/problems.py)
and its example specs' exit codes (tests/test_cli.py)."""

from __future__ import annotations

BASE = """\
name: ranges-self-tuning
plant: {kind: link, Km: 2.0, tau: 0.5}
controller: {kind: self_tuning, sampling_period: 0.00001, forgetting: 0.99, initial_covariance: 100, max_trace: 300,
             poles: [-4, -5], observer: -10, excitation_window: 1000000, nominal: {Km: 1.0, tau: 1.0}}
simulation: {duration: 1000000, trajectory: {kind: square, amplitude: 0.5, period: 4}}
"""
# sampling_period 1e-5 s makes the smallest excitation window (1e-4 s) ten samples; the window of 1e6 s holds ten
# samples of the longest period (10 s); the duration covers the longest window

RANGES = {
    f"controller.{key}": [(BASE, f"controller.{key}", f"controller.{key}")]
    for key in ("sampling_period", "forgetting", "initial_covariance", "max_trace", "observer", "excitation_window",
                "nominal.Km", "nominal.tau")
}
ARX = """\
name: ranges-self-tuning-arx
plant: {kind: transfer_function, num: [1], den: [1, 1, 0]}
controller: {kind: self_tuning, sampling_period: 0.5, poles: [-1, -1.2], observer: {polynomial: [1, 0]},
             initial_estimates: [0, 0, 0.01, 0.2]}
simulation: {duration: 100, trajectory: {kind: square, amplitude: 1, period: 50}}
"""
RANGES["controller.initial_estimates[]"] = [(ARX, "controller.initial_estimates.1", "controller.initial_estimates[1]")]
RANGES["controller.observer.polynomial[]"] = [(ARX, "controller.observer.polynomial.1",
                                               "controller.observer.polynomial[1]")]
"""Declared key path -> [(base spec, concrete path to set, the key path the loader names)]."""

CONFORMANCE = {
    # notes §4.3, SELFTUNE with a speed measurement: RLS re-converging after the link changes, pole placement
    "link": ("{kind: self_tuning, sampling_period: 0.01, forgetting: 0.99, initial_covariance: 100, poles: [-4, -5], "
             "nominal: {Km: 1.0, tau: 1.0}}",
             "{duration: 24.0, trajectory: {kind: square, amplitude: 0.5, period: 4}, "
             "plant_change: {time: 10.0, values: {Km: 1.6}}}",
             "{max_control: 50}"),
    # the same link as a transfer function and as a state-space model: the ARX form (na = nb = 2, d = 1), its
    # default observer pole, the initial estimates the exact ARX of the spec's plant
    **{kind: ("{kind: self_tuning, sampling_period: 0.05, forgetting: 0.98, initial_covariance: 100, "
              "poles: [-4, -5]}",
              "{duration: 24.0, trajectory: {kind: square, amplitude: 0.5, period: 4}, "
              "plant_change: {time: 10.0, values: {Km: 1.6}}}",
              "{max_control: 50}") for kind in ("transfer_function", "state_space")},
}
"""Canonical plant -> (controller, simulation, requirements) of the conformance suite (tests/problems.py)."""

EXAMPLES = {
    "selftune-speed": 0,
    "selftune-position": 0,
    "selftune-no-forgetting": 1,  # lambda = 1: the estimates stay between the links before and after the change
    "selftune-aw-indirect": 0,
}
"""Example spec -> the exit code of ``designkit synth`` (tests/test_cli.py)."""
