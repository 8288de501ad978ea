"""The decentralized PID's diagnosis of an overshoot, against python-control on transfer functions written by hand.

The reference for each joint loop is ``control.tf`` built from the spec's own numbers (its poles and its zero:
``T(s) = (prod|p|/|z|) (s - z)/prod(s - p)``, unit DC gain) and ``control.step_info`` on a fine grid; nothing of the
family's step computation (a companion realization discretized exactly) is used by it.  The zero's location is
checked against the zeros python-control finds in the loop written from the design's link and gains; the gain
margin of the joint with a negative rate gain against ``control.stability_margins`` of its loop at the plant input.
On ``specs/scara-decentralized-pid.yaml`` the diagnosis names joint 2, predicts its overshoot as python-control
does, and both declared fixes pass when re-run.
"""

from __future__ import annotations

import math
from pathlib import Path

import control
import numpy as np
import pytest

import designkit as dk
from designkit.analysis.diagnosis import diagnose
from designkit.families.decentralized_pid.diagnoses import joint_loops, overshoot, upper_gain_margin, zero_for

SPECS = Path(__file__).resolve().parents[3] / "specs"
GRID = np.linspace(0.0, 5.0, 50_001)  # 0.1 ms: the peak of these steps to about 1e-4 % (each settles within 3 s)


def _by_hand(poles, zero) -> control.TransferFunction:
    """``(prod|p|/|z|) (s - z)/prod(s - p)``: unit DC gain, written from the numbers alone."""
    gain = float(np.real(np.prod([-p for p in poles])))
    if zero is None:
        return control.tf([gain], np.real(np.poly(poles)))
    return control.tf([gain / -zero, gain], np.real(np.poly(poles)))


def _control_overshoot(poles, zero) -> float:
    return float(control.step_info(_by_hand(poles, zero), T=GRID)["Overshoot"])


@pytest.fixture(scope="module")
def scara():
    result = dk.run(dk.load_spec(SPECS / "scara-decentralized-pid.yaml"))
    return result, diagnose(result)


@pytest.mark.parametrize(("poles", "zero"), [
    ((-8, -10, -40), -3.0),  # the SCARA's joint 2
    ((-4, -5, -20), -3.0),  # its other joints
    ((-4, -5, -20), -5.0),  # a zero on a pole
    ((-2 + 3j, -2 - 3j, -10), -1.5),  # a lightly damped pair and a slow zero
    ((-2 + 3j, -2 - 3j, -10), None),  # the poles alone
])
def test_overshoot_of_a_joint_loop_is_python_control_s(poles, zero):
    assert overshoot(poles, zero) == pytest.approx(_control_overshoot(poles, zero), abs=1e-3)


def test_the_bound_on_the_zero_is_where_python_control_crosses_the_limit():
    poles, limit = (-8, -10, -40), 15.0
    z = zero_for(poles, limit)
    assert -8 < z < -3  # between the design's zero and the slowest pole
    assert _control_overshoot(poles, z) == pytest.approx(limit, abs=1e-3)
    assert _control_overshoot(poles, 0.99 * z) > limit + 0.1  # right of it: more
    assert _control_overshoot(poles, 1.01 * z) < limit - 0.1  # left of it: less
    # every zero further left meets the limit, and a zero on the third pole does not overshoot
    assert all(_control_overshoot(poles, w) <= limit for w in (1.5 * z, 3 * z, -40.0, -400.0))
    assert zero_for(((-1 + 5j), (-1 - 5j), -10), 15.0) is None  # the poles alone overshoot: no zero helps


def test_the_joint_loops_have_the_spec_s_poles_and_zero(scara):
    result, _ = scara
    spec = result.loaded.spec.controller
    for lp, poles in zip(joint_loops(result.design), spec.poles, strict=True):
        # the loop q_i/qD_i from the link and the gains, written out: Km ((K1 + K3 K4) s + K3)/(tau s^3 + ...)
        T = control.tf([lp.Km * (lp.K1 + lp.K3 * lp.K4), lp.Km * lp.K3],
                       [lp.tau, 1 + lp.Km * lp.K2, lp.Km * lp.K1, lp.Km * lp.K3])
        assert sorted(T.poles().real) == pytest.approx(sorted(complex(p).real for p in poles), rel=1e-9)
        assert T.zeros() == pytest.approx([spec.zero], rel=1e-9)
        assert lp.zero == pytest.approx(spec.zero, rel=1e-12)


def test_the_gain_margin_of_a_negative_rate_gain_is_python_control_s(scara):
    result, _ = scara
    joint4 = joint_loops(result.design)[3]
    assert joint4.K2 < 0
    # the loop at the plant input: u -> -(K1 + K2 s + K3/s) x1, x1 = Km/(s (tau s + 1)) u
    L = control.tf([joint4.Km * joint4.K2, joint4.Km * joint4.K1, joint4.Km * joint4.K3], [joint4.tau, 1, 0, 0])
    gm, pm, *_ = control.stability_margins(L)
    assert upper_gain_margin(joint4) == pytest.approx(gm, rel=1e-6)
    assert gm == pytest.approx(1.2813, abs=1e-4) and pm == pytest.approx(19.24, abs=0.05)  # the report's u4
    assert upper_gain_margin(joint_loops(result.design)[1]) is None  # K2 > 0


