"""The test cases the shared suites run for the adaptive_computed_torque family, found by discovery: the ranged
fields of its section (tests/spec/test_ranges.py), its conformance cases (tests/problems.py) and its example specs'
exit codes (tests/test_cli.py)."""

from __future__ import annotations

BASE = """\
name: ranges-adaptive-ct
plant: {kind: robot, robot: planar2r}
controller: {kind: adaptive_computed_torque, K1: [100, 100], K2: [20, 20], psi: [0.1, 0.1], adapt: [m1, m2],
             initial: {m1: 7.0, m2: 4.5}, gain: 5.0, delta: 0.05, acceleration: filtered, bandwidth: 200}
simulation: {duration: 2.0, trajectory: {kind: sine, amplitude: [1.0, 1.2], frequency: 0.5}}
"""

SLOTINE = """\
name: ranges-adaptive-ct-slotine-li
plant: {kind: robot, robot: planar2r}
controller: {kind: adaptive_computed_torque, scheme: slotine_li, Lambda: [10, 10], KD: [5, 1], adapt: [m1, m2],
             initial: {m1: 7.0, m2: 4.5}, gain: 5.0}
simulation: {duration: 2.0, trajectory: {kind: sine, amplitude: [1.0, 1.2], frequency: 0.5}}
"""

CONVERGENCE = BASE.replace("bandwidth: 200}", "bandwidth: 200,\n             "
                                                "convergence: {window: 0.5, tolerance: 0.1, floor: 1.0e-6}}")

RANGES = {
    "controller.K1": [(BASE, "controller.K1", "controller.K1")],
    "controller.K2": [(BASE, "controller.K2", "controller.K2")],
    "controller.psi": [(BASE, "controller.psi", "controller.psi")],
    "controller.delta": [(BASE, "controller.delta", "controller.delta")],
    "controller.bandwidth": [(BASE, "controller.bandwidth", "controller.bandwidth")],
    "controller.Lambda": [(SLOTINE, "controller.Lambda", "controller.Lambda")],
    "controller.KD": [(SLOTINE, "controller.KD", "controller.KD")],
    "controller.convergence.window": [(CONVERGENCE, "controller.convergence.window",
                                       "controller.convergence.window")],
    "controller.convergence.tolerance": [(CONVERGENCE, "controller.convergence.tolerance",
                                          "controller.convergence.tolerance")],
    "controller.convergence.floor": [(CONVERGENCE, "controller.convergence.floor", "controller.convergence.floor")],
}
"""Declared key path -> [(base spec, concrete path to set, the key path the loader names)]."""

CONFORMANCE = {
    # the SIMNOG arm: both masses adapted from 40 % and 50 % heavy on an exciting sine; without the canonical
    # plant's box on m2, which moves the link's first moment and inertia the law takes as known (refused: test_box.py)
    "two_link": ("{kind: adaptive_computed_torque, poles: [-10, -10], adapt: [m1, m2], initial: {m1: 7.0, m2: 4.5}, "
                 "gain: 5.0, bounds: {m1: [4.0, 10.0], m2: [2.5, 6.0]}, delta: 0.05}",
                 "{duration: 6.0, trajectory: {kind: sine, amplitude: [1.0, 1.2], frequency: 0.5}}",
                 "{tracking_error: 0.2}", "{kind: robot, robot: planar2r}"),
    # the PUMA 560: the mass of link 2 adapted from 26 % heavy
    "puma560": ("{kind: adaptive_computed_torque, poles: [-10, -10], adapt: [m2], initial: {m2: 22.0}, gain: 100.0, "
                "bounds: {m2: [10.0, 30.0]}}",
                "{duration: 4.0, initial_position: [0, 0.785, -3.14, 0, 0.785, 0], "
                "trajectory: {kind: sine, amplitude: 0.3, frequency: 0.5}}",
                "{tracking_error: 0.2}"),
}
"""Canonical plant -> (controller, simulation, requirements) of the conformance suite (tests/problems.py)."""

EXAMPLES = {
    "adaptive-ct-simnog": 0,
    "adaptive-ct-simnog-poor": 0,  # e -> 0 is met and certified; the estimates' convergence is not promised here
    "adaptive-ct-puma560": 0,
    "adaptive-ct-not-spr": 1,  # psi K2 < 1: the SPR certificate fails (and V rises along the run)
    "adaptive-ct-simnog-slotine-li": 0,
    "adaptive-ct-two-link-slotine-li": 0,  # the book's run: the error decreasing, the estimates not converging
}
"""Example spec -> the exit code of ``designkit synth`` (tests/test_cli.py)."""
