"""Bad MRAC specs: exit 2, one line naming the key path, nothing written."""

from __future__ import annotations

import pytest

from tests.cli_input import assert_bad_input

HEAD = "name: bad\nplant: {kind: link, Km: 2.0, tau: 0.5}\n"
SQUARE = "simulation: {duration: 10, trajectory: {kind: square, amplitude: 0.5, period: 4}}\n"
CASES = {
    "gamma zero": ("controller: {kind: mrac, poles: [-4, -5], gamma: 0}\n" + SQUARE,
                   "controller.gamma: must be positive"),
    "gamma negative entry": ("controller: {kind: mrac, poles: [-4, -5], gamma: [1, -2]}\n" + SQUARE,
                             "controller.gamma[1]: must be positive"),
    "Q indefinite": ("controller: {kind: mrac, poles: [-4, -5], gamma: 1, Q: [[1, 2], [2, 1]]}\n" + SQUARE,
                     "controller.Q: must be positive definite"),
    "Q semidefinite": ("controller: {kind: mrac, poles: [-4, -5], gamma: 1, Q: [1, 0]}\n" + SQUARE,
                       "controller.Q: must be positive definite"),
    "Q not symmetric": ("controller: {kind: mrac, poles: [-4, -5], gamma: 1, Q: [[1, 0.5], [0, 1]]}\n" + SQUARE,
                        "controller.Q: must be symmetric"),
    "unstable model (damping)": ("controller: {kind: mrac, gamma: 1, reference_model: {natural_frequency: 4, "
                                 "damping: -0.1}}\n" + SQUARE, "controller.reference_model.damping: must be positive"),
    "unstable model (pole)": ("controller: {kind: mrac, gamma: 1, reference_model: {poles: [2, -5]}}\n" + SQUARE,
                              "controller.reference_model.poles[0]: must have negative real part"),
    "wrong order model": ("controller: {kind: mrac, gamma: 1, reference_model: {poles: [-2, -5, -9]}}\n" + SQUARE,
                          "controller.reference_model.poles: must list exactly 2 poles"),
    "wrong order loop": ("controller: {kind: mrac, poles: [-4, -5, -20], gamma: 1}\n" + SQUARE,
                         "controller.poles: must list exactly 2 poles"),
    "reference it cannot follow": ("controller: {kind: mrac, poles: [-4, -5], gamma: 1}\nsimulation: {trajectory: "
                                   "{kind: sine, amplitude: 0.5, frequency: 1}}\n", "simulation.trajectory.kind"),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_bad_input(case, tmp_path, capsys):
    text, message = CASES[case]
    assert_bad_input(tmp_path, capsys, HEAD + text, message)
