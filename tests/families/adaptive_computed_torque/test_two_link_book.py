"""Slotine and Li's two-link adaptive example (specs/adaptive-ct-two-link-slotine-li.yaml) against an independent
integration: the book's arm written by hand in its parameters ``a = (a1, a2, a3, a4)`` (Applied Nonlinear Control,
1991, section 9.2, Example 9.2), its law ``tau = Y a^ - KD s`` and update ``a^' = -Gamma Y' s`` with
``s = q~' + Lambda q~``, ``q~ = q - qd`` (the book's signs), integrated by SciPy's DOP853."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from designkit.families.adaptive_computed_torque.laws import adaptive_law, estimates, true_parameters
from designkit.pipeline import design as design_of
from designkit.pipeline import run
from designkit.schema.loader import load_spec
from tests.families.adaptive_computed_torque.conftest import SPECS

SPEC = SPECS / "adaptive-ct-two-link-slotine-li.yaml"
A_TRUE = np.array([3.34, 0.97, 2 * 0.6 * np.cos(np.pi / 6), 0.6])
"""The book's a from its arm: a1 = I1 + m1 lc1^2 + Ie + me lce^2 + me l1^2, a2 = Ie + me lce^2, a3 = me l1 lce cos de,
a4 = me l1 lce sin de with m1 = 1, l1 = 1, lc1 = 0.5, I1 = 0.12, me = 2, lce = 0.6, de = 30 deg, Ie = 0.25."""
T = np.array([[1.0, 1, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, -1]])
OFFSET = np.array([2.0, 0, 0, 0])  # a = T p + (m2 l1^2, 0, 0, 0), p = (Izz1, Izz2, mcx2, mcy2)
GAMMA = np.diag([0.03, 0.05, 0.1, 0.3])
LAMBDA, KD = 20.0, 100.0
AMP = np.radians([30.0, 45.0])


def H(q: np.ndarray, a: np.ndarray) -> np.ndarray:
    """The book's inertia matrix."""
    c2, s2 = np.cos(q[1]), np.sin(q[1])
    h11 = a[0] + 2 * a[2] * c2 + 2 * a[3] * s2
    h12 = a[1] + a[2] * c2 + a[3] * s2
    return np.array([[h11, h12], [h12, a[1]]])


def C(q: np.ndarray, qd: np.ndarray, a: np.ndarray) -> np.ndarray:
    """The book's Coriolis matrix (``H' - 2 C`` skew)."""
    h = a[2] * np.sin(q[1]) - a[3] * np.cos(q[1])
    return np.array([[-h * qd[1], -h * (qd[0] + qd[1])], [h * qd[0], 0.0]])


def Y(q: np.ndarray, qd: np.ndarray, v: np.ndarray, acc: np.ndarray) -> np.ndarray:
    """``Y a = H(q; a) acc + C(q, qd; a) v``, column by column (``H`` and ``C`` are linear in ``a``)."""
    return np.column_stack([H(q, e) @ acc + C(q, qd, e) @ v for e in np.eye(4)])


