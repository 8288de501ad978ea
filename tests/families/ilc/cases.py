"""The test cases the shared suites run for the ilc family, found by discovery so that adding the family edits no
shared test: the ranged fields of its section (tests/spec/test_ranges.py), its conformance cases (tests/problems.py)
and its example specs' exit codes (tests/test_cli.py)."""

from __future__ import annotations

BASE = """\
name: ranges-ilc
plant: {kind: robot, robot: planar2r}
controller: {kind: ilc, poles: [-20, -20], trials: 3, learning: {kind: adjoint, alpha: 1000.0}}
simulation: {duration: 1.0, trajectory: {kind: quintic, amplitude: [0.2, -0.1], duration: 0.8}}
"""
P_TYPE = BASE.replace("{kind: adjoint, alpha: 1000.0}", "{kind: p_type, gain: 100.0}")
LINEAR = """\
name: ranges-ilc-linear
plant: {kind: state_space, dt: 1.0, A: [[-0.8, -0.22], [1, 0]], B: [[0.5], [1]], C: [[1, 0.5]]}
controller: {kind: ilc, trials: 3, learning: {kind: filter, num: [0.5, 0.1], den: [1.0, 0.2]}}
simulation: {duration: 50, trajectory: {kind: sine, amplitude: 1.0, frequency: 0.02}}
"""

RANGES = {
    "controller.trials": [(BASE, "controller.trials", "controller.trials")],
    "controller.learning.alpha": [(BASE, "controller.learning.alpha", "controller.learning.alpha")],
    "controller.learning.gain": [(P_TYPE, "controller.learning.gain", "controller.learning.gain")],
    "plant.dt": [(LINEAR, "plant.dt", "plant.dt")],  # only the learning family runs a discrete-time plant
    "controller.learning.num[]": [(LINEAR, "controller.learning.num.1", "controller.learning.num[1]")],
    "controller.learning.den[]": [(LINEAR, "controller.learning.den.1", "controller.learning.den[1]")],
}
"""Declared key path -> [(base spec, concrete path to set, the key path the loader names)]."""

CONFORMANCE = {
    # notes §6: computed torque learning the repeatable error a 33 % light model of m2 leaves
    "two_link": ("{kind: ilc, poles: [-20, -20], model: {parameters: {m2: 2.0}}, trials: 20}",
                 "{duration: 2.0, dt: 0.005, trajectory: {kind: quintic, amplitude: [1.0, -0.5], duration: 1.0}}",
                 "{tracking_error: 0.01}"),
    "puma560": ("{kind: ilc, damping: 1.0, natural_frequency: 10, trials: 5}",
                "{duration: 1.5, dt: 0.01, initial_position: [0, 0.785, -3.14, 0, 0.785, 0], "
                "perturbation: {value: [2.0, 2.0, 1.0, 0, 0, 0]}, "
                "trajectory: {kind: quintic, amplitude: 0.2, duration: 1.0}}",
                "{tracking_error: 0.02}"),
}
"""Canonical plant -> (controller, simulation, requirements) of the conformance suite (tests/problems.py).  The
trials are sampled at 5 and 10 ms: at 1 ms the adjoint's contraction, ``1 - sigma_min(H)^2/sigma_max(H)^2``, lies
within 1e-9 of 1 (about 1 - 1e-13) and is undecided; at these steps its margin is 7e-9 and 8e-9."""

EXAMPLES = {
    "ilc-simnog": 1,  # rho = 1 - 4.5e-13 < 1, within 1e-9 of the boundary: ilc_convergence UNDECIDED
    "ilc-moore-monotone": 0,
    "ilc-moore-asymptotic": 1,  # spectral radius 0.5 but ||I - 1.5 H||_2 = 1.149 > 1: the error norm grows for trials
    "ilc-simnog-diverging": 1,  # rho = ||I - QH|| = 1.47 > 1: the error norm grows trial after trial
}
"""Example spec -> the exit code of ``designkit synth`` (tests/test_cli.py)."""
