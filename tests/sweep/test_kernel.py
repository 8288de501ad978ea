"""The sweep's compiled kernel (sweep/kernel.py: metrics reduced inside the integrator, no records) against two
routes it does not share code with: the pipeline's time-domain checks on each sample's single run, and the NumPy
metrics of the records path (sweep/margins.py) on the same runs."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from designkit.models.codegen import find_compiler
from designkit.sweep.chunk import prepared, run_samples
from designkit.sweep.margins import joint_metrics
from designkit.verification.time_domain import time_domain_checks
from tests.sweep.specs import SIMNOG, link
from tests.sweep.test_margins import TRAJECTORY

SPECS = Path(__file__).resolve().parents[2] / "specs"

pytestmark = pytest.mark.skipif(find_compiler() is None, reason="the kernel runs compiled only")

RK4 = "numerics: {integrator: rk4}\n"
DEFAULT = {  # the same scenarios with the default integrator (the compiled Dormand-Prince pair): the kernel's case
    "simnog": SIMNOG.replace(RK4, ""),
    "link": link(km=(1.2, 3.0), tau=(0.3, 0.8), duration=8.0).replace(RK4, "").replace(
        "requirements: {steady_state_error: 0.5}",
        "requirements: {overshoot: 30, settling_time: 2.5, rise_time: 0.5, steady_state_error: 0.01, "
        "tracking_error: 1.2, max_control: 60}"),
    "trajectory": TRAJECTORY.replace(RK4, ""),
    # no command observed: the kernel reads only the grid points its plan picks step by step (a sample of the
    # points skipped could change a maximum, a crossing or the band's last exit only if a bound were wrong)
    "simnog_no_control": SIMNOG.replace(RK4, "").replace(", max_control: 300", ""),
    "simnog_spec": (SPECS / "simnog-decentralized-pid.yaml").read_text(),
    "simnog_one_joint_at_rest": SIMNOG.replace(RK4, "").replace(", max_control: 300", "").replace(
        "step: [1.0, -0.5]", "step: [0.0, -0.5]"),
    "simnog_not_settled_at_the_end": SIMNOG.replace(RK4, "").replace(", max_control: 300", "").replace(
        "duration: 2.0", "duration: 0.6"),
    "link_no_control": link(km=(1.2, 3.0), tau=(0.3, 0.8), duration=8.0).replace(RK4, "").replace(
        "requirements: {steady_state_error: 0.5}",
        "requirements: {overshoot: 30, settling_time: 2.5, rise_time: 0.5, steady_state_error: 0.01, "
        "tracking_error: 1.2}").replace("simulation: {duration: 8.0}", "simulation: {duration: 8.0, step: -0.7}"),
}
FIELDS = ("finite", "overshoot", "rise", "settle", "moving", "max_err", "amps", "u_peak", "u_ok")


def _records_path(prep):
    return dataclasses.replace(prep, kernel=None)


@pytest.mark.parametrize("name", list(DEFAULT))
def test_kernel_margins_equal_the_pipeline_checks_on_the_single_runs(name):
    prep = prepared(DEFAULT[name], "<test>", 5)
    assert prep.kernel is not None
    values, seeds = prep.space.draw(3, np.arange(5))
    m, failed = run_samples(prep, values, seeds)
    assert not failed.any()
    for i in range(5):
        params = {d.key: float(values[i, k]) for k, d in enumerate(prep.space.dimensions)}
        checks = time_domain_checks(prep.requirements, prep.simulator.run(parameters=params))
        assert {c.name for c in checks} == set(m.names)
        for c in checks:
            if c.margin is None:
                assert np.isnan(m.margin[c.name][i]), c.name
            else:
                assert m.margin[c.name][i] == pytest.approx(c.margin, rel=1e-9, abs=1e-12), (c.name, i)


@pytest.mark.parametrize("name", list(DEFAULT))
def test_kernel_metrics_are_the_records_metrics_to_the_last_bit(name):
    """Every per-joint metric is bitwise the NumPy one on the records (the same formulas in the same order), but the
    steady-state mean, summed in grid order in C and pairwise by NumPy."""
    prep = prepared(DEFAULT[name], "<test>", 4)
    values, seeds = prep.space.draw(5, np.arange(4))
    P = _parameters(prep, values)
    fast, failed = prep.kernel.run(prep.simulator, P)
    records = prep.batch.run(P)
    req = prep.requirements
    slow = joint_metrics(records, prep.simulator.kind, req.settling_band, req.max_control is not None)
    assert not failed.any()
    for f in FIELDS:
        assert np.array_equal(getattr(fast, f), getattr(slow, f), equal_nan=True), f
    np.testing.assert_allclose(fast.sse, slow.sse, rtol=1e-11, atol=0)


def test_a_sample_is_the_same_alone_and_in_a_batch():
    prep = prepared(DEFAULT["simnog"], "<test>", 8)
    values, _ = prep.space.draw(9, np.arange(8))
    P = _parameters(prep, values)
    together, _ = prep.kernel.run(prep.simulator, P)
    alone, _ = prep.kernel.run(prep.simulator, P[5:6])
    for f in (*FIELDS, "sse"):
        assert np.array_equal(getattr(together, f)[5:6], getattr(alone, f), equal_nan=True), f


def test_a_diverging_sample_fails_as_on_the_records_path():
    """The link's PID servo designed on Km = 2, tau = 0.5 diverges where tau > K1 (1 + Km K2)/K3 (Routh-Hurwitz,
    tests/sweep/test_pass_fraction.py): a box across that line has samples whose run stops, NaN metrics, failed."""
    text = link(km=(0.1, 1.0), tau=(0.5, 4.0), duration=60.0).replace(RK4, "")
    prep = prepared(text, "<test>", 16)
    values, seeds = prep.space.draw(1, np.arange(16))
    m, failed = run_samples(prep, values, seeds)
    m2, failed2 = run_samples(_records_path(prep), values, seeds)
    g = prep.design.gains
    K1, K2, K3 = (float(g[k]) for k in ("K1", "K2", "K3"))
    unstable = values[:, 1] > K1 * (1 + values[:, 0] * K2) / K3
    assert unstable.any() and (~unstable).any()
    assert np.array_equal(m.passed, ~unstable)
    assert np.array_equal(m.passed, m2.passed)
    assert np.array_equal(np.isnan(m.margin["steady_state_error"]), np.isnan(m2.margin["steady_state_error"]))


def _parameters(prep, values):
    from designkit.sweep.chunk import _inputs

    return _inputs(prep, values, np.zeros(len(values), dtype=np.int64))["parameters"]
