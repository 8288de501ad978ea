"""The feedforward/feedback structure: its ideal parameters against python-control's loop, its rules against the
equations integrated by scipy, its frozen loop against the design's poles, its refusals."""

from __future__ import annotations

import control
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from designkit.families import synthesize
from designkit.families.mrac.structure import matching
from designkit.pipeline import run
from designkit.schema.loader import parse_spec
from tests.cli_input import assert_bad_input

PLANTS = {  # (num, den, model num, model den): minimum-phase plants, models of the plant's relative degree
    "first order": ([0.5], [1, 1], [2], [1, 2]),
    "unstable, relative degree 1": ([3, 6], [1, 1, -2], [6], [1, 6]),
    "link as a transfer function": ([4], [0.5, 1, 0], [20], [1, 9, 20]),
    "third order, relative degree 2": ([2, 2], [1, 3, 0, -1], [25], [1, 7, 25]),
    "third-order model, relative degree 3": ([1], [1, 2, 3, 4], [60], [1, 9, 26, 24]),
}


def _loop(num, den, theta, lam):
    """uc -> y of u = theta1 uc - theta2 y - theta_y'(alpha/Lambda) y - theta_u'(alpha/Lambda) u by python-control."""
    G = control.tf(num, den)
    n = len(np.trim_zeros(np.asarray(den, dtype=float), "f")) - 1
    Lam = control.tf([1.0], list(lam))
    ty, tu = theta[2:2 + n - 1], theta[2 + n - 1:]
    Fy = sum((ty[j] * control.tf([1.0] + [0.0] * (n - 2 - j), [1.0]) for j in range(n - 1)), control.tf([0], [1]))
    Fu = sum((tu[j] * control.tf([1.0] + [0.0] * (n - 2 - j), [1.0]) for j in range(n - 1)), control.tf([0], [1]))
    D = 1 + Fu * Lam  # u (1 + theta_u alpha/Lambda) = theta1 uc - (theta2 + theta_y alpha/Lambda) y
    return theta[0] * G / D / (1 + G * (theta[1] + Fy * Lam) / D)


@pytest.mark.parametrize("case", sorted(PLANTS))
def test_the_ideal_parameters_make_the_loop_the_model(case):
    num, den, mnum, mden = PLANTS[case]
    n = len(den) - 1
    nz = len(mnum) - 1
    lam0 = np.poly(np.full(n - 1 - nz, -10.0)) if n - 1 - nz else [1.0]
    theta, lam = matching(num, den, mnum, mden, lam0)
    assert len(theta) == 2 * n
    loop = _loop(num, den, theta, lam)
    model = control.tf(mnum, mden)
    for w in (0.01, 0.3, 1.0, 4.0, 30.0):
        s = 1j * w
        assert abs(loop(s) - model(s)) <= 1e-9 * (1 + abs(model(s))), (case, w)


def _spec(plant: str, controller: str, duration: float = 30, extra: str = "") -> str:
    return (f"name: t\nplant: {plant}\ncontroller: {{kind: mrac, {controller}}}\n"
            f"simulation: {{duration: {duration}, trajectory: {{kind: square, amplitude: 1, period: 10}}{extra}}}\n")


AW_TF = "{kind: transfer_function, num: [b], den: [1, a], parameters: {a: 1.0, b: 0.5}}"
AW_SS = "{kind: state_space, A: [[-a]], B: [[b]], C: [[1]], parameters: {a: 1.0, b: 0.5}}"
AW_MODEL = "reference_model: {num: [2], den: [1, 2]}"


def _rule_by_hand(rule: str, gamma: float, duration: float, period: float = 10.0, alpha0: float = 1.0):
    """y and theta of Astrom-Wittenmark's first-order loop under ``rule``, from zero, by DOP853."""

    def f(_t, z, uc):
        y, ym, fuc, fy, th1, th2 = z
        e = y - ym
        phi = np.array([uc, -y]) if rule == "lyapunov" else np.array([fuc, -fy])
        rate = -gamma * e * phi
        if rule == "normalized":
            rate = rate / (alpha0 + phi @ phi)
        return [-1.0 * y + 0.5 * (th1 * uc - th2 * y), -2 * ym + 2 * uc, -2 * fuc + 2 * uc, -2 * fy + 2 * y, *rate]

    z = np.zeros(6)
    for k in range(int(round(duration / (period / 2)))):
        z = solve_ivp(f, (k * period / 2, (k + 1) * period / 2), z, method="DOP853", rtol=1e-11, atol=1e-13,
                      args=(1.0 if k % 2 == 0 else -1.0,)).y[:, -1]
    return z


