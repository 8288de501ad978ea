"""Astrom and Wittenmark's MIT-rule example (Adaptive Control, 2nd ed., Example 5.2, Figs. 5.4 and 5.5) through the
pipeline, against the same loop written by hand here and integrated by scipy."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from designkit.families.mrac.report import json as family_json
from designkit.pipeline import run
from designkit.schema.loader import load_spec
from tests.families.mrac.conftest import SPECS

A, B, AM, BM = 1.0, 0.5, 2.0, 2.0
SPEC_GAMMA = {"mrac-mit-first-order-slow.yaml": 0.2, "mrac-mit-first-order.yaml": 1.0,
              "mrac-mit-first-order-fast.yaml": 5.0}
Y_TOL, THETA_TOL = 1e-8, 1e-8
"""Largest absolute differences allowed against DOP853 at rtol 1e-11 between the square wave's jumps (measured:
2.1e-11, 5.8e-11 and 7.5e-11 on y, 1.6e-11, 9.6e-11 and 3.5e-10 on theta at gamma = 0.2, 1 and 5)."""


def _by_hand(gamma: float, t_eval: np.ndarray) -> np.ndarray:
    """y, ym, theta1, theta2 of the book's loop: plant, model, the filters am/(p + am) of uc and y, the MIT rule."""

    def f(_t, z, uc):
        y, ym, fuc, fy, th1, th2 = z
        e = y - ym
        return [-A * y + B * (th1 * uc - th2 * y), -AM * ym + BM * uc, -AM * fuc + AM * uc, -AM * fy + AM * y,
                -gamma * fuc * e, gamma * fy * e]

    z = np.zeros(6)
    out = np.empty((t_eval.size, 4))
    for k in range(10):  # the square wave: +1 over [20 j, 20 j + 10), -1 over the next 10 s
        lo, hi = 10.0 * k, 10.0 * (k + 1)
        mask = (t_eval >= lo) & (t_eval <= hi) if k == 9 else (t_eval >= lo) & (t_eval < hi)
        sol = solve_ivp(f, (lo, hi), z, method="DOP853", rtol=1e-11, atol=1e-13, dense_output=True,
                        args=(1.0 if k % 2 == 0 else -1.0,))
        if mask.any():
            out[mask] = sol.sol(t_eval[mask])[[0, 1, 4, 5]].T
        z = sol.y[:, -1]
    return out


@pytest.fixture(scope="module", params=sorted(SPEC_GAMMA))
def textbook(request):
    result = run(load_spec(SPECS / request.param))
    return SPEC_GAMMA[request.param], result


def test_the_pipeline_integrates_the_books_loop(textbook):
    gamma, result = textbook
    sim = result.simulation
    t = np.asarray(sim.time, dtype=float)
    ref = _by_hand(gamma, t)
    y = np.asarray(sim.state, dtype=float)[:, sim.positions[0]]
    theta = np.column_stack([np.asarray(sim.signals[n], dtype=float) for n in ("theta1", "theta2")])
    assert np.max(np.abs(y - ref[:, 0])) < Y_TOL
    assert np.max(np.abs(np.asarray(sim.signals["ym"]) - ref[:, 1])) < Y_TOL
    assert np.max(np.abs(theta - ref[:, 2:])) < THETA_TOL


def test_the_ideal_parameters_and_what_the_run_reports(textbook):
    gamma, result = textbook
    adaptation = family_json(result)["adaptation"]
    # theta1 = bm/b, theta2 = (am - a)/b: the loop b theta1/(s + a + b theta2) is bm/(s + am)
    assert adaptation["matching"] == pytest.approx([BM / B, (AM - A) / B], rel=1e-12)
    assert adaptation["initial"] == [0.0, 0.0]
    ref = _by_hand(gamma, np.array([0.0, 100.0]))
    assert adaptation["final"] == pytest.approx(ref[-1, 2:].tolist(), abs=THETA_TOL)
    err = adaptation["error_rms"]
    assert err["adaptive"] < err["fixed"]



def test_the_figure_draws_the_output_and_the_parameters(textbook):
    from designkit.display.svg import svg_keys
    from designkit.families.mrac.figures import outputs_figure, parameters_figure
    from designkit.families.mrac.regressor_figures import regressor_figure

    _, result = textbook
    fig = regressor_figure(result)
    assert fig.filename == "fig-mrac-regressor.svg"
    assert {"command", "model", "output", "theta", "ideal"} <= set(svg_keys(fig.svg))
    final = [float(result.simulation.signals[n][-1]) for n in ("theta1", "theta2")]
    assert f"{final[0]:.4g}" in fig.caption and "4, 2" in fig.caption
    assert outputs_figure(result) is None and parameters_figure(result) is None  # the coefficient form's
