"""The sliding-mode servo on the linear plant kinds (:mod:`designkit.families.sliding_mode.linear`).

Independent routes: the surface's sliding motion against the eigenvalues of the reduced system formed here with
NumPy; the switching gains against the model error ``g = cA - (cB/cB0) cA0`` over cB evaluated on a dense grid of the
box from matrices written here; ``s s' < 0`` of the law written here at random states of random plants of the box;
the boundary-layer law's run against ``scipy.integrate.solve_ivp`` of the loop written by hand (a short run);
the refusals with their key paths.
"""

from __future__ import annotations

from pathlib import Path

import control
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from designkit.errors import SpecError
from designkit.pipeline import design as synthesize
from designkit.pipeline import run
from designkit.schema.loader import load_spec, parse_spec

SPEC = Path(__file__).resolve().parents[3] / "specs" / "sliding-mode-third-order-drive.yaml"


def _drive(wn, zeta, K=1.0):
    A = np.array([[0, 1, 0], [0, 0, 1], [0, -wn * wn, -2 * zeta * wn]], float)
    return A, np.array([0.0, 0.0, K * wn * wn])


def test_surface_and_switching_gains_over_the_box():
    d = synthesize(load_spec(SPEC))
    info = d.data
    c, k, cA0 = (np.array(v) for v in (info.c, info.k, info.cA0))
    A0, B0 = _drive(40.0, 0.05)
    assert c @ B0 == pytest.approx(1.0, rel=1e-12)
    N = np.linalg.svd(c[None, :])[2][1:].T
    reduced = N.T @ (np.eye(3) - np.outer(B0, c) / (c @ B0)) @ A0 @ N
    assert np.allclose(np.sort(np.linalg.eigvals(reduced).real), [-10.0, -8.0], rtol=1e-9)
    rng = np.random.default_rng(0)
    worst = 0.0
    for wn in np.linspace(36.0, 44.0, 17):
        for zeta in np.linspace(0.03, 0.08, 11):
            A, B = _drive(wn, zeta)
            g = (c @ A - (c @ B) * cA0) / (c @ B)
            assert np.all(np.abs(g) <= k + 1e-12)
            worst = max(worst, float(np.max(np.abs(g) - k / 1.2)))
            # s s' < 0 with the law written here, |xi| <= 0.2, at random error states off the surface
            for _ in range(5):
                x = rng.normal(size=3) * [1.0, 10.0, 100.0]
                xi = rng.uniform(-0.2, 0.2)
                s = c @ x
                u = -cA0 @ x - (info.k0 + k @ np.abs(x)) * np.sign(s)
                assert s * (c @ (A @ x + B * (u + xi))) < 0
    assert worst == pytest.approx(0.0, abs=1e-9)  # the margin is exactly 20 % over the grid's worst corner


def test_example_certificate_and_run():
    result = run(parse_spec(SPEC.read_text().replace("duration: 2.0", "duration: 0.6")))
    checks = {c.name: c for c in result.checks}
    for name in ("sliding_linear_orientation", "sliding_linear_switching", "sliding_linear_reaching",
                 "sliding_linear_band"):
        assert checks[name].passed is True, name


LAG = "{kind: transfer_function, num: [a], den: [1, 3, 2], parameters: {a: 2.0}, uncertainty: {a: [1.6, 2.4]}}"


def test_boundary_layer_run_on_a_lag_against_solve_ivp():
    spec = parse_spec(f"""
name: sm-lag
plant: {LAG}
controller: {{kind: sliding_mode, sliding_poles: [-5], perturbation_bound: 0.1, boundary_layer: 0.01}}
simulation: {{duration: 0.5, step: 1.0}}
""")
    result = run(spec)
    info = result.design.data
    assert info.u_rest == pytest.approx(1.0 / control.dcgain(control.tf([2.0], [1.0, 3.0, 2.0])), rel=1e-12)
    A, B = np.array([[0.0, 1.0], [-2.0, -3.0]]), np.array([0.0, 2.0])  # observable form: x1 = y, x2 = y'
    c, k, cA0, rest = (np.array(v, float) for v in (info.c, info.k, info.cA0, info.x_rest))

    def law(x):
        xt = x - rest
        return info.u_rest - cA0 @ xt - (info.k0 + k @ np.abs(xt)) * np.clip(c @ xt / 0.01, -1.0, 1.0)

    sim = result.simulation
    t = np.asarray(sim.time)
    ref = solve_ivp(lambda _t, x: A @ x + B * law(x), (0.0, t[-1]), np.asarray(sim.state)[0], t_eval=t,
                    rtol=1e-10, atol=1e-12, method="LSODA")
    assert np.max(np.abs(np.asarray(sim.state)[:, 0] - ref.y[0])) < 1e-5
    assert {c.name: c.passed for c in result.checks}["sliding_linear_reaching"] is True


@pytest.mark.parametrize(("plant", "controller", "path"), [
    ("{kind: state_space, A: [[-1, 0], [0, -2]], B: [[1], [0]], C: [[1, 1]]}",
     "{kind: sliding_mode, sliding_poles: [-5], perturbation_bound: 0.1}", "plant.B"),
    (LAG, "{kind: sliding_mode, sliding_poles: [-5, -6], perturbation_bound: 0.1}", "controller.sliding_poles"),
    (LAG, "{kind: sliding_mode, sliding_poles: [-5], perturbation_bound: 0.1, alpha: 1.0}", "controller.alpha"),
])
def test_refusals_name_the_key(plant, controller, path):
    text = f"name: x\nplant: {plant}\ncontroller: {controller}\nsimulation: {{duration: 0.5, step: 1.0}}\n"
    with pytest.raises(SpecError) as info:
        synthesize(parse_spec(text))
    assert info.value.path == path
