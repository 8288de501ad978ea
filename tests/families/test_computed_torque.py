"""Computed torque (notes section 2.2) on the PUMA 560 and the SIMNOG arm, against independent routes.

* Exact model: the error of every joint obeys ``e'' + K2 e' + K1 e = 0`` from rest, so the exact solution is
  ``q(t) = qD(t)``; the reference is written here from the quintic's formula, and the simulated error must
  shrink as ``dt^4`` (classical RK4) when the step is halved -- an order measured, not a tolerance guessed.
* Error poles: the closed loop (true plant's ODE with the law's command, as the simulator composes them)
  linearized by central finite differences at points on and off the trajectory; its eigenvalues against the
  requested poles of the spec.  The gains from ``damping`` and ``natural_frequency`` against python-control's
  ``damp`` of ``s^2 + K2 s + K1`` (and the roots' definition for an overdamped pair).
* Model mismatch: the tracking error grows with the payload the model leaves out, and the error left at
  rest matches the static balance ``K1 M^(q) (qD - q) = g(q) - g^(q)`` computed from the model layer's mass
  matrix and gravity torques.
* Bad input through ``designkit synth``: exit 2, one line naming the key path, nothing written.
"""

from __future__ import annotations

import math

import control
import numpy as np
import pytest

from designkit.families import family
from designkit.pipeline import design as design_of
from designkit.pipeline import plant as plant_of
from designkit.schema.loader import parse_spec
from designkit.simulation.run import build
from tests.cli_input import assert_bad_input
from tests.tolerances import TOL

PUMA_Q0 = (0.0, 0.785, -3.1416, 0.0, 0.785, 0.0)  # table-top pose, joint 3 at -pi (limits [-3.927, 0.785] rad)
PUMA_AMPLITUDE = (0.4, 0.3, 0.5, 0.6, -0.4, 0.8)
ARMS = {
    "puma560": ("{kind: robot, robot: puma560}", PUMA_Q0, PUMA_AMPLITUDE),
    "planar2r": ("{kind: robot, robot: planar2r}", (0.0, 0.0), (1.0, -0.5)),
}
MOVE_S = 1.0


def _spec(plant: str, controller: str, q0, amplitude, *, dt: float | None = None, duration: float = 1.5,
          requirements: str = "") -> str:
    step = f"dt: {dt}, " if dt is not None else ""
    return (f"name: ct-test\nplant: {plant}\ncontroller: {controller}\n{requirements}"
            "numerics: {compile: never, integrator: rk4}\n"
            f"simulation: {{duration: {duration}, {step}initial_position: {list(q0)}, "
            f"trajectory: {{kind: quintic, amplitude: {list(amplitude)}, duration: {MOVE_S}}}}}\n")


