"""The variable structure regulator on the linear plant kinds.

Independent routes: the sliding motion's poles of the example's surface against the eigenvalues of the reduced
system formed here with NumPy; the ranges of ``l_i = -(cA)_i/(cB)`` against a dense grid of the box evaluated on the
matrices written here; the rest of a non-integrating plant against ``control.dcgain``; the boundary-layer law's run
against ``scipy.integrate.solve_ivp`` of the loop written by hand (a short run); the refusal of an uncontrollable
plant with its key path.
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

SPEC = Path(__file__).resolve().parents[3] / "specs" / "vsc-third-order-drive.yaml"


def _drive(wn, zeta, K=1.0):
    A = np.array([[0, 1, 0], [0, 0, 1], [0, -wn * wn, -2 * zeta * wn]], float)
    return A, np.array([0.0, 0.0, K * wn * wn])


def test_third_order_drive_surface_and_gain_ranges():
    d = synthesize(load_spec(SPEC))
    c = np.array(d.data.c)
    A, B = _drive(40.0, 0.05)
    # the sliding motion on c x = 0 under the equivalent control, in a basis of ker c (NumPy SVD)
    N = np.linalg.svd(c[None, :])[2][1:].T
    reduced = N.T @ (np.eye(3) - np.outer(B, c) / (c @ B)) @ A @ N
    assert np.allclose(np.sort(np.linalg.eigvals(reduced).real), [-10.0, -8.0], rtol=1e-9)
    # alpha_i < l_i < beta_i on a dense grid of the box
    for wn in np.linspace(36.0, 44.0, 9):
        for zeta in np.linspace(0.03, 0.08, 6):
            Av, Bv = _drive(wn, zeta)
            l = -(c @ Av) / (c @ Bv)
            assert np.all(np.array(d.data.alpha) < l) and np.all(l < np.array(d.data.beta))
            assert c @ Bv > 0


def test_third_order_drive_certificate_and_run():
    result = run(parse_spec(SPEC.read_text().replace("duration: 2.0", "duration: 0.6")))
    checks = {c.name: c for c in result.checks}
    for name in ("vsc_orientation", "vsc_relay", "vsc_gains_enclosed", "vsc_band", "vsc_sliding_poles"):
        assert checks[name].passed is True, name


PLANT = "{kind: transfer_function, num: [a], den: [1, 3, 2], parameters: {a: 2.0}, uncertainty: {a: [1.6, 2.4]}}"


def test_non_integrating_plant_rest_and_boundary_layer_run_against_solve_ivp():
    spec = parse_spec(f"""
name: vsc-lag
plant: {PLANT}
controller: {{kind: vsc, sliding_poles: [-5], relay_amplitude: 0.5, boundary_layer: 0.05}}
simulation: {{duration: 0.5, step: 1.0}}
""")
    result = run(spec)
    d = result.design
    info = d.data
    # the rest per unit of reference: y = 1 needs u* = 1/G(0)
    assert info.u_rest == pytest.approx(1.0 / control.dcgain(control.tf([2.0], [1.0, 3.0, 2.0])), rel=1e-12)
    # the loop written here: observable canonical form of 2/(s^2 + 3 s + 2), x1 = y, x2 = y'
    A, B = np.array([[0.0, 1.0], [-2.0, -3.0]]), np.array([0.0, 2.0])
    c, al, be = (np.array(v, float) for v in (info.c, info.alpha, info.beta))
    x_rest, eps, delta = np.array(info.rest_direction), 0.05, info.delta

    def law(x):
        xt = x - x_rest * 1.0
        sg = c @ xt
        mid, half = (al + be) / 2, (al - be) / 2
        return info.u_rest + mid @ xt + (half @ np.abs(xt) - delta) * np.clip(sg / eps, -1.0, 1.0)

    sim = result.simulation
    t = np.asarray(sim.time)
    ref = solve_ivp(lambda _t, x: A @ x + B * law(x), (0.0, t[-1]), np.asarray(sim.state)[0], t_eval=t,
                    rtol=1e-10, atol=1e-12, method="LSODA")
    assert np.max(np.abs(np.asarray(sim.state)[:, 0] - ref.y[0])) < 1e-5


def test_uncontrollable_state_space_plant_is_refused_at_plant_B():
    spec = parse_spec("""
name: vsc-uncontrollable
plant: {kind: state_space, A: [[-1, 0], [0, -2]], B: [[1], [0]], C: [[1, 1]]}
controller: {kind: vsc, sliding_poles: [-5], relay_amplitude: 0.5}
simulation: {duration: 0.5, step: 1.0}
""")
    with pytest.raises(SpecError) as info:
        synthesize(spec)
    assert info.value.path == "plant.B" and "not controllable" in info.value.message
