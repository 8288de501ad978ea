"""Independent pins of docs/notes-errata.md (misprints in the 1988 course notes).

Every expected value here is derived in this file with sympy (homogeneous transforms and
pseudo-inertia matrices, Lagrange's equations, Laplace-domain loop algebra) or computed with
numpy eigenvalues; nothing is copied from designkit's own formulas.  Each test also shows that
the formula as printed in the notes gives a clearly different answer, so it would fail with the
misprint.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import sympy as sp

from designkit.models.robots import robot
from designkit.models.robots.planar2r import DEFAULTS

SEED = 1988
STATES = 6

# ----------------------------------------------------------------------------- SIMNOG arm (appendix B)

q1, q2, qd1, qd2, u1, u2 = sp.symbols("q1 q2 qd1 qd2 u1 u2", real=True)
m1, m2, d1, d2, I1, I2, f1, f2, g = sp.symbols("m1 m2 d1 d2 I1 I2 f1 f2 g", positive=True)
Q, QD, U = (q1, q2), (qd1, qd2), (u1, u2)
PHYSICAL = {m1: DEFAULTS["m1"], m2: DEFAULTS["m2"], d1: DEFAULTS["d1"], d2: DEFAULTS["d2"], I1: DEFAULTS["I1"],
            I2: DEFAULTS["I2"], f1: DEFAULTS["f1"], f2: DEFAULTS["f2"], g: DEFAULTS["g"]}


def _states(rng: np.random.Generator) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Random (q, qd, u); |sin q2| >= 0.38 and |qd_i| >= 0.5 so that the misprints cannot vanish by chance."""
    out = []
    for _ in range(STATES):
        q = np.array([rng.uniform(-math.pi, math.pi), rng.choice([-1, 1]) * rng.uniform(0.4, 2.7)])
        qd = rng.choice([-1, 1], 2) * rng.uniform(0.5, 2.0, 2)
        out.append((q, qd, rng.uniform(-5.0, 5.0, 2)))
    return out


def _dh(theta: sp.Expr, a: sp.Expr) -> sp.Matrix:
    """Standard DH link transform with d = 0, alpha = 0: Rz(theta) Tx(a)."""
    c, s = sp.cos(theta), sp.sin(theta)
    return sp.Matrix([[c, -s, 0, a * c], [s, c, 0, a * s], [0, 0, 1, 0], [0, 0, 0, 1]])


def _pseudo_inertia(mass: sp.Expr, com: tuple, inertia_com: sp.Matrix) -> sp.Matrix:
    """J = integral of r r' dm over the link, r = (x, y, z, 1) in the link frame.

    About the centre of mass, integral(s s' dm) = tr(I_c)/2 * 1 - I_c (from I_c = integral(|s|^2 1 - s s') dm);
    shifting to the frame origin adds m c c'.
    """
    c = sp.Matrix(com)
    second = inertia_com.trace() / 2 * sp.eye(3) - inertia_com + mass * c * c.T
    return sp.Matrix(sp.BlockMatrix([[second, mass * c], [mass * c.T, sp.Matrix([[mass]])]]))


@functools.cache
def _trace_model() -> tuple[list[sp.Matrix], list[sp.Matrix]]:
    """T[p,0](q) and J_p of the two links (p = 0, 1 here for the notes' p = 1, 2)."""
    a1, a2 = _dh(q1, d1), _dh(q2, d2)
    transforms = [a1, a1 * a2]
    pseudo = [_pseudo_inertia(m, (-d / 2, 0, 0), sp.diag(0, inertia, inertia))
              for m, d, inertia in ((m1, d1, I1), (m2, d2, I2))]
    return transforms, pseudo


def _U(p: int, *joints: int) -> sp.Matrix:
    """Derivative of T[p,0] with respect to the listed joint coordinates."""
    expr = _trace_model()[0][p]
    for j in joints:
        expr = expr.diff(Q[j])
    return expr


