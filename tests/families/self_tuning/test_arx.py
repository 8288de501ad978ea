"""The ARX self-tuner in general orders against independent computations: scipy's ZOH model, a NumPy loop of
recursive least squares and the Diophantine equation written out by hand and solved by ``numpy.linalg.solve``,
python-control's discrete closed loop."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.signal import cont2discrete

from designkit.errors import SpecError
from designkit.families import synthesize
from designkit.families.self_tuning.arx import Orders, place, true_arx
from designkit.families.self_tuning.runs import samples
from designkit.pipeline import plant as plant_of
from designkit.schema.loader import load_spec, parse_spec
from designkit.simulation.run import build
from tests.families.self_tuning.oracles import closed_loop_poles

SPEC = Path(__file__).resolve().parents[3] / "specs" / "selftune-aw-indirect.yaml"
H = 0.5
# Astrom & Wittenmark, Adaptive Control (2nd ed.), section 3.3: 1/(s(s+1)) sampled at h = 0.5 s (4 decimals)
BOOK = {"a1": -1.6065, "a2": 0.6065, "b0": 0.1065, "b1": 0.0902, "am1": -1.3205, "am2": 0.4966}


def _zoh_tf(num, den, h):
    b, a, _ = cont2discrete((num, den), h, method="zoh")
    return np.squeeze(b), np.asarray(a, dtype=float)


@pytest.fixture(scope="module")
def aw_run():
    loaded = load_spec(SPEC)
    true = plant_of(loaded)
    design = synthesize(loaded.spec, true)
    return build(loaded.spec, design, plant=true).run(), design


def test_book_numbers_are_scipys_zoh():
    b, a = _zoh_tf([1.0], [1.0, 1.0, 0.0], H)
    assert b[0] == pytest.approx(0.0, abs=1e-15)
    got = {"a1": a[1], "a2": a[2], "b0": b[1], "b1": b[2]}
    for k, v in got.items():
        assert v == pytest.approx(BOOK[k], abs=5e-5), k
    w, zeta = 1.0, 0.7
    am = np.real(np.poly(np.exp(np.roots([1.0, 2 * zeta * w, w * w]) * H)))
    assert am[1] == pytest.approx(BOOK["am1"], abs=5e-5) and am[2] == pytest.approx(BOOK["am2"], abs=5e-5)
    # the family's exact ARX of the same plant (its own matrix exponential) is scipy's
    F, G, C, D = np.array([[0.0, 1.0], [0.0, -1.0]]), np.array([0.0, 1.0]), np.array([[1.0, 0.0]]), np.zeros((1, 1))
    assert true_arx(F, G, C, D, H, Orders(2, 2, 1)) == pytest.approx([a[1], a[2], b[1], b[2]], rel=1e-12)


def _diophantine_by_hand(a1, a2, b0, b1, c1, c2, c3):
    """A R + B S = Am Ao with R = q + r1, S = s0 q + s1 (Ao = q): the q^2, q^1, q^0 coefficients."""
    M = np.array([[1.0, b0, 0.0], [a1, b1, b0], [a2, 0.0, b1]])
    rhs = np.array([c1 - a1, c2 - a2, c3])
    return np.linalg.solve(M, rhs), np.linalg.cond(M)


def test_the_family_run_is_a_numpy_self_tuner(aw_run):
    """Estimates and controller polynomials at every sample against a NumPy loop on scipy's ZOH model."""
    sim, design = aw_run
    s = samples(sim, design)
    idx = np.searchsorted(np.asarray(sim.time), s.t)
    r = np.asarray(sim.desired)[idx, 0]
    Ad, Bd, Cd, Dd, _ = cont2discrete((np.array([[0.0, 1.0], [0.0, -1.0]]), np.array([[0.0], [1.0]]),
                                       np.array([[1.0, 0.0]]), np.zeros((1, 1))), H, method="zoh")
    w, zeta = 1.0, 0.7
    am = np.real(np.poly(np.exp(np.roots([1.0, 2 * zeta * w, w * w]) * H)))
    c = np.polymul(am, [1.0, 0.0])  # Am Ao, Ao = q
    theta = np.array([0.0, 0.0, 0.01, 0.2])
    P = 1e4 * np.eye(4)
    x = np.zeros(2)
    y_past, u_past = [0.0, 0.0], [0.0, 0.0]
    coefs = None
    thetas, controllers, conds = [], [], []
    for k in range(len(s.t)):
        y = float((Cd @ x)[0])
        if k > 0:
            phi = np.array([-y_past[0], -y_past[1], u_past[0], u_past[1]])
            K = P @ phi / (1.0 + phi @ P @ phi)
            theta = theta + K * (y - phi @ theta)
            P = P - np.outer(K, phi @ P)
            P = 0.5 * (P + P.T)
        a1, a2, b0, b1 = theta
        (r1, s0, s1), cond = _diophantine_by_hand(a1, a2, b0, b1, c[1], c[2], c[3])
        t0 = am.sum() / (b0 + b1)
        coefs = (r1, s0, s1, t0)
        y_prev = y_past[0] if k > 0 else y
        u = -r1 * u_past[0] + t0 * r[k] - s0 * y - s1 * y_prev
        thetas.append(theta.copy())
        controllers.append(coefs)
        conds.append(cond)
        x = Ad @ x + Bd[:, 0] * u
        y_past, u_past = [y, y_past[0]], [u, u_past[0]]
    thetas, controllers = np.array(thetas), np.array(controllers)
    scale = np.max(np.abs(thetas), axis=0)
    assert np.max(np.abs(s.theta - thetas) / scale) < 1e-6
    got = np.column_stack([s.coefs[:, 0], s.coefs[:, 1], s.coefs[:, 2], s.coefs[:, 3]])  # R1, S0, S1, T0
    assert np.max(np.abs(got - controllers) / np.max(np.abs(controllers), axis=0)) < 1e-6
    assert np.all(s.coefs[:, 4] == 0.0)  # T1: T = t0 q
    from designkit.families.self_tuning.runs import sylvester_condition

    assert sylvester_condition(s, design) == pytest.approx(np.array(conds), rel=1e-6)


