"""The test cases the shared suites run for the mrac family, found by discovery so that adding the family edits no
shared test: the ranged fields of its section (tests/spec/test_ranges.py), its conformance cases (tests/problems.py)
and its example specs' exit codes (tests/test_cli.py)."""

from __future__ import annotations

BASE = """\
name: ranges-mrac
plant: {kind: link, Km: 2.0, tau: 0.5}
controller: {kind: mrac, reference_model: {natural_frequency: 4.5, damping: 1.0}, gamma: 10000, Q: [1, 0.1],
             nominal: {Km: 2.0, tau: 0.5}}
simulation: {duration: 4.0, trajectory: {kind: square, amplitude: 0.5, period: 4}}
"""

NORMALIZED = BASE.replace("kind: mrac,", "kind: mrac, modification: {kind: normalized, rate: 4.5},", 1)
DEAD_ZONE = BASE.replace("kind: mrac,", "kind: mrac, modification: {kind: dead_zone, width: 0.001},", 1)

FIRST_ORDER = """\
name: ranges-mrac-first-order
plant: {kind: transfer_function, num: [0.5], den: [1, 1]}
controller: {kind: mrac, reference_model: {num: [2], den: [1, 2]}, rule: normalized, normalization: 1.0, gamma: 1}
simulation: {duration: 4.0, trajectory: {kind: square, amplitude: 1, period: 4}}
"""

RANGES = {
    "controller.normalization": [(FIRST_ORDER, "controller.normalization", "controller.normalization")],
    "controller.reference_model.natural_frequency": [(BASE, "controller.reference_model.natural_frequency",
                                                      "controller.reference_model.natural_frequency")],
    "controller.reference_model.damping": [(BASE, "controller.reference_model.damping",
                                            "controller.reference_model.damping")],
    "controller.nominal.Km": [(BASE, "controller.nominal.Km", "controller.nominal.Km")],
    "controller.nominal.tau": [(BASE, "controller.nominal.tau", "controller.nominal.tau")],
    "controller.modification.rate": [(NORMALIZED, "controller.modification.rate", "controller.modification.rate")],
    "controller.modification.width": [(DEAD_ZONE, "controller.modification.width",
                                       "controller.modification.width")],
}
"""Declared key path -> [(base spec, concrete path to set, the key path the loader names)]."""

CONFORMANCE = {
    # notes §4.2, the MRAC simulator: the gradient rule recovering the reference model after Km drops 20 %
    "link": ("{kind: mrac, poles: [-4, -5], gamma: 10000, Q: [1, 0.1]}",
             "{duration: 40.0, trajectory: {kind: square, amplitude: 0.5, period: 4}, "
             "plant_change: {time: 8.0, values: {Km: 1.6}}}",
             "{max_control: 50}"),  # a square wave has no settling: the adaptive checks judge the error
    # the link as a transfer function and as a state-space model measuring 2 x1: the feedforward/feedback structure
    # (four parameters), from its ideal parameters, recovering the model after Km drops 20 %
    "transfer_function": ("{kind: mrac, reference_model: {poles: [-4, -5]}, gamma: 1}",
                          "{duration: 40.0, trajectory: {kind: square, amplitude: 0.5, period: 4}, "
                          "plant_change: {time: 8.0, values: {Km: 1.6}}}", "{max_control: 50}"),
    "state_space": ("{kind: mrac, reference_model: {poles: [-4, -5]}, gamma: 1}",
                    "{duration: 40.0, trajectory: {kind: square, amplitude: 0.5, period: 4}, "
                    "plant_change: {time: 8.0, values: {Km: 1.6}}}", "{max_control: 50}"),
}
"""Canonical plant -> (controller, simulation, requirements) of the conformance suite (tests/problems.py)."""

EXAMPLES = {
    "mrac-link": 0,
    "mrac-gamma-unstable": 1,  # the gradient rule diverges for this adaptation gain: the report gives the bound
    "mrac-mit-first-order": 0,  # Astrom and Wittenmark's Example 5.2, gamma = 1
    "mrac-mit-first-order-slow": 0,  # gamma = 0.2
    "mrac-mit-first-order-fast": 0,  # gamma = 5
}
"""Example spec -> the exit code of ``designkit synth`` (tests/test_cli.py)."""