def _tr(a: sp.Matrix, p: int, b: sp.Matrix) -> sp.Expr:
    return (a * _trace_model()[1][p] * b.T).trace()


@functools.cache
def _trace_coefficients() -> dict[str, sp.Matrix | list]:
    """D_ij and D_ijk from the trace formulas, corrected and as printed in §1.2 (0-based indices)."""
    r = range(2)
    corrected_dij = sp.Matrix(2, 2, lambda i, j: sum(_tr(_U(p, j), p, _U(p, i)) for p in range(max(i, j), 2)))
    printed_dij = sp.Matrix(2, 2, lambda i, j: sum(_tr(_U(p, j), p, _U(p, j)) for p in range(max(i, j), 2)))
    # corrected: U_pjk = d2 T_p / (dq_j dq_k); printed: U_pjk = d/dq_i (dT_p/dq_k)
    corrected_dijk = [[[sum(_tr(_U(p, j, k), p, _U(p, i)) for p in range(max(i, j, k), 2))
                        for k in r] for j in r] for i in r]
    printed_dijk = [[[sum(_tr(_U(p, i, k), p, _U(p, i)) for p in range(max(i, j, k), 2))
                      for k in r] for j in r] for i in r]
    return {"Dij": corrected_dij, "Dij_printed": printed_dij, "Dijk": corrected_dijk, "Dijk_printed": printed_dijk}


def _numeric(expr: sp.Matrix | list) -> object:
    """f(q) -> nested lists, at designkit's default parameters."""
    return sp.lambdify([Q], sp.Array(expr).subs(PHYSICAL), "numpy")


def test_trace_formulas_for_D_ij_and_D_ijk_give_designkits_mass_matrix_and_christoffel_symbols():
    """§1.2: D_ij = sum Tr(U_pj J_p U_pi'), D_ijk = sum Tr(U_pjk J_p U_pi') with U_pjk = d2 T_p/(dq_j dq_k).

    T[p,0] and J_p are built here from the DH data of the SIMNOG arm; designkit builds M from link
    Jacobians and G from derivatives of M.  The printed D_ij (U'_pj) and the printed U_pjk
    (d/dq_i instead of d/dq_j) give different matrices and a different Coriolis/centripetal torque.
    """
    c = _trace_coefficients()
    dij, dij_printed = _numeric(c["Dij"]), _numeric(c["Dij_printed"])
    dijk, dijk_printed = _numeric(c["Dijk"]), _numeric(c["Dijk_printed"])
    arm = robot("planar2r")
    for q, qd, _ in _states(np.random.default_rng(SEED)):
        M, G = arm.mass_matrix(q), arm.christoffel(q)
        expected_m, expected_g = np.array(dij(q), float), np.array(dijk(q), float)
        np.testing.assert_allclose(M, expected_m, rtol=1e-12, atol=1e-14)
        # convention check: G[i, j, k] multiplies qd_j qd_k, is symmetric in (j, k) and equals D_ijk entry by entry
        np.testing.assert_allclose(G, np.swapaxes(G, 1, 2), rtol=0, atol=1e-14)
        np.testing.assert_allclose(G, expected_g, rtol=1e-12, atol=1e-14)
        coriolis = np.einsum("ijk,j,k->i", expected_g, qd, qd)
        newton_euler = arm.inverse_dynamics(q, qd, np.zeros(2)) - arm.gravity_torque(q)
        np.testing.assert_allclose(newton_euler, coriolis, rtol=1e-12, atol=1e-12)
        # the printed formulas are clearly wrong
        assert np.max(np.abs(np.array(dij_printed(q), float) - M)) > 0.3  # printed D_21: >= m2 (d1^2 - d1 d2/2)
        printed_coriolis = np.einsum("ijk,j,k->i", np.array(dijk_printed(q), float), qd, qd)
        # printed: no centripetal torque on joint 2, half the Coriolis term on joint 1 (>= 17 % off in this box)
        assert np.linalg.norm(printed_coriolis - coriolis) > 0.1 * np.linalg.norm(coriolis)


