"""The test cases the shared suites run for the sliding_mode family, found by discovery so that adding the family edits
no shared test: the ranged fields of its section (tests/spec/test_ranges.py), its conformance cases
(tests/problems.py) and its example specs' exit codes (tests/test_cli.py)."""

from __future__ import annotations

BASE = """\
name: ranges-sliding
plant: {kind: link, Km: 2.0, tau: 0.5, uncertainty: {Km: [1.4, 2.6], tau: [0.35, 0.65]}}
controller: {kind: sliding_mode, sliding_poles: [-5], perturbation_bound: 1.0, margin: 0.2, chattering_band: 0.005,
             reaching_frequency: 2.0, alpha: 1.0, beta: -10.0, M: 1.5}
simulation: {duration: 2.0}
"""
LAYER = BASE.replace("chattering_band: 0.005", "boundary_layer: 0.05")

RANGES = {f"controller.{k}": [(BASE, f"controller.{k}", f"controller.{k}")]
         for k in ("perturbation_bound", "margin", "chattering_band", "reaching_frequency", "alpha", "beta", "M")}
RANGES["controller.boundary_layer"] = [(LAYER, "controller.boundary_layer", "controller.boundary_layer")]
"""Declared key path -> [(base spec, concrete path to set, the key path the loader names)]."""

CONFORMANCE = {
    # notes §5.1: the switching law on the link box, against a 0.5 N*m input perturbation from t = 1 s
    "link": ("{kind: sliding_mode, sliding_poles: [-5], perturbation_bound: 0.5}",
             "{duration: 3.0, perturbation: {value: 0.5, time: 1.0}}",
             "{overshoot: 2, settling_time: 1.5, steady_state_error: 0.005}"),
    # the link as a transfer function and as a state-space model: the surface, the nominal equivalent control and
    # the switching gain from the box's proven model error (the minimal relay reaches s = 0 in about 0.9 s here)
    "transfer_function": ("{kind: sliding_mode, sliding_poles: [-5], perturbation_bound: 0.5}",
                          "{duration: 3.0, perturbation: {value: 0.5, time: 1.0}}",
                          "{overshoot: 2, settling_time: 2.0, steady_state_error: 0.005}"),
    "state_space": ("{kind: sliding_mode, sliding_poles: [-5], perturbation_bound: 0.5}",
                    "{duration: 3.0, perturbation: {value: 0.5, time: 1.0}}",
                    "{overshoot: 2, settling_time: 2.0, steady_state_error: 0.005}"),
}
"""Canonical plant -> (controller, simulation, requirements) of the conformance suite (tests/problems.py)."""

EXAMPLES = {
    "sliding-mode-link": 0,
    "sliding-mode-weak-switching": 1,  # M below the perturbation: the certificate names the M that would do
    "sliding-mode-link-implemented": 0,  # sampled at 1 kHz, 0.1 ms delay, a +-5 N*m actuator with a 300 rad/s lag
    "sliding-mode-third-order-drive": 0,  # a state_space plant: the surface from two sliding poles, gains from the box
}
"""Example spec -> the exit code of ``designkit synth`` (tests/test_cli.py)."""