def test_estimates_converge_to_the_book_model(aw_run):
    sim, design = aw_run
    s = samples(sim, design)
    final = s.theta[-1]
    b, a = _zoh_tf([1.0], [1.0, 1.0, 0.0], H)
    assert final == pytest.approx([a[1], a[2], b[1], b[2]], rel=2e-3)
    assert final == pytest.approx([BOOK["a1"], BOOK["a2"], BOOK["b0"], BOOK["b1"]], abs=1e-3)


def test_design_at_the_true_model_places_am_ao_by_python_control():
    b, a = _zoh_tf([1.0], [1.0, 1.0, 0.0], H)
    theta = [a[1], a[2], b[1], b[2]]
    am = np.real(np.poly(np.exp(np.roots([1.0, 1.4, 1.0]) * H)))
    p = place(theta, Orders(2, 2, 1), am, [1.0, 0.0], cancel=False)
    (r1, s0, s1), cond = _diophantine_by_hand(*theta, *np.polymul(am, [1.0, 0.0])[1:])
    assert pytest.approx([1.0, r1], rel=1e-10) == p.R and pytest.approx([s0, s1], rel=1e-10) == p.S
    assert p.condition == pytest.approx(cond, rel=1e-10)
    poles = closed_loop_poles(b[1:], a, np.array(p.R), np.array(p.S), H)
    assert poles == pytest.approx(np.sort_complex(np.r_[np.roots(am), 0.0]), abs=1e-9)


@pytest.mark.parametrize("ao", [[1.0], [1.0, 0.0], [1.0, -0.3]])
def test_zero_cancellation_puts_the_zero_in_the_loop(ao):
    """Zeros cancelled: the loop's poles are those of Am, Ao and the plant's zero (python-control), the loop from r
    is Am(1)/Am (its static gain one)."""
    b, a = _zoh_tf([1.0], [1.0, 1.0, 0.0], H)
    theta = [a[1], a[2], b[1], b[2]]
    am = np.real(np.poly(np.exp(np.roots([1.0, 1.4, 1.0]) * H)))
    p = place(theta, Orders(2, 2, 1), am, ao, cancel=True)
    poles = closed_loop_poles(b[1:], a, np.array(p.R), np.array(p.S), H)
    want = np.sort_complex(np.r_[np.roots(am), np.roots(ao), -b[2] / b[1]])
    assert poles == pytest.approx(want, abs=1e-8)
    import control

    G = control.tf(b[1:], a, H)
    loop = control.feedback(G * control.tf(p.S, p.R, H), 1) * control.tf(p.T, p.S, H)
    assert float(np.real(control.dcgain(loop))) == pytest.approx(1.0, rel=1e-9)