def test_trace_formula_reproduces_the_appendix_coefficients_with_D112_a_sum():
    """Appendix B's D112 is the coefficient of x12 x22, i.e. D_112 + D_121 of §1.2; D122, D211 are single terms."""
    dijk = _trace_coefficients()["Dijk"]
    k = m2 * d1 * d2 * sp.sin(q2)
    assert sp.simplify(dijk[0][0][1] + dijk[0][1][0] - (-k)) == 0
    assert sp.simplify(dijk[0][0][1] - (-k)) != 0  # a single symbol is only half of the printed coefficient
    assert sp.simplify(dijk[0][1][1] - (-k / 2)) == 0
    assert sp.simplify(dijk[1][0][0] - k / 2) == 0


# ----------------------------------------------------------------------------- Lagrange with dissipation


@functools.cache
def _lagrange_model() -> dict[str, sp.Matrix]:
    """Lagrange's equations of two uniform rods (q2 relative), gravity along -y, R = f1 qd1^2/2 + f2 qd2^2/2.

    Returns M(q), the velocity/gravity terms and the dissipative generalized forces, with
    M qdd + velocity + gravity + dissipation = u.
    """
    q, qd = sp.Matrix(Q), sp.Matrix(QD)
    centre1 = sp.Matrix([d1 / 2 * sp.cos(q1), d1 / 2 * sp.sin(q1)])
    centre2 = sp.Matrix([d1 * sp.cos(q1) + d2 / 2 * sp.cos(q1 + q2), d1 * sp.sin(q1) + d2 / 2 * sp.sin(q1 + q2)])
    v1, v2 = centre1.jacobian(q) * qd, centre2.jacobian(q) * qd
    kinetic = (m1 * v1.dot(v1) + I1 * qd1**2 + m2 * v2.dot(v2) + I2 * (qd1 + qd2) ** 2) / 2
    potential = g * (m1 * centre1[1] + m2 * centre2[1])
    rayleigh = (f1 * qd1**2 + f2 * qd2**2) / 2
    lagrangian = kinetic - potential
    momentum = sp.Matrix([lagrangian]).jacobian(qd).T
    mass = momentum.jacobian(qd)
    # d/dt (dL/dqd) = M qdd + (d momentum/dq) qd
    velocity = sp.expand(momentum.jacobian(q) * qd - sp.Matrix([kinetic]).jacobian(q).T)
    gravity = sp.Matrix([potential]).jacobian(q).T
    dissipation = sp.Matrix([rayleigh]).jacobian(qd).T
    return {"M": mass, "velocity": velocity, "gravity": gravity, "dissipation": dissipation}


def _accelerations(*, printed_t1v: bool = False, printed_gravity: bool = False) -> object:
    """qdd(q, qd, u) from Lagrange's equations, optionally with a printed variant of the notes."""
    L = _lagrange_model()
    dissipation = L["dissipation"]
    if printed_t1v:  # T1v = -f1 x12 + f2 x22, i.e. a generalized damping force f1 qd1 - f2 qd2 on joint 1
        dissipation = dissipation + sp.Matrix([-f2 * qd2, 0])
    gravity = -L["gravity"] if printed_gravity else L["gravity"]  # §1.2 state model: "+ [D_ij]^-1 [D_i]"
    rhs = sp.Matrix(U) - L["velocity"] - gravity - dissipation
    qdd = L["M"].subs(PHYSICAL).LUsolve(rhs.subs(PHYSICAL))
    return sp.lambdify([Q, QD, U], qdd, "numpy")


