"""The runs: the band invariant at random plants of the box, an event-driven scipy reference of the ideal sliding
motion, the sliding pole, the chattering against the step, the boundary layer, a square wave, the weak relay."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from designkit.families.sliding_mode.measure import measure
from tests.families.sliding_mode.common import BOX, check, run_text, spec_text

C, XI = 5.0, 1.0


def _s_of(sim) -> np.ndarray:
    """s = x2 + c (x1 - xD) from the recorded states (not the law's recorded signal)."""
    return sim.state[:, 1] + C * (sim.state[:, 0] - sim.reference[:, 0, 0])


def _sdot_max(design, e_max: float, band: float) -> float:
    """max |s'| from the link ODE on a grid of the box (corners included), |e| <= e_max, |s| <= band."""
    g = design.gains
    worst = 0.0
    for Km, tau in itertools.product(np.linspace(*BOX["Km"], 5), np.linspace(*BOX["tau"], 5)):
        e, s = np.meshgrid(np.linspace(-e_max, e_max, 41), [-band, band])
        x2 = s - C * e
        for psi, sign, xi in itertools.product((g["alpha"], g["beta"]), (-1, 1), (-XI, XI)):
            u = -psi * e - g["M"] * sign
            worst = max(worst, float(np.max(np.abs(C * x2 - x2 / tau + Km / tau * (u + xi)))))
    return worst


def _assert_invariant(sim, design) -> tuple[float, float]:
    """|s| enters the band dt * max|s'| and never leaves it; returns (reaching time, band)."""
    s = _s_of(sim)
    e = sim.state[:, 0] - sim.reference[:, 0, 0]
    band = sim.settings["dt"] * _sdot_max(design, max(1.0, float(np.max(np.abs(e)))), design.data.band)
    inside = np.flatnonzero(np.abs(s) <= band)
    assert inside.size, "never reached the band"
    k = int(inside[0])
    assert np.max(np.abs(s[k:])) <= band * (1 + 1e-9)
    return float(sim.time[k]), band


@pytest.fixture(scope="module")
def simulator(link_result):
    from designkit.simulation.run import build

    return build(link_result.loaded.spec, link_result.design, plant=link_result.plant, expected_runs=8)


def test_the_band_is_invariant_at_random_interior_plants(simulator, link_result):
    rng = np.random.default_rng(2024)
    plants = [dict(Km=rng.uniform(*BOX["Km"]), tau=rng.uniform(*BOX["tau"])) for _ in range(5)]
    plants.append({"Km": BOX["Km"][0], "tau": BOX["tau"][1]})  # the slowest, weakest corner
    for p in plants:
        sim = simulator.run(parameters=p)
        t_reach, _ = _assert_invariant(sim, link_result.design)
        assert t_reach < 1.0  # reached before the perturbation steps in
        e = sim.state[:, 0] - sim.reference[:, 0, 0]
        assert abs(e[-1]) < 1e-3  # and the perturbation was rejected without an integral


def _ideal(design, Km: float, tau: float, A: float = 1.0):
    """Event-driven reference: the link under the alpha structure and the relay from rest at e = -A until s = 0
    (scipy, events on e = 0 switch psi), then the ideal sliding motion e = e_r exp(-c (t - t_r))."""
    g = design.gains
    a, b = 1 / tau, Km / tau

    def rhs(_t, z, psi, sign):
        e, v = z
        return [v, -a * v + b * (-psi * e - g["M"] * sign)]

    def on_s(_t, z, *_):
        return z[1] + C * z[0]

    def on_e(_t, z, *_):
        return z[0]

    on_s.terminal = on_e.terminal = True
    z, t0 = np.array([-A, 0.0]), 0.0
    while True:
        s = z[1] + C * z[0]
        psi = g["alpha"] if z[0] * s > 0 else g["beta"]
        sol = solve_ivp(rhs, (t0, 5.0), z, args=(psi, np.sign(s)), events=(on_s, on_e), rtol=1e-11, atol=1e-13)
        if sol.t_events[0].size:
            t_r, z_r = float(sol.t_events[0][0]), sol.y_events[0][0]
            sdot = C * z_r[1] + rhs(0, z_r, psi, np.sign(s))[1]
            return t_r, float(z_r[0]), abs(sdot)
        t0, z = float(sol.t_events[1][0]), sol.y_events[1][0] + np.array([1e-12, 0.0])


@pytest.mark.parametrize("plant", [(2.0, 0.5), (1.7, 0.41)], ids=["nominal", "interior"])
def test_run_against_the_event_driven_ideal_sliding_motion(plant, simulator, link_result):
    d = link_result.design
    sim = simulator.run(parameters=dict(zip(("Km", "tau"), plant, strict=True)))
    t_ideal, e_r, sdot = _ideal(d, *plant)
    t_run, band = _assert_invariant(sim, d)
    dt = sim.settings["dt"]
    assert abs(t_run - t_ideal) <= band / sdot + 2 * dt  # entering the band at most band/|s'| before s = 0
    t = sim.time
    after = t >= t_ideal + 0.01
    e = sim.state[:, 0] - sim.reference[:, 0, 0]
    ideal = e_r * np.exp(-C * (t[after] - t_ideal))
    # on the line e' = -c e + s with |s| <= band: within band/c, plus the entry error decaying at c;
    # the perturbation (t >= 1 s) does not move the motion on the line
    tol = band / C + abs(C * e_r) * (band / sdot + 2 * dt) * np.exp(-C * (t[after] - t_ideal))
    assert np.all(np.abs(e[after] - ideal) <= tol + 1e-12)


def test_measured_sliding_pole_is_the_requested_one(link_result):
    c = check(link_result, "sliding_pole")
    assert c.passed is True and c.required is False
    assert c.achieved == pytest.approx(-C, rel=1e-2)
    sim = link_result.simulation
    e = np.abs(sim.state[:, 0] - sim.reference[:, 0, 0])
    t = sim.time
    run = measure(link_result.design, sim)
    window = (t > run.reaching_time + 0.02) & (e > 50 * run.band / C)  # an independent log-linear fit
    slope = np.polyfit(t[window], np.log(e[window]), 1)[0]
    assert slope == pytest.approx(-C, rel=1e-2)


def _sign_changes(s: np.ndarray) -> int:
    nz = s[s != 0]
    return int(np.count_nonzero(np.sign(nz[1:]) != np.sign(nz[:-1])))


def test_chattering_scales_with_the_step(link_result):
    """Half the band: half the step, about half the chattering amplitude and twice the switching frequency."""
    half = run_text(spec_text(chattering_band=0.0025))
    runs = [measure(r.design, r.simulation) for r in (link_result, half)]
    dts = [r.simulation.settings["dt"] for r in (link_result, half)]
    assert dts[1] <= 0.5 * dts[0] * 1.01
    amp = runs[1].amplitude / runs[0].amplitude
    freq = runs[1].switching_frequency / runs[0].switching_frequency
    assert 0.3 < amp < 0.7 and 1.5 < freq < 2.5
    for r, m in zip((link_result, half), runs, strict=True):
        s = _s_of(r.simulation)
        k = m.reach[0]
        assert _sign_changes(s[k:]) == m.switches  # the count, independently
        assert m.switching_frequency <= 1 / r.simulation.settings["dt"]
        assert check(r, "sliding_band").passed is True
        # a chattering that scales with the step is judged as physics: its rate is the step's, not the loop's
        chatter = check(r, "chattering")
        assert chatter.passed is False and chatter.required is False and "integration step" in chatter.detail


def test_boundary_layer_stops_the_switching_and_leaves_the_layer_error():
    eps = 0.05
    r = run_text(spec_text(boundary_layer=eps))
    d, sim = r.design, r.simulation
    m = measure(d, sim)
    assert m.band == eps and check(r, "sliding_band").passed is True
    s = _s_of(sim)
    t = sim.time
    assert np.max(np.abs(s[m.reach[0]:])) <= eps
    late = t >= 2.0  # well after the perturbation (t = 1 s): s settles inside the layer, no switching
    assert _sign_changes(s[late]) == 0
    g = d.gains
    s_eq = XI / (g["alpha"] / C + g["M"] / eps)  # x2 = 0, s = c e: -alpha e - M s/eps + xi = 0
    assert s[-1] == pytest.approx(s_eq, rel=1e-3)
    assert (sim.state[-1, 0] - sim.reference[-1, 0, 0]) == pytest.approx(s_eq / C, rel=1e-3)
    assert d.data.max_step == pytest.approx(eps / (10 * d.data.sdot_max))


def _square(**controller):
    text = spec_text(drop=("requirements:",), **controller).replace(
        "  duration: 3.0\n", "  duration: 4.0\n  trajectory: {kind: square, amplitude: 0.5, period: 2.0}\n")
    return run_text(text)


def test_square_wave_minimal_switching_reaches_too_slowly_against_the_perturbation():
    """The minimal-switching alpha reaches the line in 0.3 s on the up moves (the perturbation helps) but not
    within the half period on the down move it opposes: the run does not slide there, and the checks say so."""
    r = _square()
    m = measure(r.design, r.simulation)
    assert m.cut and len(m.segments) == 4  # the run ends on a switch: the one-sample last segment is left out
    assert m.reach[0] is not None and m.reach[1] is None and m.reach[2] is not None
    assert check(r, "reaching_time").passed is False and "segment 2 of 4" in check(r, "reaching_time").detail
    assert check(r, "sliding_band").passed is False
    from designkit.families.sliding_mode.diagnoses import diagnose

    cause, fix = diagnose(r, check(r, "sliding_band"))
    assert cause.startswith("Segment 2 (from t = 1 s") and "reaching_frequency" in fix


def test_square_wave_with_a_reaching_frequency_slides_after_every_switch():
    r = _square(reaching_frequency=5)
    d = r.design
    assert d.gains["alpha"] == pytest.approx(25 * BOX["tau"][1] / BOX["Km"][0], rel=1e-7)  # b alpha >= 5^2
    assert d.data.e_max == 1.0  # the error jumps by 2 A at a switch
    m = measure(d, r.simulation)
    assert m.reached and max(m.reaching_times) < 0.2
    assert check(r, "sliding_band").passed is True and check(r, "reaching_time").passed is True
    s_all = _s_of(r.simulation)
    for (a, b), k in zip(m.segments, m.reach, strict=True):
        assert np.max(np.abs(s_all[a:b][k:])) <= m.band * (1 + 1e-9)


def test_weak_relay_leaves_the_line_and_settles_off_the_reference(weak_result):
    band = check(weak_result, "sliding_band")
    assert band.passed is False and "leaves it" in band.detail and band.margin < 0
    sim = weak_result.simulation
    e_end = sim.state[-1, 0] - sim.reference[-1, 0, 0]
    e_star = (XI - 0.8) / weak_result.design.gains["alpha"]  # x2 = 0, e s > 0: -alpha e - M + xi = 0
    assert e_end == pytest.approx(e_star, rel=0.05)
    assert check(weak_result, "steady_state_error").passed is False
    assert not weak_result.verified
