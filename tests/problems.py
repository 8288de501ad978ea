"""Canonical problems with known answers, shared by the tests of every layer."""

from __future__ import annotations

POSSPEED_YAML = """\
name: posspeed-link
plant: {kind: link, Km: 2.0, tau: 0.5}
controller: {kind: pid_servo, poles: [-4, -5, -20], zero: -3}
"""
# Hand-derived answer: S1 = -29, S2 = 200, S3 = -400 (1/s, 1/s^2, 1/s^3), Km = 2, tau = 0.5:
# K1 = tau S2 / Km = 50, K2 = -(tau S1 + 1)/Km = 6.75, K3 = -tau S3 / Km = 100,
# K4 = -(K3 + K1 z)/(K3 z) = -(100 - 150)/(-300) = -1/6.
POSSPEED_GAINS = {"K1": 50.0, "K2": 6.75, "K3": 100.0, "K4": -1.0 / 6.0}

TRACKING_YAML = """\
name: tracking
plant: {kind: link, Km: 2.0, tau: 0.5}
controller: {kind: pid_tracking, poles: [-10, -12, -15]}
"""
# S1 = -37, S2 = 120 + 150 + 180 = 450, S3 = -1800: K1 = 112.5, K2 = 9.25, K3 = 450.
TRACKING_GAINS = {"K1": 112.5, "K2": 9.25, "K3": 450.0}

COMPLEX_YAML = """\
name: complex-poles
plant: {kind: link, Km: 1.3, tau: 0.8}
controller: {kind: pid_servo, poles: ['-3+4j', '-3-4j', -12], zero: -2}
"""

# ----------------------------------------------------------------------------- canonical problems

PLANTS = {
    "link": "{kind: link, Km: 2.0, tau: 0.5, uncertainty: {Km: [1.6, 2.4], tau: [0.4, 0.6], grid: 5}}",
    "two_link": "{kind: robot, robot: planar2r, uncertainty: {m2: [2.5, 3.5], grid: 3}}",
    "puma560": "{kind: robot, robot: puma560}",
    "elastic_joint": "{kind: elastic_joint}",
    # the link Km/(s (tau s + 1)) as a transfer function and as a state-space model measuring 2 x1 (the realisation
    # then makes y = 2 x1 a state), both with named parameters in their entries
    "transfer_function": "{kind: transfer_function, num: [Km], den: [tau, 1, 0], parameters: {Km: 2.0, tau: 0.5}, "
                         "uncertainty: {Km: [1.6, 2.4], tau: [0.4, 0.6], grid: 5}}",
    "state_space": "{kind: state_space, A: [[0, 1], [0, '-1/tau']], B: [[0], ['Km/tau']], C: [[2, 0]], "
                   "parameters: {Km: 2.0, tau: 0.5}, uncertainty: {Km: [1.6, 2.4], tau: [0.4, 0.6], grid: 5}}",
}
"""The canonical plants every layer's tests reuse (the SIMNOG arm is designkit's planar2r)."""