@pytest.mark.parametrize("rule", ["lyapunov", "normalized"])
def test_the_lyapunov_and_normalized_rules_against_scipy(rule):
    res = run(parse_spec(_spec(AW_TF, f"{AW_MODEL}, rule: {rule}, gamma: 2, initial: [0, 0]")))
    sim = res.simulation
    want = _rule_by_hand(rule, 2.0, 30.0)
    got = [float(np.asarray(sim.signals[n])[-1]) for n in ("theta1", "theta2")]
    assert got == pytest.approx(want[4:].tolist(), abs=1e-7)
    assert float(np.asarray(sim.state)[-1, sim.positions[0]]) == pytest.approx(want[0], abs=1e-7)


def test_a_state_space_plant_is_the_same_loop():
    tf = run(parse_spec(_spec(AW_TF, f"{AW_MODEL}, gamma: 1, initial: [0, 0]")))
    ss = run(parse_spec(_spec(AW_SS, f"{AW_MODEL}, gamma: 1, initial: [0, 0]")))
    for name in ("theta1", "theta2", "e"):
        assert np.allclose(tf.simulation.signals[name], ss.simulation.signals[name], rtol=0, atol=1e-12)


def test_a_plant_change_is_adapted_to_and_the_final_ideal_values_follow_it():
    """From the ideal parameters of a = 1, b = 0.5 the plant changes to b = 1 at 20 s: the ideal values become
    bm/b = 2 and (am - a)/b = 1, which the run reports as matching_final (matching stays the nominal plant's)."""
    from designkit.families.mrac.report import json as family_json

    res = run(parse_spec(_spec(AW_TF, f"{AW_MODEL}, gamma: 5", 200,
                               ", plant_change: {time: 20, values: {b: 1.0}}")))
    a = family_json(res)["adaptation"]
    assert a["initial"] == pytest.approx([4.0, 2.0]) and a["matching"] == pytest.approx([4.0, 2.0])
    assert a["matching_final"] == pytest.approx([2.0, 1.0], rel=1e-12)
    assert a["final"] == pytest.approx([2.0, 1.0], rel=0.05)
    checks = {c.name: c for c in res.checks}
    assert checks["adaptation_error"].passed is True and checks["adaptation_error"].required is True
    assert checks["parameter_convergence"].certificate["matching"] == pytest.approx([2.0, 1.0])


def _second_order_by_hand(gamma: float, theta0, duration: float, period: float = 10.0) -> np.ndarray:
    """The link 4/(0.5 s^2 + s) under u = th1 uc - th2 y - th3 y/(p + 5) - th4 u/(p + 5) (Lambda = s + 5), the model
    20/(s^2 + 9 s + 20), each regressor entry filtered by the model (static gain 1), the MIT rule; by DOP853."""

    def f(_t, z, uc):
        y, yd, wy, wu, ym, ymd = z[:6]
        phi, phid = z[6:14:2], z[7:14:2]
        th = z[14:18]
        omega = np.array([uc, -y, -wy, -wu])
        u = th @ omega
        e = y - ym
        d_phi = np.empty(8)
        d_phi[0::2], d_phi[1::2] = phid, -9 * phid - 20 * phi + 20 * omega
        return [yd, -2 * yd + 8 * u, -5 * wy + y, -5 * wu + u, ymd, -9 * ymd - 20 * ym + 20 * uc, *d_phi,
                *(-gamma * e * phi)]

    z = np.r_[np.zeros(14), np.asarray(theta0, dtype=float)]
    for k in range(int(round(duration / (period / 2)))):
        z = solve_ivp(f, (k * period / 2, (k + 1) * period / 2), z, method="DOP853", rtol=1e-11, atol=1e-13,
                      args=(1.0 if k % 2 == 0 else -1.0,)).y[:, -1]
    return z


