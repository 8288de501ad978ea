"""Bad adaptive computed-torque specs: exit 2, one line naming the key path, nothing written."""

from __future__ import annotations

import pytest

from tests.cli_input import assert_bad_input

HEAD = "name: bad\nplant: {kind: robot, robot: planar2r}\n"
SINE = "simulation: {duration: 2, trajectory: {kind: sine, amplitude: [1.0, 1.2], frequency: 0.5}}\n"
GOOD = "adapt: [m1, m2], initial: {m1: 7.0, m2: 4.5}"


def _ctrl(body: str) -> str:
    return "controller: {kind: adaptive_computed_torque, " + body + "}\n" + SINE


CASES = {
    "K1 zero": (_ctrl(f"K1: [0, 100], K2: [20, 20], {GOOD}"), "controller.K1[0]: must be positive"),
    "K2 negative": (_ctrl(f"K1: [100, 100], K2: [20, -1], {GOOD}"), "controller.K2[1]: must be positive"),
    "psi negative": (_ctrl(f"poles: [-10, -10], psi: [-0.1, 0.1], {GOOD}"), "controller.psi[0]: must be positive"),
    "psi wrong length": (_ctrl(f"poles: [-10, -10], psi: [0.1, 0.1, 0.1], {GOOD}"), "controller.psi"),
    "K1 wrong length": (_ctrl(f"K1: [100, 100, 100], K2: [20, 20], {GOOD}"), "controller.K1"),
    "K1 without K2": (_ctrl(f"K1: [100, 100], {GOOD}"), "controller.K2: K1 and K2 go together"),
    "poles and gains": (_ctrl(f"poles: [-10, -10], K1: [100, 100], K2: [20, 20], {GOOD}"),
                        "controller: give either poles, or K1 and K2"),
    "bounds reversed": (_ctrl(f"poles: [-10, -10], {GOOD}, bounds: {{m1: [10.0, 4.0]}}"),
                        "controller.bounds.m1: l = 10 > h = 4"),
    "initial outside bounds": (_ctrl(f"poles: [-10, -10], {GOOD}, bounds: {{m2: [1.0, 4.0]}}"),
                               "controller.initial.m2: the initial estimate 4.5 is outside its bounds"),
    "unknown parameter": (_ctrl("poles: [-10, -10], adapt: [m1, m7], initial: {m1: 7.0, m7: 1.0}"),
                          "controller.adapt[1]: the robot has no parameter 'm7'"),
    "missing initial": (_ctrl("poles: [-10, -10], adapt: [m1, m2], initial: {m1: 7.0}"),
                        "controller.initial: no initial estimate of the adapted parameter 'm2'"),
    "gain zero": (_ctrl(f"poles: [-10, -10], {GOOD}, gain: [1.0, 0.0]"), "controller.gain[1]: must be positive"),
    "gain wrong length": (_ctrl(f"poles: [-10, -10], {GOOD}, gain: [1.0, 2.0, 3.0]"),
                          "controller.gain: must be one number or 2"),
    "K1 beyond its range": (_ctrl(f"K1: [100, 1.0e+13], K2: [20, 20], {GOOD}"), "controller.K1[1]: must be between"),
    "Lambda with Craig's scheme": (_ctrl(f"poles: [-10, -10], Lambda: [10, 10], {GOOD}"),
                                   "controller.Lambda: a gain of scheme: slotine_li only"),
    "K1 with Slotine-Li": (_ctrl(f"scheme: slotine_li, Lambda: [10, 10], KD: [5, 1], K1: [1, 1], {GOOD}"),
                           "controller.K1: not a gain of the Slotine-Li scheme"),
    "Slotine-Li without KD": (_ctrl(f"scheme: slotine_li, Lambda: [10, 10], {GOOD}"),
                              "controller.KD: required by the Slotine-Li scheme"),
    "acceleration with Slotine-Li": (_ctrl(f"scheme: slotine_li, Lambda: [10, 10], KD: [5, 1], acceleration: ideal, "
                                           f"{GOOD}"), "controller.acceleration: the Slotine-Li scheme needs no"),
    "KD negative": (_ctrl(f"scheme: slotine_li, Lambda: [10, 10], KD: [5, -1], {GOOD}"),
                    "controller.KD[1]: must be positive"),
    "Lambda wrong length": (_ctrl(f"scheme: slotine_li, Lambda: [10, 10, 10], KD: [5, 1], {GOOD}"),
                            "controller.Lambda"),
    "adapted twice": (_ctrl("poles: [-10, -10], adapt: [m1, m1], initial: {m1: 7.0}"),
                      "controller.adapt[1]: 'm1' is listed twice"),
    "gain matrix not symmetric": (_ctrl(f"poles: [-10, -10], {GOOD}, gain_matrix: [[2, 1], [0.5, 2]]"),
                                  "controller.gain_matrix: must be symmetric"),
    "gain matrix indefinite": (_ctrl(f"poles: [-10, -10], {GOOD}, gain_matrix: [[1, 2], [2, 1]]"),
                               "controller.gain_matrix: must be positive definite (its Cholesky factorisation "
                               "fails; smallest eigenvalue -1)"),
    "gain matrix short row": (_ctrl(f"poles: [-10, -10], {GOOD}, gain_matrix: [[1, 0], [0]]"),
                              "controller.gain_matrix[1]: must be a row of 2 numbers"),
    "gain matrix and gain": (_ctrl(f"poles: [-10, -10], {GOOD}, gain: 1.0, gain_matrix: [[1, 0], [0, 1]]"),
                             "controller.gain_matrix: give either gain (diagonal) or gain_matrix"),
    "combination singular": (_ctrl(f"poles: [-10, -10], {GOOD}, combination: [[1, 1], [2, 2]]"),
                             "controller.combination: must be invertible"),
    "combination and gain matrix": (_ctrl(f"poles: [-10, -10], {GOOD}, combination: [[1, 0], [0, 1]], "
                                          "gain_matrix: [[1, 0], [0, 1]]"),
                                    "controller.combination: takes the diagonal gain"),
    "convergence window beyond half the run": (_ctrl(f"poles: [-10, -10], {GOOD}, convergence: {{window: 1.5}}"),
                                               "controller.convergence.window: 1.5 s is longer than half the run"),
    "convergence tolerance beyond 1": (_ctrl(f"poles: [-10, -10], {GOOD}, convergence: {{tolerance: 2}}"),
                                       "controller.convergence.tolerance"),
    "convergence floor zero": (_ctrl(f"poles: [-10, -10], {GOOD}, convergence: {{floor: 0}}"),
                               "controller.convergence.floor"),
    "sine phase beyond a turn": ("controller: {kind: adaptive_computed_torque, poles: [-10, -10], " + GOOD + "}\n"
                                 "simulation: {duration: 2, trajectory: {kind: sine, phase: [0, 7]}}\n",
                                 "simulation.trajectory.phase[1]"),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_bad_input(case, tmp_path, capsys):
    text, message = CASES[case]
    assert_bad_input(tmp_path, capsys, HEAD + text, message)
