"""The adaptive computed torque's diagnosis of a filter that is not SPR, against a NumPy frequency sweep.

The reference is ``Re H(jw)`` of ``H(s) = (1 + psi s)/(s^2 + K2 s + K1)`` computed here with complex arithmetic on
a dense grid (not the family's sweep nor its grid), with ``w^2 Re H(jw)`` at a very high frequency for the
strictness: the bound ``psi > 1/K2`` the fix states is where that sweep turns from "not SPR" to "SPR", and the
frequency above which the diagnosis says ``Re H < 0`` is the sweep's sign change.  On
``specs/adaptive-ct-not-spr.yaml`` both failing checks are diagnosed, the rise of ``V`` the run shows is the one
the error equation predicts from the run's errors, and the declared fix passes when re-run.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from designkit.analysis.diagnosis import diagnose
from designkit.families.adaptive_computed_torque.diagnoses import crossing, psi_fix

K1, K2 = 100.0, 20.0  # the spec's poles -10, -10
W = np.concatenate([[0.0], np.logspace(-4, 6, 200_001)])


def _re_h(psi: float, w: np.ndarray) -> np.ndarray:
    s = 1j * w
    return ((1 + psi * s) / (s * s + K2 * s + K1)).real


def _sweep_says_spr(psi: float) -> bool:
    """Re H > 0 on the grid and w^2 Re H(jw) at 1e9 rad/s (its limit psi K2 - 1, to 1e-13) clearly positive."""
    top = 1e9
    return bool(np.all(_re_h(psi, W) > 0) and top**2 * _re_h(psi, np.array([top]))[0] > 1e-6)


@pytest.fixture(scope="module")
def diagnosed(not_spr_result):
    return not_spr_result, diagnose(not_spr_result)


def test_the_spr_bound_is_where_the_sweep_turns():
    bound = 1.0 / K2
    assert not _sweep_says_spr(0.02)  # the spec's psi
    for rel in (1e-3, 1e-2, 0.5, 1.0, 10.0):
        assert _sweep_says_spr(bound * (1 + rel)), rel
        assert not _sweep_says_spr(bound * (1 - rel / 2)), rel
    assert not _sweep_says_spr(bound)  # positive real, not strictly: w^2 Re H -> 0
    # the family's fix: psi = 2/K2 on the joints that fail
    psi, joints = psi_fix(SimpleNamespace(K1=(K1, K1), K2=(K2, K2), psi=(0.02, 0.2)))
    assert joints == [1] and psi == [pytest.approx(0.1), 0.2] and _sweep_says_spr(psi[0])


def test_re_h_is_negative_above_the_crossing_the_diagnosis_states():
    w0 = crossing(K1, K2, 0.02)
    re = _re_h(0.02, W)
    k = int(np.flatnonzero(re < 0)[0])  # the sweep's first negative value
    assert W[k - 1] <= w0 <= W[k]
    assert w0 == pytest.approx(12.91, abs=5e-3)
    assert crossing(K1, K2, 0.06) is None


def test_both_failures_are_diagnosed_from_the_spr_condition(diagnosed):
    result, diag = diagnosed
    by = {f.check: f for f in diag.findings}
    assert set(by) == {"spr_certificate", "adaptive_lyapunov"}
    spr, lyap = by["spr_certificate"], by["adaptive_lyapunov"]
    assert "ψ K2 = 0.02 s × 20 1/s = 0.4, below 1" in spr.cause and "12.91 rad/s" in spr.cause
    assert "0.05 s on joints 1 and 2" in spr.fix and "0.1 s on joints 1 and 2" in spr.fix
    assert lyap.fix == spr.fix  # one condition, one fix, shown once
    assert "12.91 1/s × |e|" in lyap.cause
    assert "_" not in spr.cause + spr.fix + lyap.cause


def test_the_rise_of_v_is_the_one_the_error_equation_predicts(diagnosed):
    result, diag = diagnosed
    lyap = next(f for f in diag.findings if f.check == "adaptive_lyapunov")
    check = next(c for c in result.checks if c.name == "adaptive_lyapunov")
    measured = 100 * check.certificate["relative_rise"]
    text = lyap.cause.split("V rises by ")[1]
    said, predicted = float(text.split(" %")[0]), float(text.split("from the run's errors, is ")[1].split(" %")[0])
    assert said == pytest.approx(measured, rel=1e-3)
    assert predicted == pytest.approx(measured, rel=0.01)  # the recorded V against the integral of V' from e, e'


def test_the_declared_fix_passes_when_re_run(diagnosed):
    _, diag = diagnosed
    (proposed,) = diag.proposed  # the two findings share the sentence
    (trial,) = proposed.trials
    assert trial.remedy.changes == (("controller.psi", [0.1, 0.1]),)
    assert trial.passed, trial.verdict
    assert {o.name for o in trial.outcomes} == {"spr_certificate", "adaptive_lyapunov"}
    spr = next(o for o in trial.outcomes if o.name == "spr_certificate")
    assert spr.value == pytest.approx(1.0)  # psi K2 - 1 at psi = 2/K2
