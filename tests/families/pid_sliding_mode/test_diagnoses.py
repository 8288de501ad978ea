"""The PID/sliding-mode diagnosis of a relay below the perturbation, on the two example specs that fail it.

``pid-sm-link-weak-relay`` (notes section 5.4): the perturbation the diagnosis reads off the run (the parameter
change's ``xi_p`` from ``x2`` and ``u0``) is checked against an independent route, the link's own equation solved
for the perturbation with the simulated acceleration (``numpy.gradient`` of ``x2``) and the recorded relay output;
the fix ``M = (1 + margin) sup|xi|`` is recomputed here and passes when re-run.  ``hierarchy-simnog-small-M``: the
fix covers the largest proven bound with the margin, and both declared fixes (that ``M``, and ``M`` left to the
design) pass when re-run.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import designkit as dk
from designkit.analysis.diagnosis import diagnose
from designkit.families.pid_sliding_mode.diagnoses import run_xi

SPECS = Path(__file__).resolve().parents[3] / "specs"


@pytest.fixture(scope="module")
def runs():
    out = {}
    for name in ("pid-sm-link-weak-relay", "hierarchy-simnog-small-M"):
        result = dk.run(dk.load_spec(SPECS / f"{name}.yaml"))
        out[name] = (result, diagnose(result))
    return out


def test_the_run_s_perturbation_is_the_link_equation_s(runs):
    result, _ = runs["pid-sm-link-weak-relay"]
    sim, info = result.simulation, result.design.data
    t, xi = run_xi(info, sim)
    # after the change the true link is x2' = -x2/tau + (Km/tau) u, the model x2' = -x2/tau0 + (Km0/tau0) u0 +
    # (Km/tau)(du + xi_p): solved for xi_p with the simulated acceleration
    Km, tau, (Km0, tau0) = 1.3, 0.7, info.nominal
    x2 = np.asarray(sim.state)[:, 1]
    u0, du = (np.asarray(sim.signals[k]) for k in ("u0", "du"))
    x2dot = np.gradient(x2, t)
    reference = (tau / Km) * (x2dot + x2 / tau0 - (Km0 / tau0) * u0) - du
    xd = np.asarray(sim.reference)[:, 0, 0]
    jumps = np.convolve(np.abs(np.diff(xd, prepend=xd[0], append=xd[-1])) > 0, np.ones(5), "same")[:-1] > 0
    after = (t > 4.3) & ~jumps & (np.arange(t.size) < t.size - 1)  # away from the change and the reference's jumps
    assert np.max(np.abs(xi[after] - reference[after])) < 0.02 * info.M
    assert np.all(xi[t < 4.2] == 0.0)
    assert np.max(np.abs(xi)) > info.M  # what the diagnosis says: the run's xi exceeds the relay


def test_the_link_relay_failure_and_its_fix(runs):
    result, diag = runs["pid-sm-link-weak-relay"]
    by = {f.check: f for f in diag.findings}
    assert set(by) == {"pid_sm_relay", "pid_sm_in_band"}
    info = result.design.data
    xi = info.xi_total
    assert f"M = 3 N·m is below sup|ξ| = {xi:.4g} N·m" in by["pid_sm_relay"].cause
    assert "exceeds M for" in by["pid_sm_in_band"].cause
    M = math.ceil(1.2 * xi * 1000) / 1000  # the 20 % margin, rounded up at the printed digits
    assert by["pid_sm_relay"].fix == by["pid_sm_in_band"].fix and f"M = {M:.4g} N·m" in by["pid_sm_relay"].fix
    (proposed,) = diag.proposed
    (trial,) = proposed.trials
    assert trial.remedy.changes == (("controller.M", M),) and 1.2 * xi <= M
    assert trial.passed, trial.verdict


def test_the_hierarchy_failures_and_their_fixes(runs):
    result, diag = runs["hierarchy-simnog-small-M"]
    assert {f.check for f in diag.findings} == {"pid_sm_hierarchy", "pid_sm_robot_xi", "pid_sm_robot_in_band"}
    assert all(f.cause and f.fix for f in diag.findings)
    info = result.design.data
    largest = max(info.bound)
    M = math.ceil(1.2 * largest * 1000) / 1000
    xi_finding = next(f for f in diag.findings if f.check == "pid_sm_robot_xi")
    peak = next(c for c in result.checks if c.name == "pid_sm_robot_xi").certificate["peak_xi_inside"][1]
    assert peak > 4.0 and f"the run meets |ξ2| = {peak:.4g} N·m, above M2 = 4 N·m" in xi_finding.cause
    (proposed,) = diag.proposed
    given, chosen = proposed.trials
    assert given.remedy.changes == (("controller.M", M),) and chosen.remedy.changes == (("controller.M", None),)
    assert given.passed and chosen.passed, (given.verdict, chosen.verdict)
