"""The design: the LP's gains against the closed form, the margins at every corner, the law, the step, bad input."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from designkit.families.sliding_mode.conditions import SlidingGains, sdot_bound
from designkit.families.sliding_mode.design_lp import design_gains
from tests.cli_input import assert_bad_input
from tests.families.sliding_mode.common import BOX, check, spec_text

C, XI, MARGIN, E_MAX = 5.0, 1.0, 0.2, 1.0
CORNERS = list(itertools.product(BOX["Km"], BOX["tau"]))


def closed_form(c: float, xi: float, m: float) -> tuple[float, float, float]:
    """The tightest corner bound of each gain, written in (a, b) = (1/tau, Km/tau) as the notes do."""
    alpha, beta = -np.inf, np.inf
    for Km, tau in CORNERS:
        a, b = 1 / tau, Km / tau
        k = (a - c) * c / b
        alpha = max(alpha, (1 + m) * a * a / (4 * b), k + m * abs(k))
        beta = min(beta, k - m * (c + c * c * tau) / Km)
    return alpha, beta, (1 + m) * xi


def test_lp_gains_are_the_closed_form_optimum():
    lp = design_gains(C, BOX, XI, MARGIN, E_MAX)
    alpha, beta, M = closed_form(C, XI, MARGIN)
    assert lp.status == "optimal"
    assert (lp.alpha, lp.beta, lp.M) == pytest.approx((alpha, beta, M), rel=1e-7)
    assert lp.weights == (E_MAX, -E_MAX, 2.0)
    assert lp.objective == pytest.approx(E_MAX * (alpha - beta) + 2 * M, rel=1e-7)


@pytest.mark.parametrize("c", [0.5, 2.0, 5.0, 30.0])
def test_lp_gains_meet_every_margin_at_every_corner(c):
    lp = design_gains(c, BOX, XI, MARGIN, E_MAX)
    for Km, tau in CORNERS:
        a, b = 1 / tau, Km / tau
        k = (a - c) * c / b
        assert lp.alpha >= (1 + MARGIN) * a * a / (4 * b) * (1 - 1e-12)
        assert lp.alpha > k and lp.beta < k
        assert Km * lp.beta <= c * (1 - c * tau) - MARGIN * (c + c * c * tau) + 1e-9
    assert lp.M >= (1 + MARGIN) * XI


def test_a_given_gain_is_kept_and_the_others_designed():
    lp = design_gains(C, BOX, XI, MARGIN, E_MAX, fixed={"M": 0.8, "alpha": 3.0})
    _, beta, _ = closed_form(C, XI, MARGIN)
    relay = lp.M
    assert relay == pytest.approx(0.8, rel=1e-9)
    assert lp.alpha == pytest.approx(3.0, rel=1e-9)
    assert lp.beta == pytest.approx(beta, rel=1e-7)
    assert lp.fixed == ("M", "alpha")


def test_a_given_gain_near_the_smallest_float_is_kept():
    """``beta: 2.3e-308``: the scaled row's norm would underflow in a plain sum of squares."""
    lp = design_gains(C, BOX, XI, MARGIN, E_MAX, fixed={"beta": 2.3e-308})
    alpha, _, relay = closed_form(C, XI, MARGIN)
    designed = lp.M
    assert lp.beta == pytest.approx(2.3e-308, rel=1e-9)
    assert lp.alpha == pytest.approx(alpha, rel=1e-7)
    assert designed == pytest.approx(relay, rel=1e-7)


def test_torque_rows_bound_the_command_or_are_dropped():
    kept = design_gains(C, BOX, XI, MARGIN, E_MAX, u_max=20.0)
    assert kept.torque_rows == "kept"
    assert kept.alpha * E_MAX + kept.M <= 20.0 + 1e-7 and -kept.beta * E_MAX + kept.M <= 20.0 + 1e-7
    _, beta, M = closed_form(C, XI, MARGIN)
    dropped = design_gains(C, BOX, XI, MARGIN, E_MAX, u_max=-beta * E_MAX + M - 0.5)  # below what beta needs
    assert dropped.torque_rows.startswith("dropped")
    assert dropped.beta == pytest.approx(beta, rel=1e-7)


def test_sdot_bound_against_a_dense_grid_of_the_plant_ode():
    """max |s'| over the box, |e| <= e_max, |s| <= band, both structures and relay signs, from the ODE."""
    g = SlidingGains(*closed_form(C, XI, MARGIN), C)
    band = 5e-3
    bound = sdot_bound(g, XI, BOX, E_MAX, band)
    Km, tau, e, s, xi = np.meshgrid(np.linspace(*BOX["Km"], 9), np.linspace(*BOX["tau"], 9),
                                    np.linspace(-E_MAX, E_MAX, 21), np.linspace(-band, band, 5), [-XI, XI],
                                    indexing="ij")
    x2 = s - C * e
    worst = 0.0
    for psi in (g.alpha, g.beta):
        for sign in (-1.0, 1.0):
            u = -psi * e - g.M * sign
            sdot = C * x2 - x2 / tau + Km / tau * (u + xi)
            worst = max(worst, float(np.max(np.abs(sdot))))
    assert worst <= bound * (1 + 1e-12)
    assert worst >= 0.97 * bound  # the corner, |e| = e_max and |s| = band are on the grid: nearly attained