def test_simnog_joint_friction_by_rayleigh_dissipation():
    """App. B, T1v: Lagrange's equations with R = f1 qd1^2/2 + f2 qd2^2/2 give T1v = -f1 x12, not -f1 x12 + f2 x22.

    designkit adds the joint viscous friction f1, f2 only with ``friction=True`` (Robot's friction option,
    ``Fv qd + Fc sign(qd)`` with zero Coulomb friction for planar2r), so that model is the one compared.
    """
    arm = robot("planar2r", friction=True)
    assert np.any(arm.friction_torque(np.ones(2)) != 0)  # the option really brings f1, f2 in
    correct, printed = _accelerations(), _accelerations(printed_t1v=True)
    for q, qd, u in _states(np.random.default_rng(SEED + 1)):
        expected = np.array(correct(q, qd, u), float).ravel()
        np.testing.assert_allclose(arm.forward_dynamics(q, qd, u), expected, rtol=1e-10, atol=1e-10)
        wrong = np.array(printed(q, qd, u), float).ravel()
        assert np.max(np.abs(wrong - expected)) > 0.5  # f2 |qd2| >= 0.5 N*m misplaced through M^-1


def test_state_model_gravity_enters_with_a_minus_sign():
    """§1.2 state model: qdd = D^-1 (u - sum D_ijk qd_j qd_k - D_i); the printed "+ D^-1 D_i" disagrees.

    The frictionless arm is compared with Lagrange's equations (f1 = f2 = 0 there), which also fixes the
    Coriolis/centripetal part as quadratic in the velocities.
    """
    arm = robot("planar2r")
    frictionless = {f1: 0.0, f2: 0.0}
    L = _lagrange_model()
    assert all(sp.expand(e.subs({qd1: 3 * qd1, qd2: 3 * qd2}) - 9 * e) == 0 for e in L["velocity"])
    for q, qd, u in _states(np.random.default_rng(SEED + 2)):
        values = {**PHYSICAL, **frictionless, **dict(zip(Q, q, strict=True)), **dict(zip(QD, qd, strict=True))}
        M = np.array(L["M"].subs(values), float)
        bias = np.array((L["velocity"] + L["gravity"]).subs(values), float).ravel()
        gravity = np.array(L["gravity"].subs(values), float).ravel()
        expected = np.linalg.solve(M, u - bias)
        np.testing.assert_allclose(arm.forward_dynamics(q, qd, u), expected, rtol=1e-10, atol=1e-10)
        printed = np.linalg.solve(M, u - bias + 2 * gravity)  # gravity term with the printed plus sign
        assert np.max(np.abs(printed - expected)) > 1.0


# ----------------------------------------------------------------------------- §3.2 PID servo and tracker

s, Km, tau, K1, K2, K3, K4, xD, xi = sp.symbols("s K_m tau K1 K2 K3 K4 x_D xi")
x1, x2, x3 = sp.symbols("x1 x2 x3")


def _plant(u: sp.Expr) -> sp.Matrix:
    """Simplified link x1' = x2, x2' = -x2/tau + (Km/tau)(u + xi) with integral state x3' = x1 - xD."""
    return sp.Matrix([x2, -x2 / tau + Km / tau * (u + xi), x1 - xD])


SERVO_LAW = -K1 * (x1 - xD) - K2 * x2 - K3 * x3 + K3 * K4 * xD
# tracker with a fixed set-point (xD' = xD'' = 0): stability does not depend on the reference
TRACKER_LAW = x2 / Km - K1 * (x1 - xD) - K2 * x2 - K3 * x3


def _characteristic(law: sp.Expr) -> sp.Poly:
    """tau * det(s 1 - A) of the closed loop, A = d(x')/d(x1, x2, x3)."""
    A = _plant(law).jacobian([x1, x2, x3])
    return sp.Poly(sp.expand(tau * (s * sp.eye(3) - A).det()), s)


def _closed_loop_a(law: sp.Expr) -> object:
    return sp.lambdify([Km, tau, K1, K2, K3], _plant(law).jacobian([x1, x2, x3]), "numpy")


