"""Decentralized PID on the SIMNOG arm, against the notes' printed SIMNOG equations (appendix B).

The independent route is the appendix's closed forms (D11, D12, D22, D112, D122, D211, the
gravity torques T1g, T2g and the joint friction, with the T1v erratum of docs/notes-errata.md),
written here in NumPy and integrated with scipy's ``solve_ivp``; nothing of designkit's model
layer is used by the reference.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from designkit.errors import SpecError
from designkit.families import pid_servo
from designkit.models.robots.planar2r import DEFAULTS
from designkit.pipeline import design as design_of
from designkit.pipeline import run
from designkit.schema.loader import parse_spec
from designkit.simulation.run import simulate
from tests import oracles
from tests.tolerances import TOL

P = DEFAULTS

SIMNOG = """\
name: simnog
plant: {kind: robot, robot: planar2r}
controller: {kind: decentralized_pid, poles: [-4, -5, -20], zero: -3}
simulation: {duration: 3.0, step: [1.0, -0.5]}
"""


def _mass(q2: float) -> np.ndarray:
    """D_ij of the appendix."""
    m1, m2, d1, d2, I1, I2 = (P[k] for k in ("m1", "m2", "d1", "d2", "I1", "I2"))
    c = np.cos(q2)
    D11 = 0.25 * m1 * d1**2 + m2 * (d1**2 + 0.25 * d2**2 + d1 * d2 * c) + I1 + I2
    D12 = m2 * (0.25 * d2**2 + 0.5 * d1 * d2 * c) + I2
    D22 = 0.25 * m2 * d2**2 + I2
    return np.array([[D11, D12], [D12, D22]])


def _gravity(q: np.ndarray) -> np.ndarray:
    """``-T_ig`` of the appendix: the torques that hold the arm against gravity."""
    m1, m2, d1, d2, g = (P[k] for k in ("m1", "m2", "d1", "d2", "g"))
    return g * np.array([(m2 + 0.5 * m1) * d1 * np.cos(q[0]) + 0.5 * m2 * d2 * np.cos(q[0] + q[1]),
                         0.5 * m2 * d2 * np.cos(q[0] + q[1])])


def _simnog_rhs(gains: dict, target: np.ndarray):
    """The appendix's state equations with the two PIDs and the gravity feed-forward of SIMNOG."""
    m2, d1, d2, f1, f2 = (P[k] for k in ("m2", "d1", "d2", "f1", "f2"))
    K1, K2, K3, K4 = (np.asarray(gains[k]) for k in ("K1", "K2", "K3", "K4"))

    def rhs(t, x):
        q, qd, x3 = x[0:2], x[2:4], x[4:6]
        s = np.sin(q[1])
        D112, D122, D211 = -m2 * d1 * d2 * s, -0.5 * m2 * d1 * d2 * s, 0.5 * m2 * d1 * d2 * s
        T = -K1 * (q - target) - K2 * qd - K3 * x3 + K3 * K4 * target  # decentralized PIDs
        T = T + _gravity(q)  # feed-forward on the measured configuration
        T1 = T[0] - _gravity(q)[0] - f1 * qd[0]  # T1' = T1 + T1g + T1v (T1v = -f1 x12, erratum)
        T2 = T[1] - _gravity(q)[1] - f2 * qd[1]
        D = _mass(q[1])
        a = 1.0 / (D[0, 0] * D[1, 1] - D[0, 1] * D[1, 0])
        b1 = T1 - D112 * qd[0] * qd[1] - D122 * qd[1] ** 2
        b2 = T2 - D211 * qd[0] ** 2
        qdd = np.array([a * D[1, 1] * b1 - a * D[0, 1] * b2, -a * D[1, 0] * b1 + a * D[0, 0] * b2])
        return np.concatenate([qd, qdd, q - target])

    return rhs


def test_simulation_of_the_coupled_arm_matches_the_printed_simnog_equations():
    loaded = parse_spec(SIMNOG)
    design = design_of(loaded)
    res = simulate(loaded.spec, design)
    target = np.array([1.0, -0.5])
    sol = solve_ivp(_simnog_rhs(dict(design.gains), target), (0.0, 3.0), np.zeros(6), t_eval=res.time,
                    rtol=1e-11, atol=1e-12, method="DOP853")
    ref = sol.y.T
    err = np.max(np.abs(res.state - ref[:, :4]) / (1.0 + np.abs(ref[:, :4])))
    assert err < TOL["rk4_vs_ivp"], err
    np.testing.assert_allclose(res.controller_state, ref[:, 4:], rtol=1e-5, atol=1e-7)
    assert np.max(np.abs(res.tracking_errors[-1])) < 1e-3


def test_per_link_models_use_the_diagonal_inertia_at_the_configuration():
    text = SIMNOG.replace("zero: -3}", "zero: -3, configuration: [0.3, 1.1]}")
    design = design_of(parse_spec(text))
    D = _mass(1.1)
    for i, loop in enumerate(design.loops):
        f = P[f"f{i + 1}"]
        assert loop.plant.Km == pytest.approx(1.0 / f, rel=TOL["algebra"])
        assert loop.plant.tau == pytest.approx(D[i, i] / f, rel=TOL["algebra"])
    assert design.data.configuration == (0.3, 1.1)