CASES = {
    "pid_servo": {
        "link": ("{kind: pid_servo, poles: [-4, -5, -20], zero: -3}", "{duration: 3.0}"),
        # the link-position PID from the rigid approximation (specs/robel.yaml's controller (i))
        "elastic_joint": ("{kind: pid_servo, poles: [-4, -5, -6], zero: -5.5}", "{duration: 4.0}"),
        "transfer_function": ("{kind: pid_servo, poles: [-4, -5, -20], zero: -3}", "{duration: 3.0}"),
        "state_space": ("{kind: pid_servo, poles: [-4, -5, -20], zero: -3}", "{duration: 3.0}"),
    },
    "pid_tracking": {
        "link": ("{kind: pid_tracking, poles: [-10, -12, -15]}",
                 "{duration: 2.0, trajectory: {kind: quintic, amplitude: 1.0, duration: 1.0}}"),
        "transfer_function": ("{kind: pid_tracking, poles: [-10, -12, -15]}",
                              "{duration: 2.0, trajectory: {kind: quintic, amplitude: 1.0, duration: 1.0}}"),
        "state_space": ("{kind: pid_tracking, poles: [-10, -12, -15]}",
                        "{duration: 2.0, trajectory: {kind: quintic, amplitude: 1.0, duration: 1.0}}"),
    },
    "computed_torque": {
        # the nominal model against the true m2 anywhere in [2.5, 3.5] kg: the corners track to 0.06 rad
        "two_link": ("{kind: computed_torque, poles: [-10, -10]}",
                     "{duration: 2.0, trajectory: {kind: quintic, amplitude: [1.0, -0.5], duration: 1.0}}",
                     "{tracking_error: 0.1}"),
        "puma560": ("{kind: computed_torque, damping: 1.0, natural_frequency: 10}",
                    "{duration: 1.5, initial_position: [0, 0.785, -3.14, 0, 0.785, 0], "
                    "trajectory: {kind: quintic, amplitude: 0.2, duration: 1.0}}",
                    "{tracking_error: 1.0e-6}"),
    },
    "resolved_acceleration": {
        "two_link": ("{kind: resolved_acceleration, poles: [-10, -10]}",
                     "{duration: 1.5, initial_position: [0.3, 1.2], "
                     "trajectory: {kind: line, displacement: [-0.3, 0.1, 0.0], duration: 1.0}}",
                     "{tracking_error: 0.1}"),
        "puma560": ("{kind: resolved_acceleration, damping: 1.0, natural_frequency: 10, orientation: held}",
                    "{duration: 1.5, initial_position: [0, 0.785, -3.14, 0.5, 0.3, 0.2], "
                    "trajectory: {kind: line, displacement: [0.0, 0.0, 0.1], duration: 1.0}}",
                    "{tracking_error: 1.0e-6}"),
    },
    "decentralized_pid": {
        "two_link": ("{kind: decentralized_pid, poles: [-4, -5, -20], zero: -3}",
                     "{duration: 3.0, step: [1.0, -0.5]}"),
        # the PUMA's Coulomb friction (up to 25 N*m at the joints) makes the wrist creep to its target long
        # after the linear modes have decayed: only a loose steady-state bound is asked of it here
        "puma560": ("{kind: decentralized_pid, poles: [-4, -5, -20], zero: -3}",
                    "{duration: 3.0, step: 0.1, initial_position: [0, 0.785, -3.14, 0, 0.785, 0]}",
                    "{steady_state_error: 0.1}"),
    },
}
"""Family -> canonical plant -> (controller section, simulation section[, requirements]): the conformance suite
runs each.  A family whose tests declare ``CONFORMANCE`` in ``tests/families/<kind>/cases.py`` adds its cases there
(:func:`discovered`), so adding a family edits no shared test."""


def discovered(name: str) -> dict:
    """``{kind: cases.<name>}`` of every family test package that declares it."""
    from importlib import import_module
    from pathlib import Path

    out = {}
    for path in sorted((Path(__file__).resolve().parent / "families").glob("*/cases.py")):
        value = getattr(import_module(f"tests.families.{path.parent.name}.cases"), name, None)
        if value is not None:
            out[path.parent.name] = value
    return out


CASES.update(discovered("CONFORMANCE"))

REQUIREMENTS = "{overshoot: 50, settling_time: 10.0, steady_state_error: 0.05}"


def for_family(kind: str, plant_text: str) -> str:
    """A canonical plant's flow mapping without the settings of its parameter box the family does not use (a spec
    giving them is refused: ``Family.uses``)."""
    import re

    from designkit.families import FAMILIES

    uses = FAMILIES[kind].uses
    if "plant.uncertainty" not in uses:
        return re.sub(r", uncertainty: \{[^}]*\}", "", plant_text)
    if "plant.uncertainty.grid" not in uses:
        return re.sub(r", grid: \d+", "", plant_text)
    return plant_text


def case_yaml(kind: str, plant: str) -> str:
    """The spec of one conformance case.

    A case is ``(controller, simulation[, requirements[, plant]])``; the optional ``plant`` replaces the canonical
    plant's flow mapping when the family needs what the canonical one leaves out (the hierarchy of control needs
    velocity and acceleration limits and takes no parameter box).
    """
    controller, simulation, *rest = CASES[kind][plant]
    requirements = rest[0] if rest and rest[0] is not None else REQUIREMENTS
    plant_text = rest[1] if len(rest) > 1 else for_family(kind, PLANTS[plant])
    return (f"name: conformance-{kind}-{plant}\nplant: {plant_text}\ncontroller: {controller}\n"
            f"requirements: {requirements}\nsimulation: {simulation}\n")
