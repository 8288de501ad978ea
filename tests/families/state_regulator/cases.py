"""The test cases the shared suites run for the state_regulator family (found by discovery): its conformance cases
(tests/problems.py) and its example specs' exit codes (tests/test_cli.py)."""

from __future__ import annotations

CONFORMANCE = {
    # ROBEL figure 5.2 on the default elastic joint: four poles placed, no load
    "elastic_joint": ("{kind: state_regulator, poles: [-8, -10, -12, -15]}", "{duration: 2.0}",
                      "{overshoot: 15, settling_time: 1.5, steady_state_error: 0.01}"),
    # the link (position, speed): two real poles, on the canonical Km and tau box
    "link": ("{kind: state_regulator, poles: [-6, -8]}", "{duration: 2.0}",
             "{overshoot: 5, settling_time: 1.5, steady_state_error: 0.01}"),
    # the link written as a transfer function and as a state-space model whose output is 2 x1
    "transfer_function": ("{kind: state_regulator, poles: [-6, -8]}", "{duration: 2.0}",
                          "{overshoot: 5, settling_time: 1.5, steady_state_error: 0.01}"),
    "state_space": ("{kind: state_regulator, poles: [-6, -8]}", "{duration: 2.0}",
                    "{overshoot: 5, settling_time: 1.5, steady_state_error: 0.01}"),
}
"""Canonical plant -> (controller, simulation, requirements) of the conformance suite (tests/problems.py)."""

EXAMPLES = {
    "state-regulator-elastic-joint": 0,
    "state-space-third-order": 0,  # an identified drive with a gearbox resonance, three states measured
}
"""Example spec -> the exit code of ``designkit synth`` (tests/test_cli.py)."""