def _quintic(t: np.ndarray, q0, amplitude) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rest-to-rest quintic ``q0 + A (10 s^3 - 15 s^4 + 6 s^5)``, ``s = t / T`` clipped to [0, 1]; derivatives."""
    s = np.clip(np.asarray(t, dtype=float) / MOVE_S, 0.0, 1.0)[:, None]
    A, q0 = np.asarray(amplitude, dtype=float), np.asarray(q0, dtype=float)
    pos = q0 + A * (10 * s**3 - 15 * s**4 + 6 * s**5)
    vel = A * (30 * s**2 - 60 * s**3 + 30 * s**4) / MOVE_S
    acc = A * (60 * s - 180 * s**2 + 120 * s**3) / MOVE_S**2
    return pos, vel, acc


# ----------------------------------------------------------------------------- exact model: integrator precision


@pytest.mark.parametrize("arm", sorted(ARMS))
def test_exact_model_tracks_the_reference_to_rk4_precision(arm):
    plant, q0, amplitude = ARMS[arm]
    controller = "{kind: computed_torque, damping: 1.0, natural_frequency: 10}"
    errors = []
    for dt in (0.02, 0.01, 0.005):
        loaded = parse_spec(_spec(plant, controller, q0, amplitude, dt=dt))
        res = build(loaded.spec, design_of(loaded)).run()
        assert res.settings["dt"] == dt
        qD = _quintic(res.time, q0, amplitude)[0]
        n = len(q0)
        errors.append(float(np.max(np.abs(res.state[:, :n] - qD))))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    # the error is the integrator's alone: it falls as dt^4 (measured orders 4.12, 4.06 for both arms)
    assert np.all(np.abs(orders - 4.0) < 0.25), (errors, orders)
    assert errors[-1] < 1e-7, errors


# ----------------------------------------------------------------------------- error poles


PUMA_POLES = ("[[-8, -12], ['-6+4j', '-6-4j'], [-10, -15], [-9, -11], ['-7+3j', '-7-3j'], [-20, -25]]")
PUMA_POLE_VALUES = np.array([-8, -12, -6 + 4j, -6 - 4j, -10, -15, -9, -11, -7 + 3j, -7 - 3j, -20, -25])


def _closed_loop_jacobian(plant, law, x: np.ndarray, r: np.ndarray) -> np.ndarray:
    """``d/dx`` of ``x' = f(x, command(x, r))`` by central differences (the simulator's composition)."""
    ode = plant.ode()
    p = np.asarray(plant.parameter_vector, dtype=float)
    d = np.zeros(len(plant.disturbances))

    def f(z: np.ndarray) -> np.ndarray:
        u = law.command(z, np.zeros(0), np.zeros(0), r).full().ravel()
        return ode(z, u, d, p).full().ravel()

    J = np.empty((x.size, x.size))
    for k in range(x.size):
        h = 1e-6 * max(1.0, abs(x[k]))
        dz = np.zeros(x.size)
        dz[k] = h
        J[:, k] = (f(x + dz) - f(x - dz)) / (2 * h)
    return J


def _matched_error(got: np.ndarray, want: np.ndarray) -> float:
    """Largest ``|got - want| / |want|`` after pairing each requested pole with its nearest computed one."""
    got = list(got)
    worst = 0.0
    for w in want:
        k = int(np.argmin([abs(g - w) for g in got]))
        worst = max(worst, abs(got.pop(k) - w) / abs(w))
    return worst


def test_error_poles_by_finite_differences_equal_the_requested_poles_everywhere():
    plant, q0, amplitude = ARMS["puma560"]
    loaded = parse_spec(_spec(plant, f"{{kind: computed_torque, poles: {PUMA_POLES}}}", q0, amplitude))
    design = design_of(loaded)
    law = family(design.kind).law(design)
    true_plant = plant_of(loaded)
    rng = np.random.default_rng(7)
    t = np.array([0.1, 0.35, 0.5, 0.8])
    pos, vel, acc = _quintic(t, q0, amplitude)
    for k in range(t.size):
        r = np.concatenate([pos[k], vel[k], acc[k]])
        on_path = np.concatenate([pos[k], vel[k]])
        off_path = on_path + np.concatenate([rng.uniform(-0.3, 0.3, 6), rng.uniform(-1.0, 1.0, 6)])
        for x in (on_path, off_path):  # decoupled and linear at every state, not only on the reference
            eig = np.linalg.eigvals(_closed_loop_jacobian(true_plant, law, x, r))
            assert _matched_error(eig, PUMA_POLE_VALUES) < 10 * TOL["finite_difference"], (t[k], np.sort_complex(eig))


def test_gains_from_damping_and_natural_frequency_have_the_requested_characteristic_polynomial():
    zetas = [0.3, 0.5, 0.7, 1.0, 1.5, 2.0]
    wns = [12.0, 5.0, 10.0, 15.0, 20.0, 8.0]
    plant, q0, amplitude = ARMS["puma560"]
    controller = f"{{kind: computed_torque, damping: {zetas}, natural_frequency: {wns}}}"
    design = design_of(parse_spec(_spec(plant, controller, q0, amplitude)))
    K1, K2 = (np.asarray(design.gains[k], dtype=float) for k in ("K1", "K2"))
    for j, (zeta, wn) in enumerate(zip(zetas, wns, strict=True)):
        roots = np.roots([1.0, K2[j], K1[j]])
        if zeta <= 1.0:  # python-control's damping and natural frequency of s^2 + K2 s + K1
            wn_c, zeta_c, _ = control.damp(control.tf([1.0], [1.0, K2[j], K1[j]]), doprint=False)
            assert wn_c == pytest.approx([wn, wn], rel=1e-6 if zeta == 1.0 else 1e-12)
            assert zeta_c == pytest.approx([zeta, zeta], rel=1e-6 if zeta == 1.0 else 1e-12)
        else:  # two real roots: wn is their geometric mean, zeta their arithmetic over geometric mean
            assert np.all(np.isreal(roots)) and np.all(roots.real < 0)
            a, b = -roots.real
            assert math.sqrt(a * b) == pytest.approx(wn, rel=1e-12)
            assert (a + b) / (2 * math.sqrt(a * b)) == pytest.approx(zeta, rel=1e-12)
        requested = np.array(design.poles[2 * j:2 * j + 2], dtype=complex)
        assert _matched_error(roots, requested) < (1e-6 if zeta == 1.0 else 1e-12)


# ----------------------------------------------------------------------------- model mismatch


def _payload_run(model_payload: float) -> tuple[float, np.ndarray, np.ndarray, object, object]:
    model = f"{{payload: {{mass: {model_payload}, link: 2}}}}"
    text = _spec("{kind: robot, robot: planar2r, payload: {mass: 2.0, link: 2}}",
                 f"{{kind: computed_torque, poles: [-10, -10], model: {model}}}", (0.0, 0.0), (1.0, -0.5), duration=3.0)
    loaded = parse_spec(text)
    true_plant = plant_of(loaded)
    design = design_of(loaded, true_plant)
    res = build(loaded.spec, design, plant=true_plant).run()
    qD = _quintic(res.time, (0.0, 0.0), (1.0, -0.5))[0]
    err = res.state[:, :2] - qD
    return float(np.max(np.abs(err))), err[-1], res.state[-1, :2], true_plant, design.plant


def test_tracking_error_grows_with_the_payload_the_model_leaves_out():
    peaks, finals, rest = [], [], []
    for model_payload in (2.0, 1.8, 1.5, 1.0):  # exact, then 10 %, 25 %, 50 % of the payload missing
        peak, final, q_end, true_plant, model = _payload_run(model_payload)
        peaks.append(peak)
        finals.append(final)
        rest.append((q_end, true_plant, model))
    assert peaks[0] < 1e-8  # exact model: integrator precision
    assert peaks[1] > 1e-3  # a tenth of the payload missing is visible
    assert peaks[1] < peaks[2] < peaks[3], peaks
    # at rest (the poles at -10 1/s have decayed 2 s after the move) the law balances the missing weight:
    # K1 M^(q) (qD - q) = g(q) - g^(q), from the model layer's own mass matrix and gravity torques
    for (q_end, true_plant, model), final in zip(rest[1:], finals[1:], strict=True):
        robot = model.robot
        g_true = robot.functions["gravity_torque"](q_end, true_plant.parameter_vector).full().ravel()
        g_model = robot.functions["gravity_torque"](q_end, model.parameter_vector).full().ravel()
        M_model = robot.functions["mass_matrix"](q_end, model.parameter_vector).full()
        # K1 = 100 1/s^2: the requested (s + 10)^2 = s^2 + 20 s + 100
        predicted = -np.linalg.solve(100.0 * M_model, g_true - g_model)  # e = q - qD
        assert final == pytest.approx(predicted, rel=1e-4, abs=1e-9)


# ----------------------------------------------------------------------------- bad input through the CLI


PUMA_CT = f"""\
name: bad-ct
plant: {{kind: robot, robot: puma560PLANT}}
controller: {{kind: computed_torque, CONTROLLER}}
simulation: {{duration: 1.0, initial_position: {list(PUMA_Q0)}, trajectory: {{kind: quintic, amplitude: AMPLITUDE,
  duration: 0.5}}}}