def test_design_gains_units_step_and_law(link_result):
    d = link_result.design
    assert list(d.gains) == ["alpha", "beta", "M", "c"]
    assert {k: d.gains.unit(k) for k in d.gains} == {"alpha": "N*m/rad", "beta": "N*m/rad", "M": "N*m", "c": "1/s"}
    assert (d.gains["alpha"], d.gains["beta"], d.gains["M"]) == pytest.approx(closed_form(C, XI, MARGIN), rel=1e-7)
    info = d.data
    assert info.band == pytest.approx(1e-3 * C * E_MAX)
    assert info.max_step * info.sdot_max == pytest.approx(info.band)
    law = d.law
    assert law.discontinuous and law.max_step == pytest.approx(info.max_step) and law.signal_names == ("s", "psi")
    assert d.linearization.kind == "none" and d.closed_loop is None and d.input_loop is None
    assert link_result.simulation.settings["dt"] <= law.max_step
    rng = np.random.default_rng(2)
    for _ in range(50):  # the CasADi law against the notes' law written here
        y, r = rng.normal(0, 2, 2), rng.normal(0, 1)
        e = y[0] - r
        s = y[1] + C * e
        psi = d.gains["alpha"] if e * s > 0 else d.gains["beta"]
        want = -psi * e - d.gains["M"] * np.sign(s)
        got = float(law.command(y, [], [], [r, 0.0, 0.0]))
        assert got == pytest.approx(want, rel=1e-12, abs=1e-12)
        assert float(law.signals(y, [], [], [r, 0.0, 0.0])[0]) == pytest.approx(s)


def test_no_linear_check_is_offered(link_result):
    from designkit.verification.suite import GENERIC, applicable

    spec, d = link_result.loaded.spec, link_result.design
    offered = applicable(d, spec, link_result.simulation, rules=list(GENERIC))
    for name in ("pole_placement", "routh_hurwitz", "lyapunov", "loop_margins", "robustness", "designed_loop",
                 "robust_box", "frozen_final"):
        assert name not in offered
    names = {c.name for c in link_result.checks}
    assert not names & {"pole_placement", "lyapunov", "loop_margins", "robust_vertices", "robust_grid",
                        "common_lyapunov", "designed_loop"}
    assert "overshoot" in names and "sliding_existence" in names


def test_widened_box_and_given_bound(tmp_path):
    from designkit.families import synthesize
    from designkit.schema.loader import parse_spec

    text = spec_text(perturbation_bound=1.5).replace("tau: [0.35, 0.65]", "tau: [0.55, 0.65]")
    d = synthesize(parse_spec(text).spec)
    info = d.data
    assert info.box["tau"] == (0.5, 0.65)  # widened to hold the nominal tau = 0.5
    assert info.xi_bar == 1.5 and d.gains["M"] == pytest.approx(1.8, rel=1e-7)
    assert any("widened" in n for n in d.notes)


BAD = {
    "pole at 0": ({"replace": ("sliding_poles: [-5]", "sliding_poles: [0]")}, "controller.sliding_poles[0]: must have "
                  "negative real part"),
    "pole in the RHP": ({"replace": ("sliding_poles: [-5]", "sliding_poles: [2]")}, "controller.sliding_poles[0]"),
    "complex pole": ({"replace": ("sliding_poles: [-5]", "sliding_poles: ['-5+1j']")}, "controller.sliding_poles[0]: "
                     "must be real"),
    "two poles": ({"replace": ("sliding_poles: [-5]", "sliding_poles: [-5, -6]")}, "controller.sliding_poles: must "
                  "list exactly 1 pole"),
    "M zero": ({"M": 0}, "controller.M: must be positive"),
    "M negative": ({"M": -1}, "controller.M: must be positive"),
    "quintic reference": ({"replace": ("  duration: 3.0\n", "  duration: 3.0\n  trajectory: {kind: quintic}\n")},
                          "simulation.trajectory.kind"),
    "dt above max_step": ({"replace": ("  duration: 3.0\n", "  duration: 3.0\n  dt: 0.001\n")},
                          "simulation.dt: 0.001 s is coarser than"),
    "Km interval with 0": ({"replace": ("Km: [1.4, 2.6]", "Km: [0, 2.6]")}, "plant.uncertainty.Km: must be positive"),
    "negative tau": ({"replace": ("tau: [0.35, 0.65]", "tau: [-0.1, 0.65]")}, "plant.uncertainty.tau: must be "
                     "positive"),
    "no perturbation bound": ({"drop": ("perturbation:",)}, "controller.perturbation_bound: give sup |xi|"),
    "bound below the run": ({"perturbation_bound": 0.5}, "controller.perturbation_bound: 0.5 N*m is below"),
    "anti-windup": ({"replace": ("  duration: 3.0\n", "  duration: 3.0\n  anti_windup: {kind: threshold, value: 0.1}"
                                 "\n")}, "simulation.anti_windup"),
    "band and layer": ({"chattering_band": 0.01, "boundary_layer": 0.01}, "controller.boundary_layer: give"),
    "band outside the strip": ({"chattering_band": 0.1}, "controller.chattering_band: 0.1 rad/s is not inside"),
    "zero margin": ({"replace": ("margin: 0.2", "margin: 0")}, "controller.margin"),
    "plant change to Km < 0": ({"replace": ("  duration: 3.0\n", "  duration: 3.0\n  plant_change: {time: 1.0, "
                                            "values: {Km: -1.0}}\n")}, "simulation.plant_change.values.Km"),
}


@pytest.mark.parametrize("case", list(BAD), ids=list(BAD))
def test_bad_input_exits_2_with_the_key_path(case, tmp_path, capsys):
    change, message = BAD[case]
    change = dict(change)
    old_new = change.pop("replace", None)
    drop = change.pop("drop", ())
    text = spec_text(drop=drop, **change)
    if old_new is not None:
        assert old_new[0] in text
        text = text.replace(*old_new)
    assert_bad_input(tmp_path, capsys, text, message)


def test_the_design_notes_say_where_the_bound_came_from(link_result):
    assert any("simulation.perturbation.value" in n for n in link_result.design.notes)
    assert check(link_result, "sliding_perturbation").passed is True
