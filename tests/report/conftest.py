"""Fixtures for the report tests: real designs, hand-made checks and a linear 'simulation'.

The pipeline's own verification and simulation are not used here, so that the report layer is
tested on values whose content is known exactly.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pytest

from designkit.families import synthesize
from designkit.pipeline import PipelineResult, versions
from designkit.schema.loader import parse_spec
from designkit.simulation.result import SimulationResult
from designkit.verification.check import Check
from designkit.verification.loop import loop_margins_check
from tests.problems import TRACKING_YAML

SERVO_YAML = """\
name: report-servo
description: >
  PID servo with a perturbation and an uncertainty box, used by the report tests.
plant:
  kind: link
  Km: 2.0
  tau: 0.5
  uncertainty: {Km: [1.5, 2.5], tau: [0.4, 0.6], grid: 5}
controller: {kind: pid_servo, poles: [-4, -5, -20], zero: -3}
requirements: {overshoot: 10, settling_time: 2.0, rise_time: 0.8, steady_state_error: 0.01, max_control: 40}
simulation:
  duration: 4.0
  perturbation: {value: -5.0, time: 2.5}
"""

NASTY = 'P_1 #x $y$ *bold* @ref <lab> [a] \\cmd `code` ~ // /* -- = + "q" \'s\' http://x.org {b}'


def assert_svg(svg: str) -> ET.Element:
    """Parse ``svg`` and check that it is an SVG document without a creation date (reproducible)."""
    root = ET.fromstring(svg.encode("utf-8"))
    assert root.tag.endswith("svg")
    assert "<dc:date>" not in svg  # no creation date: reproducible
    return root


def linear_simulation(design, spec, *, limit: float | None = None) -> SimulationResult:
    """A SimulationResult from python-control's forced_response of the design's closed loop."""
    import control

    cl = design.closed_loop
    duration = spec.simulation.duration or 4.0
    t = np.linspace(0.0, duration, 801)
    ref = np.zeros((t.size, 3))
    tracking = design.reference == "trajectory"
    if tracking:
        s = np.clip(t / 1.0, 0, 1)
        ref[:, 0] = 10 * s**3 - 15 * s**4 + 6 * s**5
        ref[:, 1] = np.where(t <= 1.0, 30 * s**2 - 60 * s**3 + 30 * s**4, 0.0)
        ref[:, 2] = np.where(t <= 1.0, 60 * s - 180 * s**2 + 120 * s**3, 0.0)
    else:
        ref[:, 0] = spec.simulation.step
    pert = np.zeros(t.size)
    if spec.simulation.perturbation is not None:
        p = spec.simulation.perturbation
        pert[t >= p.time] = p.value
    names = {"xD": ref[:, 0], "xDd": ref[:, 1], "xDdd": ref[:, 2], "xi": pert}
    U = np.vstack([names[name] for name in cl.inputs])
    resp = control.forced_response(control.ss(cl.A, cl.B, cl.C, cl.D), T=t, U=U, X0=np.zeros(3),
                                   return_x=True)
    x = np.asarray(resp.states).T
    u = np.asarray(resp.outputs)[1]
    applied = u if limit is None else np.clip(u, -limit, limit)
    return SimulationResult(
        time=t, reference=ref, state=x[:, :2], controller_state=x[:, 2:], u_command=u, u_applied=applied,
        perturbation=pert, measured=x[:, :2], kind="trajectory" if tracking else "step",
        settings={"integrator": "linear (test fixture)", "dt": float(t[1] - t[0]), "noise": None},
    )


def servo_checks(*, overshoot_passed: bool | None = True, detail_extra: str = "") -> tuple[Check, ...]:
    km = np.linspace(1.5, 2.5, 5)
    tau = np.linspace(0.4, 0.6, 5)
    grid = [[float(0.6 + 0.8 * (k - 2.0) - 4.0 * (t - 0.5)) for k in km] for t in tau]
    return (
        Check("routh_hurwitz", True, target="all first-column entries > 0", achieved=0.25, margin=0.25,
              unit="1 (scaled)", detail="all Routh first-column entries are positive",
              certificate={"coefficients": [0.5, 14.5, 100.0, 200.0], "status": "stable",
                           "conditions": [{"condition": "K2 > -1/Km", "value": 6.75, "threshold": -0.5,
                                           "margin": 7.25, "unit": "N*m*s/rad"},
                                          {"condition": "K1 > 0", "value": 50.0, "threshold": 0.0,
                                           "margin": 50.0, "unit": "N*m/rad"}]}),
        Check("lyapunov", True, target="P >= 1e-06 I", achieved=0.0123, margin=0.0122, unit="1 (normalised)",
              detail="Lyapunov function found and re-checked",
              certificate={"P": [[1.0, 0.123456789, -3.3e-5], [0.123456789, 0.5, 0.01], [-3.3e-5, 0.01, 0.25]],
                           "eig_P": [0.2, 0.5, 1.0], "solver_status": "optimal",
                           "eig_A": [[[-4.0, 0.0], [-5.0, 0.0], [-20.0, 0.0]]]}),
        Check("overshoot", overshoot_passed, target="<= 10 %", achieved=4.2, margin=5.8, unit="%",
              detail="peak of x1 over the step" + detail_extra),
        Check("robust_grid", True, target="stable over the box", achieved=0.1, margin=0.1, unit="1/s",
              detail="min over the grid", certificate={"grid": {
                  "axes": [{"name": "Km", "unit": "(rad/s)/(N*m)", "values": km.tolist()},
                           {"name": "tau", "unit": "s", "values": tau.tolist()}],
                  "values": grid, "label": "-max Re(pole) (1/s)"}}),
    )


def make_result(yaml_text: str = SERVO_YAML, checks: tuple[Check, ...] | None = None, *, simulate: bool = True,
                path: str = "specs/report-servo.yaml", margins: bool = True) -> PipelineResult:
    loaded = parse_spec(yaml_text, path=path)
    design = synthesize(loaded.spec)
    sim = linear_simulation(design, loaded.spec) if simulate else None
    checks = (*(servo_checks() if checks is None else checks), *([loop_margins_check(design)] if margins else []))
    return PipelineResult(loaded=loaded, design=design, checks=checks, simulation=sim, versions=versions())


@pytest.fixture(scope="session")
def servo_result() -> PipelineResult:
    return make_result()


@pytest.fixture(scope="session")
def failed_result() -> PipelineResult:
    return make_result(checks=servo_checks(overshoot_passed=False))


@pytest.fixture(scope="session")
def undecided_result() -> PipelineResult:
    return make_result(checks=servo_checks(overshoot_passed=None))


@pytest.fixture(scope="session")
def tracking_result() -> PipelineResult:
    text = TRACKING_YAML + "requirements: {overshoot: 5, settling_time: 2.0}\nsimulation: {duration: 3.0}\n"
    return make_result(text, checks=servo_checks()[:2], path="<string>")


@pytest.fixture(scope="session")
def servo_model(servo_result):
    from designkit.report.model import build_report_model

    return build_report_model(servo_result, studies=False)
