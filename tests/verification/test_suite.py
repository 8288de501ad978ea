"""run_checks: order, conditional groups, and independence from the simulation engine."""

from __future__ import annotations

import dataclasses
import json

import control
import numpy as np

from designkit.spec import parse_spec
from designkit.synthesis.registry import family
from designkit.verification.suite import run_checks
from tests.problems import POSSPEED_YAML, TRACKING_YAML
from tests.verification.helpers import step_result

CORE = ["pole_placement", "routh_hurwitz", "lyapunov"]
ROBUST = ["robust_vertices", "robust_grid", "common_lyapunov"]

SERVO_FULL = """\
name: servo-full
plant: {kind: link, Km: 2.0, tau: 0.5, uncertainty: {Km: [1.5, 2.5], tau: [0.4, 0.6], grid: 11}}
controller: {kind: pid_servo, poles: [-4, -5, -20], zero: -3}
requirements: {overshoot: 10, settling_time: 2.0, rise_time: 1.0, steady_state_error: 0.001, max_control: 100}
"""


def _setup(text):
    spec = parse_spec(text).spec
    fam = family(spec.controller.kind)
    return spec, fam, fam.synthesize(spec)


def _linear_sim(design, duration=5.0, n=5001):
    T = np.linspace(0.0, duration, n)
    resp = control.step_response(design.closed_loop.to_control(), T=T, input=0)
    y = np.asarray(resp.outputs).reshape(2, -1)
    return step_result(T, y[0], y[1])


def test_core_checks_only_without_uncertainty_or_simulation():
    spec, fam, design = _setup(POSSPEED_YAML)
    checks = run_checks(spec, design, fam, None)
    assert [c.name for c in checks] == CORE
    assert all(c.passed is True for c in checks), [c.detail for c in checks]


def test_tracking_core_checks_pass():
    spec, fam, design = _setup(TRACKING_YAML)
    checks = run_checks(spec, design, fam, None)
    assert [c.name for c in checks] == CORE
    assert all(c.passed is True for c in checks), [c.detail for c in checks]


def test_full_order_and_json():
    spec, fam, design = _setup(SERVO_FULL)
    checks = run_checks(spec, design, fam, _linear_sim(design))
    assert [c.name for c in checks] == CORE + ROBUST + [
        "overshoot", "settling_time", "rise_time", "steady_state_error", "max_control",
    ]
    assert all(c.passed is True for c in checks), [(c.name, c.detail) for c in checks if not c.passed]
    json.dumps([c.to_dict() for c in checks])  # certificates are JSON-serialisable


def test_requirements_without_simulation_give_no_time_domain_checks():
    spec, fam, design = _setup(SERVO_FULL)
    assert [c.name for c in run_checks(spec, design, fam, None)] == CORE + ROBUST


def test_time_domain_checks_use_only_the_result_fields():
    """Engine-specific fields (controller state, measurements, settings) do not change any verdict."""
    spec, fam, design = _setup(SERVO_FULL)
    sim = _linear_sim(design)
    other = dataclasses.replace(
        sim, controller_state=np.full((len(sim.time), 4), np.nan), measured=np.zeros_like(sim.measured),
        settings={"integrator": "something else"},
    )
    a = [c.to_dict() for c in run_checks(spec, design, fam, sim)]
    b = [c.to_dict() for c in run_checks(spec, design, fam, other)]
    assert a == b


def test_a_design_with_wrong_gains_fails_the_core_checks():
    spec, fam, design = _setup(POSSPEED_YAML)
    gains = {**design.gains, "K1": 1.0}  # violates K1 > tau K3/(1 + Km K2)
    bad = dataclasses.replace(design, gains=gains, closed_loop=fam.closed_loop(dataclasses.replace(design, gains=gains),
                                                                              design.plant))
    checks = {c.name: c for c in run_checks(spec, bad, fam, None)}
    assert checks["pole_placement"].passed is False
    assert checks["routh_hurwitz"].passed is False
    assert checks["lyapunov"].passed is False