"""


def _bad(plant: str = "", controller: str = "damping: 1, natural_frequency: 10", amplitude: str = "0.1") -> str:
    return (PUMA_CT.replace("PLANT", plant).replace("CONTROLLER", controller).replace("AMPLITUDE", amplitude))


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (_bad(plant=", payload: {mass: 1.0, link: 7}"), "plant.payload.link: this robot has links 1..6, got 7"),
        ("name: bad-ct\nplant: {kind: robot, robot: planar2r, payload: {mass: 1.0, link: 3}}\n"
         "controller: {kind: computed_torque, poles: [-10, -10]}\n", "plant.payload.link:"),
        (_bad(controller="damping: 1, natural_frequency: 10, model: {payload: {mass: 1.0, link: 7}}"),
         "controller.model.payload.link: this robot has links 1..6, got 7"),
        (_bad(controller="damping: 1, natural_frequency: 10, model: {parameters: {m9: 1.0}}"),
         "controller.model.parameters.m9: unknown parameter"),
        (_bad(controller="damping: 1, natural_frequency: 10, model: {parameters: {m2: -1.0}}"),
         "controller.model.parameters.m2:"),
        (_bad(amplitude="[0, 0, 4.0, 0, 0, 0]"), "simulation.trajectory: joint 3 leaves its limits"),
        (_bad(controller="poles: [[-10, -10], [-10, -10]]"), "controller.poles: needs one pair of poles per joint (6)"),
        (_bad(controller="poles: [-10, -10, -12]"), "controller.poles: must list exactly 2 poles per joint, got 3"),
        (_bad(controller="poles: [[-1, -2], [-1, -2, -3], [-1, -2], [-1, -2], [-1, -2], [-1, -2]]"),
         "controller.poles[1]: must list exactly 2 poles per joint, got 3"),
        (_bad(controller="damping: [1, 1], natural_frequency: 10"), "controller.damping"),
    ],
    ids=["plant-payload-link", "planar2r-payload-link", "model-payload-link", "model-unknown-parameter",
         "model-negative-mass", "trajectory-joint-limits", "pole-pairs-count", "three-poles", "pair-of-three",
         "damping-length"],
)
def test_bad_input_exits_2_with_the_key_path(tmp_path, capsys, text, message):
    assert_bad_input(tmp_path, capsys, text, message)