def desired(t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    w = 2 * np.pi
    return AMP * (1 - np.cos(w * t)), AMP * w * np.sin(w * t), AMP * w**2 * np.cos(w * t)


def field(t: float, z: np.ndarray) -> np.ndarray:
    q, qd, a_hat = z[0:2], z[2:4], z[4:8]
    q_d, qd_d, qdd_d = desired(t)
    qt, qdt = q - q_d, qd - qd_d
    s = qdt + LAMBDA * qt
    qr_d, qr_dd = qd_d - LAMBDA * qt, qdd_d - LAMBDA * qdt
    Yr = Y(q, qd, qr_d, qr_dd)
    tau = Yr @ a_hat - KD * s
    qdd = np.linalg.solve(H(q, A_TRUE), tau - C(q, qd, A_TRUE) @ qd)
    return np.concatenate([qd, qdd, -GAMMA @ Yr.T @ s])


def test_the_spec_arm_is_the_books_arm():
    d = design_of(load_spec(SPEC))
    p = true_parameters(d.plant)
    names = list(d.plant.robot.parameter_names)
    adapted = np.array([p[names.index(x)] for x in ("Izz1", "Izz2", "mcx2", "mcy2")])
    np.testing.assert_allclose(T @ adapted + OFFSET, A_TRUE, rtol=1e-12)
    rng = np.random.default_rng(3)
    for _ in range(4):
        q = rng.uniform(-2, 2, 2)
        np.testing.assert_allclose(d.plant.robot.mass_matrix(q, p=d.plant.model_parameters()), H(q, A_TRUE),
                                   atol=1e-12)


def test_adaptation_rate_is_the_books_update_through_the_combination():
    """The law's ``p^'`` at random states equals ``T^-1 (a^')`` with the book's ``a^' = -Gamma Y' s`` (hand-written
    ``Y``): the combination's gain ``K = T^-1 Gamma T^-T`` acts as a diagonal gain on ``a``."""
    d = design_of(load_spec(SPEC))
    law = adaptive_law(d.plant, d.data.adaptation)
    rng = np.random.default_rng(0)
    for _ in range(5):
        y = rng.uniform(-1, 1, 4)
        xc = rng.uniform(-1, 1, 4)
        r = rng.uniform(-1, 1, 6)  # qD, qD', qD''
        got = np.asarray(law.derivative(y, xc, [], r, np.ones(4))).ravel()
        q, qd = y[0:2], y[2:4]
        qt, qdt = q - r[0:2], qd - r[2:4]
        s = qdt + LAMBDA * qt
        Yr = Y(q, qd, r[2:4] - LAMBDA * qt, r[4:6] - LAMBDA * qdt)
        np.testing.assert_allclose(got, np.linalg.solve(T, -GAMMA @ Yr.T @ s), rtol=1e-10, atol=1e-12)
        a_hat = T @ xc + OFFSET
        u = np.asarray(law.command(y, xc, [], r)).ravel()
        np.testing.assert_allclose(u, Yr @ a_hat - KD * s, rtol=1e-10, atol=1e-10)


@pytest.fixture(scope="module")
def book_run(tmp_path_factory):
    text = SPEC.read_text().replace("duration: 3.0", "duration: 0.6")
    path = Path(tmp_path_factory.mktemp("book")) / "short.yaml"
    path.write_text(text)
    return run(load_spec(path))


def test_short_run_agrees_with_an_independent_integration(book_run):
    from scipy.integrate import solve_ivp

    sim = book_run.simulation
    t = np.asarray(sim.time, dtype=float)
    z0 = np.zeros(8)  # at rest at q = 0, a^(0) = 0 (the book's start)
    sol = solve_ivp(field, (t[0], t[-1]), z0, method="DOP853", rtol=1e-11, atol=1e-12, t_eval=t[::100])
    assert sol.success
    q = np.asarray(sim.state, dtype=float)[::100][:, list(sim.positions)]
    a_hat = estimates(sim, ("Izz1", "Izz2", "mcx2", "mcy2"))[::100] @ T.T + OFFSET
    np.testing.assert_allclose(q, sol.y[0:2].T, atol=1e-9)  # measured 8e-13 rad
    np.testing.assert_allclose(a_hat, sol.y[4:8].T, atol=1e-9)  # measured 9e-12
    assert np.max(np.abs(sol.y[4:8])) > 0.1  # the estimates move: the comparison is not of zeros


def test_starting_estimates_warned_and_tracking_judged_decreasing(book_run):
    warnings = [w for w in book_run.warnings if w.startswith("Physically impossible starting estimate")]
    assert any("Izz1 = -2" in w and "not positive semidefinite" in w for w in warnings)
    assert any("link 2" in w and "triangle inequality" in w for w in warnings)
    assert book_run.to_json()["warnings"] == list(book_run.warnings)


def test_error_figure_draws_the_judged_window_maxima(book_run):
    """The short run holds less than two periods: a tenth of the run is the window; the figure's dashed steps are
    the check's window maxima."""
    from designkit.display import svg
    from designkit.families.adaptive_computed_torque.figures import _draw_error, error_figure

    check = next(c for c in book_run.checks if c.name == "tracking_convergence")
    c = check.certificate
    assert c["window_s"] == pytest.approx(0.06) and c["window_from"] == "a tenth of the run"
    fig, _ = _draw_error(book_run)
    steps = [a for a in fig.findobj(lambda a: svg.tag_key(a.get_gid()) == "envelope")]
    assert len(steps) == 2
    for line, row in zip(steps, c["window_maxima_rad"], strict=True):
        np.testing.assert_array_equal(line.get_ydata()[::2], row)
    e = np.abs(np.asarray(book_run.simulation.reference)[:, :, 0]
               - np.asarray(book_run.simulation.state)[:, :2])
    assert np.max(c["window_maxima_rad"]) == pytest.approx(np.max(e), rel=0, abs=0)
    assert "Dashed: the largest |e|" in error_figure(book_run).caption