def test_each_joint_loop_places_its_poles_on_its_simplified_link():
    text = SIMNOG.replace("poles: [-4, -5, -20], zero: -3", "poles: [[-4, -5, -20], ['-3+2j', '-3-2j', -15]]")
    design = design_of(parse_spec(text))
    for loop, requested in zip(design.loops, ([-4, -5, -20], [-3 + 2j, -3 - 2j, -15]), strict=True):
        A = oracles.servo_closed_loop(dict(loop.gains), loop.plant).A  # hand-derived, not the library's loop
        got = np.sort_complex(np.linalg.eigvals(A))
        np.testing.assert_allclose(got, np.sort_complex(np.array(requested, dtype=complex)), atol=TOL["eigenvalues"])
    assert np.asarray(design.gains["K1"]).shape == (2,)


def test_coupled_linearization_equals_finite_differences_of_the_simnog_equations():
    loaded = parse_spec(SIMNOG)
    design = design_of(loaded)
    target = np.zeros(2)  # the operating point: the design configuration at rest
    rhs = _simnog_rhs(dict(design.gains), target)
    z0 = np.concatenate([design.operating_point["x"], design.operating_point["xc"]])
    np.testing.assert_allclose(rhs(0.0, z0), 0.0, atol=1e-9)  # it is an equilibrium of the printed model
    h = 1e-6
    J = np.column_stack([(rhs(0.0, z0 + h * e) - rhs(0.0, z0 - h * e)) / (2 * h) for e in np.eye(6)])
    A = design.closed_loop.A
    fd = TOL["finite_difference"]
    np.testing.assert_allclose(A, J, rtol=fd, atol=10 * fd * np.max(np.abs(J)))


def test_without_feedforward_the_integrals_carry_the_gravity_load():
    text = SIMNOG.replace("zero: -3}", "zero: -3, gravity_feedforward: none}").replace("duration: 3.0", "duration: 8.0")
    loaded = parse_spec(text)
    design = design_of(loaded)
    res = simulate(loaded.spec, design)
    target = np.array([1.0, -0.5])
    np.testing.assert_allclose(res.joint_positions[-1], target, atol=1e-4)
    np.testing.assert_allclose(res.u_applied[-1], _gravity(target), rtol=1e-4)  # held by the PIDs alone
    # with the feed-forward the PIDs hold no load: at rest -K3 x3 + K3 K4 xD = 0, so x3 = K4 xD
    measured = simulate(parse_spec(SIMNOG).spec, design_of(parse_spec(SIMNOG)))
    np.testing.assert_allclose(measured.controller_state[-1], np.asarray(design.gains["K4"]) * target, atol=1e-5)


def test_coupling_check_measures_the_disturbance_of_a_joint_told_to_stay():
    text = SIMNOG.replace("step: [1.0, -0.5]", "step: [1.0, 0.0]")
    result = run(parse_spec(text))
    coupling = next(c for c in result.checks if c.name == "coupling")
    q2 = result.simulation.joint_positions[:, 1]
    row = coupling.certificate["intercoupling_error"][1]
    # joint 2's own loop predicts it stays at 0, so its intercoupling error is its own motion
    assert row["max_abs_rad"] == pytest.approx(np.max(np.abs(q2)), rel=1e-9)
    assert row["max_abs_rad"] > 1e-2 and coupling.required is False


def test_joint_loops_are_the_one_link_servo():
    design = design_of(parse_spec(SIMNOG))
    for loop in design.loops:
        direct = pid_servo.design(loop.plant, [-4, -5, -20], -3.0)
        assert dict(loop.gains) == dict(direct.gains)


@pytest.mark.parametrize(
    ("replace", "by", "path"),
    [
        ("poles: [-4, -5, -20]", "poles: [[-4, -5, -20]]", "controller.poles"),
        ("zero: -3}", "zero: -3, configuration: [0, 0, 0]}", "controller.configuration"),
        ("zero: -3}", "zero: [-3, -2, -1]}", "controller.zero"),
        ("robot: planar2r}", "robot: planar2r, friction: false}", "plant.friction"),
        ("step: [1.0, -0.5]", "step: [1.0, -0.5, 2.0]", "simulation.step"),
        ("poles: [-4, -5, -20]", "poles: [[-4, -5, -20], [-1, 2, -3]]", "controller.poles[1][1]"),
    ],
)
def test_bad_input_names_the_key_path(replace, by, path):
    text = SIMNOG.replace(replace, by)
    assert text != SIMNOG
    with pytest.raises(SpecError) as info:
        loaded = parse_spec(text)
        simulate(loaded.spec, design_of(loaded))
    assert info.value.path == path, str(info.value)
    assert "\n" not in str(info.value)
