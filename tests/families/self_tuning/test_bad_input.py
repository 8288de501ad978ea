"""Bad self-tuning specs: exit 2, one line naming the key path, nothing written."""

from __future__ import annotations

import pytest

from tests.cli_input import assert_bad_input

HEAD = "name: bad\nplant: {kind: link, Km: 2.0, tau: 0.5}\n"
SQUARE = "simulation: {duration: 10, trajectory: {kind: square, amplitude: 0.5, period: 4}}\n"


def _c(extra: str = "", poles: str = "[-4, -5]") -> str:
    return f"controller: {{kind: self_tuning, sampling_period: 0.01, poles: {poles}{extra}}}\n"


CASES = {
    "lambda zero": (_c(", forgetting: 0") + SQUARE, "controller.forgetting"),
    "lambda above one": (_c(", forgetting: 1.01") + SQUARE, "controller.forgetting"),
    "lambda negative": (_c(", forgetting: -0.5") + SQUARE, "controller.forgetting"),
    "covariance zero": (_c(", initial_covariance: 0") + SQUARE, "controller.initial_covariance"),
    "covariance negative": (_c(", initial_covariance: -10") + SQUARE, "controller.initial_covariance"),
    "bound zero": (_c(", max_trace: 0") + SQUARE, "controller.max_trace"),
    "no sampling period": ("controller: {kind: self_tuning, poles: [-4, -5]}\n" + SQUARE,
                           "controller.sampling_period"),
    "run shorter than the window": (_c(", excitation_window: 12") + SQUARE,
                                    "controller.excitation_window: 12 s is longer than simulation.duration"),
    "window of too few samples": (_c(", excitation_window: 0.05") + SQUARE,
                                  "controller.excitation_window: 0.05 s spans fewer than 10 samples"),
    "trajectory too short": (_c() + "simulation: {duration: 6, trajectory: {kind: square, amplitude: 0.5, "
                             "period: 4}}\n", "simulation.duration: 6 s covers fewer than two periods"),
    "change too late": (_c() + "simulation: {duration: 10, trajectory: {kind: square, amplitude: 0.5, period: 4}, "
                        "plant_change: {time: 9, values: {Km: 1}}}\n", "simulation.plant_change.time"),
    "three poles for pole placement": (_c(poles="[-4, -5, -6]") + SQUARE,
                                       "controller.poles: must list exactly 2 poles"),
    "two poles for the pid": (_c(", design: pid") + SQUARE, "controller.poles: must list exactly 3 poles"),
    "observer with the pid": (_c(", design: pid, observer: -10", poles="[-4, -5, -6]") + SQUARE,
                              "controller.observer"),
    "unstable observer": (_c(", observer: 3") + SQUARE, "controller.observer"),
    "unknown estimator": (_c(", estimator: acceleration") + SQUARE, "controller.estimator"),
    "unstable pole": (_c(poles="[4, -5]") + SQUARE, "controller.poles[0]"),
    "conflicting simulation sampling period": (
        _c() + "simulation: {duration: 10, sampling_period: 0.02, trajectory: {kind: square, amplitude: 0.5, "
        "period: 4}}\n", "simulation.sampling_period: 0.02 s conflicts with the 0.01 s"),
    "reference it cannot follow": (_c() + "simulation: {trajectory: {kind: sine, amplitude: 0.5, frequency: 1}}\n",
                                   "simulation.trajectory.kind"),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_bad_input(case, tmp_path, capsys):
    text, message = CASES[case]
    assert_bad_input(tmp_path, capsys, HEAD + text, message)
