"""run_checks: checks chosen by what a design exposes, their order, and independence from the simulation engine."""

from __future__ import annotations

import dataclasses
import json

import control
import numpy as np

from designkit.families import check_rules, family, pid_servo, synthesize
from designkit.schema.loader import parse_spec
from designkit.synthesis.closed_loop import with_closed_loop
from designkit.verification.suite import GENERIC, applicable
from designkit.verification.suite import run_checks as run_rules
from tests.problems import POSSPEED_YAML, TRACKING_YAML
from tests.verification.helpers import step_result

CORE = ["pole_placement", "routh_hurwitz", "lyapunov"]
ROBUST = ["robust_box", "robust_vertices", "robust_grid", "common_lyapunov"]
MARGINS = ["loop_margins"]

SERVO_FULL = """\
name: servo-full
plant: {kind: link, Km: 2.0, tau: 0.5, uncertainty: {Km: [1.5, 2.5], tau: [0.4, 0.6], grid: 11}}
controller: {kind: pid_servo, poles: [-4, -5, -20], zero: -3}
requirements: {overshoot: 10, settling_time: 2.0, rise_time: 1.0, steady_state_error: 0.001, max_control: 100}
"""


def run_checks(spec, design, simulation):
    """The checks the design's family offers."""
    return run_rules(spec, design, simulation, rules=check_rules(design.kind))


def _setup(text):
    spec = parse_spec(text).spec
    fam = family(spec.controller.kind)
    return spec, fam, synthesize(spec)


def _linear_sim(design, duration=5.0, n=5001):
    T = np.linspace(0.0, duration, n)
    resp = control.step_response(design.closed_loop.to_control(), T=T, input=0)
    y = np.asarray(resp.outputs).reshape(2, -1)  # outputs (x1, u) for the reference xD
    return step_result(T, y[0], y[1])


def test_core_checks_only_without_uncertainty_or_simulation():
    spec, fam, design = _setup(POSSPEED_YAML)
    checks = run_checks(spec, design, None)
    assert [c.name for c in checks] == CORE + MARGINS
    assert all(c.passed is True for c in checks), [c.detail for c in checks]


def test_tracking_core_checks_pass():
    spec, fam, design = _setup(TRACKING_YAML)
    checks = run_checks(spec, design, None)
    assert [c.name for c in checks] == CORE + MARGINS
    assert all(c.passed is True for c in checks), [c.detail for c in checks]


def test_full_order_and_json():
    spec, fam, design = _setup(SERVO_FULL)
    checks = run_checks(spec, design, _linear_sim(design))
    assert [c.name for c in checks] == CORE + ROBUST + MARGINS + ["designed_loop",
        "overshoot", "settling_time", "rise_time", "steady_state_error", "max_control", "command_chatter",
        "command_switching",
    ]
    assert all(c.passed is True for c in checks), [(c.name, c.detail) for c in checks if not c.passed]
    json.dumps([c.to_dict() for c in checks])  # certificates are JSON-serialisable


def test_requirements_without_simulation_give_no_time_domain_checks():
    spec, fam, design = _setup(SERVO_FULL)
    assert [c.name for c in run_checks(spec, design, None)] == CORE + ROBUST + MARGINS


def test_time_domain_checks_use_only_the_result_fields():
    """Engine-specific fields (controller state, measurements, settings) do not change any verdict."""
    spec, fam, design = _setup(SERVO_FULL)
    sim = _linear_sim(design)
    other = dataclasses.replace(
        sim, controller_state=np.full((len(sim.time), 4), 7.0), measured=np.zeros_like(sim.measured),
        settings={"integrator": "something else"},
    )
    a = [c.to_dict() for c in run_checks(spec, design, sim)]
    b = [c.to_dict() for c in run_checks(spec, design, other)]
    assert a == b


def test_a_design_with_wrong_gains_fails_the_core_checks():
    spec, fam, design = _setup(POSSPEED_YAML)
    wrong = dataclasses.replace(design, gains=design.gains.replace(K1=1.0))  # violates K1 > tau K3/(1 + Km K2)
    bad = with_closed_loop(wrong, pid_servo.law(wrong), [0.0, 0.0, 0.0])
    checks = {c.name: c for c in run_checks(spec, bad, None)}
    assert checks["pole_placement"].passed is False
    assert checks["routh_hurwitz"].passed is False
    assert checks["lyapunov"].passed is False


def test_checks_follow_what_the_design_exposes():
    """A design without a characteristic gets no Routh check; without requested poles, no pole placement."""
    spec, fam, design = _setup(SERVO_FULL)
    offered = applicable(design, spec, rules=fam.checks)
    assert "routh_hurwitz" in offered and "robust_box" in offered
    bare = dataclasses.replace(design, characteristic=None, poles=())
    names = applicable(bare, spec, rules=fam.checks)
    assert "routh_hurwitz" not in names and "robust_box" not in names and "pole_placement" not in names
    assert "lyapunov" in names and "robust_vertices" not in names  # robustness is one group, named by its rule
    assert "robustness" in names


def test_every_check_rule_is_offered_by_some_family():
    from designkit.families import FAMILIES

    offered = {c for f in FAMILIES.values() for c in f.check_names}
    universal = {name for name, rule in GENERIC.items() if rule.universal}  # offered for every family
    assert universal == {"command_chatter", "command_switching", "finite_run", "generated_code"}
    assert offered | universal >= set(GENERIC)


def test_a_generic_check_is_found_by_name_without_importing_the_others():
    import subprocess
    import sys
    from pathlib import Path

    src = Path(__file__).resolve().parents[2] / "src"
    code = ("import sys\nfrom designkit.verification.suite import GENERIC\nassert 'coupling' in GENERIC\n"
            "assert GENERIC['lyapunov'].name == 'lyapunov'\n"
            "print(sorted(m.split('.')[-1] for m in sys.modules if m.startswith('designkit.verification.checks.')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         env={"PYTHONPATH": str(src), "PATH": "/usr/bin:/bin"}).stdout
    assert out.strip() == "['lyapunov']"
    assert list(GENERIC) == sorted(GENERIC, key=lambda name: GENERIC[name].order)  # iteration: report order