def test_the_scara_overshoot_is_explained_by_joint_2_s_zero(scara):
    result, diag = scara
    (finding,) = diag.findings
    assert finding.check == "overshoot"
    predicted = _control_overshoot((-8, -10, -40), -3.0)
    assert f"joint 2's loop, as designed on its simplified link, overshoots {predicted:.4g} %" in finding.cause.lower()
    assert "zero at -3 1/s" in finding.cause and "right of its closed-loop poles -8, -10 and -40 1/s" in finding.cause
    assert "1/|z| = 0.3333 s" in finding.cause
    assert "_" not in finding.cause and "_" not in finding.fix  # words, no identifiers
    others = _control_overshoot((-4, -5, -20), -3.0)
    assert f"{others:.4g} % (joint 1" in finding.cause
    assert "joint 4's rate gain K2 = -0.0384 N·m·s/rad is negative" in finding.cause.replace("Joint", "joint")
    bound = zero_for((-8, -10, -40), 15.0)
    printed = -math.ceil(-bound * 1000 - 1e-9) / 1000
    assert f"move the zero of joint 2 to {printed:.4g} 1/s or further left" in finding.fix.lower()


def test_both_declared_fixes_pass_when_re_run(scara):
    result, diag = scara
    (proposed,) = diag.proposed
    assert len(proposed.trials) == 2
    for trial in proposed.trials:
        assert trial.passed, trial.verdict
        (path, zeros), = trial.remedy.changes
        assert path == "controller.zero" and zeros[0] == zeros[2] == zeros[3] == -3.0
        (outcome,) = trial.outcomes
        assert outcome.name == "overshoot" and outcome.value <= 15.0
    margin, pole = proposed.trials
    # with the design margin the loop is aimed at 13.5 %, and the simulation stays under it; on the pole, near zero
    assert _control_overshoot((-8, -10, -40), margin.remedy.changes[0][1][1]) == pytest.approx(13.5, abs=0.05)
    assert margin.outcomes[0].value < 13.5
    assert pole.remedy.changes[0][1][1] == -40.0 and pole.outcomes[0].value < 5.0


# The SCARA with lightly damped poles designed at the folded elbow (tests/families/decentralized_pid/test_workspace.py):
# its workspace reaches the stretched elbow, where D_11 is 1.65 times the design value and joint 1's loop is unstable.
FRAGILE = """\
name: scara-fragile
plant: {kind: robot, robot: scara}
controller:
  kind: decentralized_pid
  poles: ['-0.6+5j', '-0.6-5j', -5]
  configuration: [0, 1.5708, 0.1, 0]
  workspace: {low: [-1, -0.5, 0, -1], high: [1, 1.6, 0.21, 1]}
simulation: {duration: 2.0, step: 0.05, initial_position: [0, 1.5708, 0.1, 0]}
"""


def _ratio(poles) -> float:
    """S1 S2/S3 from the coefficients of prod(s - p) = s^3 + S1 s^2 + S2 s + S3 (numpy.poly)."""
    _, S1, S2, S3 = np.real(np.poly(poles))
    return S1 * S2 / S3


def test_a_failed_workspace_certificate_is_explained_and_fixed_by_better_damped_poles():
    from designkit.schema.loader import parse_spec

    result = dk.run(parse_spec(FRAGILE))
    diag = diagnose(result)
    (finding,) = diag.findings
    assert finding.check == "workspace"
    row = next(c for c in result.checks if c.name == "workspace").certificate["joints"][0]
    d_star = row["tau_nominal_s"]  # Km_1 = 1/f_1 = 1: D_11 = tau_1
    ratio = _ratio([-0.6 + 5j, -0.6 - 5j, -5])
    assert row["inertia_critical"] == pytest.approx(d_star * ratio, rel=1e-9)  # the pole-placement identity
    assert f"{ratio:.4g} times the design value" in finding.cause and "2.503 kg·m²" in finding.cause
    need = row["inertia_range"][1] / d_star
    assert f"S1 S2/S3 exceeds {need:.4g}" in finding.fix
    (proposed,) = diag.proposed
    poles, configuration = proposed.trials
    sets = poles.remedy.changes[0][1]
    assert sets[1:] == [["-0.6-5i", "-0.6+5i", -5.0]] * 3  # the other joints as designed
    joint1 = [complex(p.replace("i", "j")) if isinstance(p, str) else p for p in sets[0]]
    assert [p.imag for p in joint1] == [-5, 5, 0] and _ratio(joint1) >= 1.1 * need  # the design margin above it
    assert poles.passed, poles.verdict
    # the configuration where D_11 is largest covers the box for joint 1, but the coupled arm linearized there is not
    # certified: tried, said with its numbers, not numbered
    assert configuration.remedy.changes == (("controller.configuration", [0.0, 0.0, 0.105, 0.0]),)
    assert not configuration.passed and "lyapunov" in configuration.verdict.lower()