def _max_real(a_of: object, *args: float) -> float:
    return float(np.max(np.linalg.eigvals(np.array(a_of(*args), float)).real))


def test_tracking_pid_has_other_stability_conditions_than_the_servo():
    """§3.2: the tracker's stability requirements are not "identical to the case of the position servo".

    Servo: tau s^3 + (1 + Km K2) s^2 + Km K1 s + Km K3 (K3 > 0, K2 > -1/Km, K1 > tau K3/(1 + Km K2)).
    Tracker: tau s^3 + Km K2 s^2 + Km K1 s + Km K3 (K3 > 0, K2 > 0, K1 > tau K3/(Km K2)).
    """
    servo, tracker = _characteristic(SERVO_LAW), _characteristic(TRACKER_LAW)
    assert sp.expand(servo.as_expr() - (tau * s**3 + (1 + Km * K2) * s**2 + Km * K1 * s + Km * K3)) == 0
    assert sp.expand(tracker.as_expr() - (tau * s**3 + Km * K2 * s**2 + Km * K1 * s + Km * K3)) == 0
    servo_a, tracker_a = _closed_loop_a(SERVO_LAW), _closed_loop_a(TRACKER_LAW)

    def servo_ok(km: float, t: float, k1: float, k2: float, k3: float) -> bool:
        return k3 > 0 and k2 > -1 / km and k1 > t * k3 / (1 + km * k2)

    def tracker_ok(km: float, t: float, k1: float, k2: float, k3: float) -> bool:
        return k3 > 0 and k2 > 0 and k1 > t * k3 / (km * k2)

    # the stated conditions are exactly the eigenvalue test (Routh-Hurwitz of each cubic), away from the boundary
    rng = np.random.default_rng(SEED + 3)
    checked = 0
    for _ in range(400):
        args = (rng.uniform(0.5, 3.0), rng.uniform(0.1, 2.0), *rng.uniform(-1.0, 4.0, 3))
        for a_of, ok in ((servo_a, servo_ok), (tracker_a, tracker_ok)):
            worst = _max_real(a_of, *args)
            if abs(worst) > 1e-6:
                assert (worst < 0) == ok(*args)
                checked += 1
    assert checked > 700
    # a gain set that satisfies the servo conditions (-1/Km < K2 < 0) destabilizes the tracker
    km, t, k1, k2, k3 = 2.0, 0.5, 2.0, -0.2, 1.0
    assert servo_ok(km, t, k1, k2, k3) and not tracker_ok(km, t, k1, k2, k3)
    assert _max_real(servo_a, km, t, k1, k2, k3) < -0.1
    assert _max_real(tracker_a, km, t, k1, k2, k3) > 0.1


def test_tracking_pid_gains_by_coefficient_matching():
    """§3.2 gains: placing p1, p2, p3 gives the tracker K2 = servo K2 + 1/Km; K1 and K3 are the same."""
    p1, p2, p3 = sp.symbols("p1 p2 p3")
    target = sp.Poly(sp.expand(tau * (s - p1) * (s - p2) * (s - p3)), s)

    def gains(poly: sp.Poly) -> dict:
        equations = [a - b for a, b in zip(poly.all_coeffs()[1:], target.all_coeffs()[1:], strict=True)]
        return sp.solve(equations, [K1, K2, K3], dict=True)[0]

    servo, tracker = gains(_characteristic(SERVO_LAW)), gains(_characteristic(TRACKER_LAW))
    assert sp.simplify(tracker[K2] - servo[K2] - 1 / Km) == 0
    assert sp.simplify(tracker[K1] - servo[K1]) == 0 and sp.simplify(tracker[K3] - servo[K3]) == 0
    assert sp.simplify(servo[K2] + ((p1 + p2 + p3) * tau + 1) / Km) == 0  # the servo row's corrected K2