THIRD = """\
name: arx-third
plant: {{kind: {kind}, {plant}}}
controller: {{kind: self_tuning, sampling_period: 0.5, forgetting: 1.0, initial_covariance: 1.0e6,
             poles: [-1, -1.2, -1.5], excitation_window: 30{extra}}}
simulation: {{duration: 60, trajectory: {{kind: prbs, amplitude: 1, bit: 1.5, seed: 2}}}}
"""


def _run(text):
    from designkit.pipeline import run

    return run(parse_spec(text))


@pytest.mark.parametrize("kind, plant", [
    ("transfer_function", "num: [2, 1], den: [1, 3, 3, 1]"),
    ("state_space", "A: [[0, 1, 0], [0, 0, 1], [-1, -3, -3]], B: [[0], [0], [1]], C: [[1, 0, 1]]"),
])
def test_third_order_plants_converge_with_default_orders(kind, plant):
    """A third-order plant with a zero, default orders (3, 3, 1), wrong initial estimates: the estimates reach scipy's
    ZOH model and the true loop's poles are the roots of Am Ao.  (Six correlated regressors: the normalized excitation
    indicator stays below its threshold although the estimates converge, so it is not asserted.)"""
    text = THIRD.format(kind=kind, plant=plant, extra=", initial_estimates: [-2, 1, -0.2, 0.05, 0.05, 0.02]")
    res = _run(text)
    checks = {c.name: c for c in res.checks}
    # the state-space plant is the companion form of 1/(s + 1)^3 read through y = x1 + x3 = (1 + s^2) x1
    num = [2.0, 1.0] if kind == "transfer_function" else [1.0, 0.0, 1.0]
    b, a = _zoh_tf(num, [1.0, 3.0, 3.0, 1.0], 0.5)
    s = samples(res.simulation, res.design)
    assert s.theta[-1] == pytest.approx([*a[1:], *b[1:]], rel=1e-3)
    for name in ("characteristic_polynomial", "estimate_convergence", "true_loop"):
        assert checks[name].passed, (name, checks[name].detail)


def test_default_window_fits_a_long_sampling_period():
    """At h = 0.5 s the default excitation window is 20 samples (10 s), not refused."""
    spec = parse_spec(THIRD.format(kind="transfer_function", plant="num: [1], den: [1, 1, 0]", extra="").replace(
        ", excitation_window: 30", "").replace("-1, -1.2, -1.5", "-1, -1.2")).spec
    assert spec.controller.window == pytest.approx(10.0)
    link = parse_spec("name: l\nplant: {kind: link, Km: 1, tau: 1}\ncontroller: {kind: self_tuning, "
                      "sampling_period: 0.5, poles: [-1, -1.2]}\nsimulation: {duration: 40, trajectory: "
                      "{kind: square, amplitude: 1, period: 20}}\n").spec
    assert link.controller.window == pytest.approx(10.0)


@pytest.mark.parametrize("extra, path", [
    (", estimator: speed", "controller.estimator"),
    (", orders: {na: 3, nb: 3, d: 1}, initial_estimates: [1, 2]", "controller.initial_estimates"),
    (", design: pid", "controller.design"),
])
def test_bad_arx_input_names_the_key(extra, path):
    with pytest.raises(SpecError) as err:
        parse_spec(THIRD.format(kind="transfer_function", plant="num: [2, 1], den: [1, 3, 3, 1]", extra=extra))
    assert path in str(err.value)


@pytest.mark.parametrize("poly", ["[2, 0, 0]", "[1, -1.5, 0]"])
def test_an_observer_polynomial_not_monic_or_unstable_is_refused(poly):
    loaded = parse_spec(THIRD.format(kind="transfer_function", plant="num: [2, 1], den: [1, 3, 3, 1]",
                                     extra=f", observer: {{polynomial: {poly}}}"))
    with pytest.raises(SpecError, match="controller.observer.polynomial"):
        synthesize(loaded.spec, plant_of(loaded))