def test_a_second_order_plant_against_its_equations_by_hand():
    """The link written as the transfer function 4/(0.5 s^2 + s), the model 20/(s^2 + 9 s + 20): four parameters
    (theta1, theta2, theta_y, theta_u), ideal values from the polynomial identity; the run against the loop written
    here by hand."""
    plant = "{kind: transfer_function, num: [4], den: [0.5, 1, 0]}"
    res = run(parse_spec(_spec(plant, "reference_model: {num: [20], den: [1, 9, 20]}, rule: mit, gamma: 5, "
                                      "initial: [2, 1, 0, 0]", 40)))
    x = res.design.data
    # L R + kp M = Lambda0 Rm with R = s^2 + 2 s, kp = 8, Lambda = s + 5: L = s + 12, 8 M = 41 s + 100
    assert x.structure.ideal == pytest.approx((2.5, 41 / 8, 100 / 8 - 5 * 41 / 8, 7.0), rel=1e-12)
    assert x.structure.lam == pytest.approx((1.0, 5.0))
    want = _second_order_by_hand(5.0, [2, 1, 0, 0], 40)
    final = np.array([float(np.asarray(res.simulation.signals[n])[-1]) for n in x.parameters])
    assert final == pytest.approx(want[14:], abs=1e-6)
    assert float(np.asarray(res.simulation.state)[-1, 0]) == pytest.approx(want[0], abs=1e-6)
    checks = {c.name: c for c in res.checks}
    assert checks["adaptive_stability"].passed is True
    assert checks["adaptation_error"].passed is True


def test_the_frozen_loop_has_the_poles_of_its_polynomials():
    """The loop frozen at the initial parameters has the roots of Lambda (L R + kp Z M) (from the polynomials) as
    the eigenvalues of the closed loop the core linearizes from the CasADi law; the design requests no pole, so
    pole_placement does not apply to it."""
    from designkit.families.mrac.structure import closed_loop_polynomials
    from designkit.verification.suite import GENERIC

    spec = parse_spec(_spec("{kind: transfer_function, num: [2, 2], den: [1, 3, 0, -1]}",
                            "reference_model: {num: [25], den: [1, 7, 25]}, gamma: 1, initial: [1, 2, 3, 4, 5, 6]"))
    d = synthesize(spec)
    _, char = closed_loop_polynomials(d.data.structure, d.data.initial)
    eig = np.sort_complex(np.linalg.eigvals(d.closed_loop.A))
    want = np.sort_complex(np.roots(char))
    assert eig.shape == want.shape == (3 + 2 * 2,)
    assert np.allclose(eig, want, atol=1e-7 * max(1.0, float(np.max(np.abs(want)))))
    assert d.poles == () and not GENERIC["pole_placement"].applies(d, None)


HEAD = "name: bad\n"
SQUARE = "simulation: {duration: 10, trajectory: {kind: square, amplitude: 1, period: 10}}\n"
TF = f"plant: {AW_TF}\n"
BAD = {
    "Q on a transfer function": (TF + f"controller: {{kind: mrac, {AW_MODEL}, gamma: 1, Q: [1, 1]}}\n" + SQUARE,
                                 "controller.Q:"),
    "no model": (TF + "controller: {kind: mrac, gamma: 1}\n" + SQUARE, "poles"),
    "relative degree": (TF + "controller: {kind: mrac, reference_model: {poles: [-2, -3]}, gamma: 1}\n" + SQUARE,
                        "controller.reference_model: the model's relative degree is 2, the plant's 1"),
    "gamma count": (TF + f"controller: {{kind: mrac, {AW_MODEL}, gamma: [1, 2, 3]}}\n" + SQUARE,
                    "controller.gamma: must be one number or 2"),
    "initial count": (TF + f"controller: {{kind: mrac, {AW_MODEL}, gamma: 1, initial: [0]}}\n" + SQUARE,
                      "controller.initial: must list the 2 adapted parameters"),
    "non-minimum phase": ("plant: {kind: transfer_function, num: [-1, 2], den: [1, 3, 2]}\n"
                          f"controller: {{kind: mrac, {AW_MODEL}, gamma: 1}}\n" + SQUARE,
                          "plant: the plant has the zero"),
    "two inputs": ("plant: {kind: state_space, A: [[0, 1], [-2, -3]], B: [[0, 1], [1, 0]], C: [[1, 0]]}\n"
                   f"controller: {{kind: mrac, {AW_MODEL}, gamma: 1}}\n" + SQUARE, "plant.B: the plant has 2 inputs"),
    "improper model": (TF + "controller: {kind: mrac, reference_model: {num: [1, 2], den: [1, 2]}, gamma: 1}\n"
                       + SQUARE, "controller.reference_model"),
    "rule on the link": ("plant: {kind: link, Km: 2.0, tau: 0.5}\n"
                         "controller: {kind: mrac, poles: [-4, -5], gamma: 1, rule: lyapunov}\n" + SQUARE,
                         "controller.rule:"),
    "normalization without the rule": (TF + f"controller: {{kind: mrac, {AW_MODEL}, gamma: 1, normalization: 2}}\n"
                                       + SQUARE, "controller.normalization:"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_input(case, tmp_path, capsys):
    text, message = BAD[case]
    assert_bad_input(tmp_path, capsys, HEAD + text, message)
