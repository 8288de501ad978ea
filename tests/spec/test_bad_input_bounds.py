"""Inputs inside the ranges the run cannot carry, refused before the work starts: one line, exit 2, the key path."""

from __future__ import annotations

import pytest

from tests.cli_input import assert_bad_input

LINK = ("name: b\nplant: {kind: link, Km: 2.0, tau: 0.5}\n"
        "controller: {kind: pid_servo, poles: [-4, -5, -20], zero: -3}\n")
SCARA = ("name: aw\nplant: {kind: robot, robot: scara}\ncontroller: {kind: decentralized_pid, poles: [-4, -5, -20]}\n"
         "simulation: {duration: 1.0, anti_windup: {kind: saturation, value: [1, 2, 3]}, "
         "initial_position: [0, 1.5708, 0.1, 0]}\n")


@pytest.mark.parametrize("text, message", [
    (LINK + "simulation: {delay: 1e3}\n", "simulation.delay: 1000 s is"),  # a delay line of 1e6 steps, over its bound
    (SCARA, "simulation.anti_windup.value: needs one value or one per joint (4), got 3"),
    ("name: u\nplant: {kind: robot, urdf: '" + "a" * 4090 + ".urdf'}\n"
     "controller: {kind: computed_torque, poles: [-20, -20]}\n", "plant.urdf: cannot be read"),
])
def test_bounded_before_the_work_starts(tmp_path, capsys, text, message):
    assert_bad_input(tmp_path, capsys, text, message)