def test_a_plant_above_the_largest_default_order_needs_orders():
    den = "[" + ", ".join(["1"] * 10) + "]"
    text = THIRD.format(kind="transfer_function", plant=f"num: [1], den: {den}", extra="")
    with pytest.raises(SpecError, match="controller.orders"):
        parse_spec(text)


def test_too_few_poles_for_a_causal_controller_is_refused():
    text = THIRD.format(kind="transfer_function", plant="num: [2, 1], den: [1, 3, 3, 1]", extra="").replace(
        "poles: [-1, -1.2, -1.5]", "poles: [-1, -1.2]")
    with pytest.raises(SpecError, match="controller.poles.*causal"):
        parse_spec(text)


def test_orders_that_do_not_hold_the_plant_need_initial_estimates():
    text = THIRD.format(kind="transfer_function", plant="num: [2, 1], den: [1, 3, 3, 1]",
                        extra=", orders: {na: 2, nb: 2, d: 1}").replace("-1, -1.2, -1.5", "-1, -1.2")
    loaded = parse_spec(text)
    with pytest.raises(SpecError, match="controller.initial_estimates"):
        synthesize(loaded.spec, plant_of(loaded))


def test_orders_below_the_plant_leave_convergence_undecided():
    """A second-order ARX model on a third-order plant: no exact parameters exist, so the convergence and true-loop
    checks say so (undecided, not required); the estimated loop is still placed exactly."""
    text = THIRD.format(kind="transfer_function", plant="num: [2, 1], den: [1, 3, 3, 1]",
                        extra=", orders: {na: 2, nb: 2, d: 1}, initial_estimates: [-1, 0.3, 0.1, 0.1]").replace(
        "-1, -1.2, -1.5", "-1, -1.2")
    checks = {c.name: c for c in _run(text).checks}
    assert checks["estimate_convergence"].passed is None and not checks["estimate_convergence"].required
    assert checks["true_loop"].passed is None and not checks["true_loop"].required
    assert checks["characteristic_polynomial"].passed


def test_zero_cancellation_tracks_a_gain_change():
    """Zeros cancelled, the plant's gain doubled half-way: the estimates re-converge to scipy's model of the new
    plant and A R + B S is B+ Am Ao at every redesign."""
    text = """\
name: arx-change
plant: {kind: transfer_function, num: [K], den: [1, 1, 0], parameters: {K: 1.0}}
controller: {kind: self_tuning, sampling_period: 0.5, forgetting: 0.95, initial_covariance: 1.0e4,
             poles: [-0.7+0.714j, -0.7-0.714j], observer: {polynomial: [1, 0]}, zeros: cancel}
simulation: {duration: 80, trajectory: {kind: prbs, amplitude: 1, bit: 2, seed: 2},
             plant_change: {time: 40, values: {K: 2.0}}}
"""
    res = _run(text)
    checks = {c.name: c for c in res.checks}
    for name in ("characteristic_polynomial", "estimate_convergence", "parameter_step", "true_loop"):
        assert checks[name].passed, (name, checks[name].detail)
    b, a = _zoh_tf([2.0], [1.0, 1.0, 0.0], H)
    assert samples(res.simulation, res.design).theta[-1] == pytest.approx([a[1], a[2], b[1], b[2]], rel=0.05)


def test_the_arx_form_on_the_link_is_the_same_self_tuner(aw_run):
    """The link Km = 1, tau = 1 is 1/(s(s + 1)): the ARX form on it (not the link's default forms) estimates what the
    transfer function's run estimates."""
    text = SPEC.read_text().replace("plant:\n  kind: transfer_function\n  num: [1]\n  den: [1, 1, 0]",
                                    "plant: {kind: link, Km: 1.0, tau: 1.0}")
    assert "kind: link" in text
    loaded = parse_spec(text)
    true = plant_of(loaded)
    design = synthesize(loaded.spec, true)
    link = samples(build(loaded.spec, design, plant=true).run(), design)
    tf = samples(*aw_run)
    assert link.theta == pytest.approx(tf.theta, rel=1e-7, abs=1e-12)
