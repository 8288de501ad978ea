"""Recursive least squares in the simulated loop, against batch least squares (numpy lstsq) and the exact ZOH model
(scipy), from the recorded states and commands at the sample instants -- not from the law's own records."""

from __future__ import annotations

import numpy as np
import pytest

from designkit.families import synthesize
from designkit.pipeline import plant as plant_of
from designkit.schema.loader import parse_spec
from designkit.simulation.run import build
from tests.families.self_tuning.oracles import theta_scipy

SPEC = """\
name: rls-test
plant: {{kind: link, Km: 2.0, tau: 0.5}}
controller: {{kind: self_tuning, sampling_period: 0.01, estimator: {form}, forgetting: {lam},
             initial_covariance: {P0}, safeguards: {safe}, poles: [-4, -5], nominal: {{Km: 1.0, tau: 1.0}}}}
simulation: {{duration: {T}, dt: 0.002, trajectory: {{kind: prbs, amplitude: 0.3, bit: {bit}, seed: 3}}{change}}}
"""


def _run(form: str, lam: float = 1.0, P0: float = 1e8, T: float = 6.0, change: str = "", safe: str = "false",
         bit: float = 0.25):
    loaded = parse_spec(SPEC.format(form=form, lam=lam, P0=P0, T=T, change=change, safe=safe, bit=bit))
    true = plant_of(loaded)
    design = synthesize(loaded.spec, true)
    return build(loaded.spec, design, plant=true).run(), design


def _at_samples(res, Ts: float):
    t = np.asarray(res.time)
    idx = np.flatnonzero(np.isclose(np.mod(t + 1e-9, Ts), 0.0, atol=1e-6))
    th = np.column_stack([np.asarray(res.signals[k])[idx] for k in sorted(res.signals) if k.startswith("th")])
    return idx, np.asarray(res.state)[idx], np.asarray(res.u_command)[idx, 0], th


def _batch(form: str, x: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Regressors and outputs of the form's ARX equation from the sampled states and commands (at rest before)."""
    if form == "speed":
        return np.column_stack([x[:-1, 1], u[:-1]]), x[1:, 1]
    d = np.diff(np.r_[x[0, 0], x[:, 0]])  # D(i) = x1(i) - x1(i-1), D(0) = 0 (at rest before the run)
    u_prev = np.r_[0.0, u]
    return np.column_stack([d[:-1], u_prev[1:-1], u_prev[:-2]]), d[1:]


@pytest.mark.parametrize("form", ["speed", "position"])
def test_rls_without_forgetting_recovers_the_exact_zoh_parameters(form):
    """A PRBS bit of one sample keeps u(k-1) and u(k-2) apart (the position form's regressors are nearly collinear
    under a slow reference: the estimate is then conditioned by the data, not by the algorithm)."""
    P0 = 1e10
    res, design = _run(form, bit=0.01, P0=P0)
    idx, x, u, th = _at_samples(res, 0.01)
    Phi, out = _batch(form, x, u)
    theta_ls = np.linalg.lstsq(Phi, out, rcond=None)[0]
    exact = theta_scipy(2.0, 0.5, 0.01, form)
    np.testing.assert_allclose(theta_ls, exact, rtol=1e-8)  # the simulated data are the exact sampled link
    np.testing.assert_allclose(th[-1], exact, rtol=1e-8)  # RLS (lambda = 1, P0 = 1e10) on them
    np.testing.assert_allclose(th[-1], theta_ls, rtol=1e-8)
    # RLS is exactly the batch solution with the prior (theta0, P0 I): (I/P0 + Phi'Phi) theta = theta0/P0 + Phi'y
    theta0 = np.asarray(design.data.settings.theta0)
    prior = np.linalg.solve(np.eye(len(theta0)) / P0 + Phi.T @ Phi, theta0 / P0 + Phi.T @ out)
    np.testing.assert_allclose(th[-1], prior, rtol=1e-12)


def test_forgetting_tracks_a_parameter_step():
    change = ", plant_change: {time: 6.0, values: {Km: 1.0, tau: 0.8}}"
    res, design = _run("speed", lam=0.95, P0=100.0, T=12.0, change=change, safe="true")
    idx, x, u, th = _at_samples(res, 0.01)
    t = np.asarray(res.time)[idx]
    before = theta_scipy(2.0, 0.5, 0.01, "speed")
    after = theta_scipy(1.0, 0.8, 0.01, "speed")
    np.testing.assert_allclose(th[t < 6.0][-1], before, rtol=1e-6)
    np.testing.assert_allclose(th[-1], after, rtol=1e-6)
    # the same without forgetting stays between the two links
    res1, _ = _run("speed", lam=1.0, P0=100.0, T=12.0, change=change, safe="true")
    th1 = _at_samples(res1, 0.01)[3]
    assert np.max(np.abs(th1[-1] / after - 1)) > 0.05


def test_the_recorded_regressor_is_the_sampled_data():
    res, design = _run("position", T=2.0)
    idx, x, u, th = _at_samples(res, 0.01)
    Phi, _ = _batch("position", x, u)
    phi = np.column_stack([np.asarray(res.signals[f"phi{i}"])[idx] for i in (1, 2, 3)])
    np.testing.assert_allclose(phi[1:], Phi, rtol=1e-12, atol=1e-15)


def test_the_notes_recursion_is_the_standard_one_with_P_over_lambda():
    """§4.3 as printed (gamma = 1/(1 + x'Px), K = gamma P x, P <- (P - K x'P)/lambda) started from P0/lambda gives
    the estimates of designkit's law (the standard form from P0), on measurements fed to the law's update."""
    from designkit.families.self_tuning import settings_from
    from designkit.families.self_tuning.laws import self_tuning_law

    loaded = parse_spec(SPEC.format(form="speed", lam=0.9, P0=10.0, T=2.0, change="", safe="false", bit=0.25))
    design = synthesize(loaded.spec, plant_of(loaded))
    st = settings_from(design)
    law = self_tuning_law(design.plant, st)
    names = law.memory_names
    rng = np.random.default_rng(7)
    m = np.asarray(law.initial_memory, dtype=float)
    theta, P = np.asarray(st.theta0, dtype=float), np.eye(2) * st.P0 / st.forgetting
    v_prev = u_prev = None
    for _ in range(40):
        y = [rng.normal(), rng.normal()]
        if u_prev is not None:  # an exciting past input in the law's memory (its own command would do too)
            u_prev = rng.normal()
            m[names.index("u1")] = u_prev
        m = np.asarray(law.update(y, [], m, [0.3, 0.0, 0.0]), dtype=float).ravel()
        if v_prev is not None:
            x = np.array([v_prev, u_prev])
            gamma = 1.0 / (1.0 + x @ P @ x)
            K = gamma * P @ x
            theta = theta + K * (y[1] - x @ theta)
            P = (P - np.outer(K, x @ P)) / st.forgetting
        v_prev, u_prev = y[1], 0.0
        np.testing.assert_allclose(m[[names.index("th1"), names.index("th2")]], theta, rtol=1e-9, atol=1e-12)
    # the law's covariance is the notes' times lambda
    P_law = m[[names.index(n) for n in ("P11", "P12", "P21", "P22")]].reshape(2, 2)
    np.testing.assert_allclose(P_law, st.forgetting * P, rtol=1e-9, atol=1e-12)