def test_servo_F2_printed_is_the_perturbation_transfer_not_the_velocity_ratio():
    """§3.2: the printed F2 = s Km / (tau s^3 + (1 + Km K2) s^2 + Km K1 s + Km K3) is x1/xi.

    x1'/xD1' = (s x1)/(s xD) = x1/xD = F1, a different function.  In the pole form the notes also give,
    s / (K3 (1 + a1 s + a2 s^2)(1 - s/p3)), it is again x1/xi once K1, K2, K3 place p1, p2, p3.
    """
    X1 = sp.Symbol("X1")
    # Laplace domain, zero initial state: x2 = s x1, x3 = (x1 - xD)/s
    law = SERVO_LAW.subs({x2: s * X1, x3: (X1 - xD) / s, x1: X1})
    x1_of = sp.solve(sp.Eq(s * X1 * (tau * s + 1), Km * (law + xi)), X1)[0]
    to_xi = sp.simplify(sp.diff(x1_of, xi))
    to_xd = sp.simplify(sp.diff(x1_of, xD))
    denominator = tau * s**3 + (1 + Km * K2) * s**2 + Km * K1 * s + Km * K3
    printed_f2 = s * Km / denominator
    printed_f1 = (s * Km * (K1 + K3 * K4) + K3 * Km) / denominator
    assert sp.simplify(to_xd - printed_f1) == 0  # F1 as printed is right
    velocity_ratio = sp.simplify((s * to_xd * xD) / (s * xD))
    assert sp.simplify(printed_f2 - to_xi) == 0
    assert sp.simplify(printed_f2 - velocity_ratio) != 0
    # pole form of the perturbation transfer
    p1, p2, p3 = sp.symbols("p1 p2 p3")
    placed = {K1: tau / Km * (p1 * p2 + p2 * p3 + p1 * p3), K2: -((p1 + p2 + p3) * tau + 1) / Km,
              K3: -tau / Km * p1 * p2 * p3}
    a1, a2 = -(1 / p1 + 1 / p2), 1 / (p1 * p2)
    pole_form = s / (K3 * (1 + a1 * s + a2 * s**2) * (1 - s / p3))
    assert sp.simplify((pole_form - to_xi).subs(placed)) == 0
    # numerically, at a sample point, the two candidate meanings of F2 differ clearly
    point = {s: 1.3j, Km: 2.0, tau: 0.5, K1: 3.0, K2: 0.4, K3: 1.5, K4: 0.2}
    assert abs(complex(printed_f2.subs(point)) - complex(velocity_ratio.subs(point))) > 0.1


def test_servo_feedforward_is_K3_K4_xD():
    """§3.2: the servo law prints "+ K4 xD1"; the printed F1 and K4 = (-K3 - K1 z)/(K3 z) need "+ K3 K4 xD1".

    With K3 K4 xD the zero of x1/xD is -K3/(K1 + K3 K4), which the printed K4 puts at z; with K4 xD it is not.
    """
    X1, z = sp.symbols("X1 z")

    def zero_of_x1_over_xd(feedforward: sp.Expr) -> sp.Expr:
        law = -K1 * (X1 - xD) - K2 * s * X1 - K3 * (X1 - xD) / s + feedforward
        transfer = sp.diff(sp.solve(sp.Eq(s * X1 * (tau * s + 1), Km * law), X1)[0], xD)
        (root,) = sp.solve(sp.numer(sp.together(transfer)), s)
        return root

    printed_k4 = (-K3 - K1 * z) / (K3 * z)
    assert sp.simplify(zero_of_x1_over_xd(K3 * K4 * xD).subs(K4, printed_k4) - z) == 0
    printed_zero = zero_of_x1_over_xd(K4 * xD).subs(K4, printed_k4)
    assert abs(float(printed_zero.subs({K1: 3.0, K3: 1.5, z: -2.0})) - (-2.0)) > 0.5
