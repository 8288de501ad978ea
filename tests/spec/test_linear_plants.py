"""The ``transfer_function`` and ``state_space`` plant sections: through the spec (API) and ``designkit synth``
(CLI), good sections give the plant python-control gives for the same numbers, bad ones exit 2 naming the key."""

from __future__ import annotations

import json

import control
import numpy as np
import pytest

from designkit.cli import main
from designkit.errors import SpecError
from designkit.schema.loader import parse_spec
from designkit.spec.plant_builder import plant_from_spec
from tests.cli_input import assert_bad_input

REG2 = "{kind: state_regulator, poles: [-6, -8]}"
TF = ("{kind: transfer_function, num: [Km], den: [tau, 1, 0], parameters: {Km: 2.0, tau: 0.5}, "
      "uncertainty: {Km: [1.6, 2.4], tau: [0.4, 0.6]}}")


def _spec(plant: str, controller: str = REG2) -> str:
    return f"name: linear-plant\nplant: {plant}\ncontroller: {controller}\n"


def test_an_uncertainty_box_over_entry_parameters_moves_the_plant_to_each_corner():
    loaded = parse_spec(_spec(TF))
    plant = plant_from_spec(loaded.spec.plant)
    box = loaded.spec.plant.uncertainty.intervals
    assert set(box) == {"Km", "tau"}
    s = 1j * np.array([0.3, 2.0, 11.0])
    for Km in box["Km"]:
        for tau in box["tau"]:
            A, B, C, D = plant.with_params(Km=Km, tau=tau).matrices()
            mine = np.array([complex(np.squeeze(control.ss(A, B, C, D)(x))) for x in s])
            ref = np.array([complex(np.squeeze(control.tf([Km], [tau, 1, 0])(x))) for x in s])
            assert np.allclose(mine, ref, rtol=1e-12)


@pytest.mark.parametrize(("plant", "message"), [
    ("{kind: transfer_function, num: [1, 2, 3, 4], den: [1, 2, 0]}", "plant.num: has degree 3 above"),
    ("{kind: transfer_function, num: [1, 2, 3], den: [1, 2, 0]}", "plant.num: has the degree of the denominator"),
    ("{kind: transfer_function, num: [1], den: [0, 1, 2]}", "plant.den[0]: the leading coefficient is 0"),
    ("{kind: transfer_function, num: [0, 1], den: [1, 1, 2]}", "plant.num[0]: the leading coefficient is 0"),
    ("{kind: transfer_function, num: [c], den: [1, 1, 0], parameters: {a: 1}}", "plant.num[0]: unknown parameter 'c'"),
    ("{kind: transfer_function, num: ['2**a'], den: [1, 1, 0], parameters: {a: 1}}", "plant.num[0]: cannot read"),
    ("{kind: transfer_function, num: [1], den: [1, 1, 0], dt: 0}", "plant.dt: must be positive"),
    ("{kind: transfer_function, num: [1], den: [1, 1, 0], dt: -0.01}", "plant.dt: must be positive"),
    ("{kind: transfer_function, num: [1], den: [1, 1, 0], dt: 0.01}",
     "plant.dt: the state_regulator controller does not use it: it designs and simulates a continuous-time loop"),
    ("{kind: transfer_function, num: [1], den: [1, 1, 0], dt: .inf}", "plant.dt: Input should be a finite number"),
    ("{kind: transfer_function, num: [1], den: [1, 1, 0], parameters: {a: 1}, uncertainty: {b: [1, 2]}}",
     "plant.uncertainty.b: unknown parameter"),
    ("{kind: transfer_function, num: [1], den: [tau, 1, 0], parameters: {tau: 1}, uncertainty: {tau: [0, 2]}}",
     "plant.uncertainty.tau: makes plant.den[0] = 0"),
    ("{kind: transfer_function, num: [1], den: [1, 1e13, 0]}", "plant.den[1]"),
    ("{kind: state_space, A: [[0, 1], [0]], B: [[0], [1]], C: [[1, 0]]}", "plant.A[1]: needs 2 entries"),
    ("{kind: state_space, A: [[0, 1], [0, 0]], B: [[0]], C: [[1, 0]]}", "plant.B: needs 2 rows"),
    ("{kind: state_space, A: [[0, 1], [0, 0]], B: [[0], [1]], C: [[1]]}", "plant.C[0]: needs 2 entries"),
    ("{kind: state_space, A: [[0, 1], [0, 0]], B: [[0], [1]], C: [[1, 0]], D: [[1]]}", "plant.D[0][0]"),
    ("{kind: state_space, A: [[0, .nan], [0, 0]], B: [[0], [1]], C: [[1, 0]]}", "plant.A[0][1]"),
    ("{kind: state_space, A: [[0, 1], [0, 0]], B: [[0], [1]], C: [[1, 0]], states: [p]}", "plant.states: needs 2"),
    ("{kind: state_space, A: [[0, 1], [0, 0]], B: [[0], [1]], C: [[1, 0]], dt: 0.001}",
     "plant.dt: the state_regulator controller does not use it"),
])
def test_bad_linear_plants_exit_2_naming_the_key(plant, message, tmp_path, capsys):
    assert_bad_input(tmp_path, capsys, _spec(plant), message)
    with pytest.raises(SpecError) as info:  # the API says the same
        plant_from_spec(parse_spec(_spec(plant)).spec.plant)
    assert message.split(":")[0] in str(info.value)


@pytest.mark.parametrize(("plant", "controller", "message"), [
    ("{kind: state_space, A: [[0, 1, 0], [0, 0, 1], [0, 0, 0]], B: [[0, 0], [1, 0], [0, 1]], C: [[1, 0, 0]]}",
     "{kind: state_regulator, poles: [-2, -2, -2]}", "controller.poles: "),
    ("{kind: state_space, A: [[-1, 0], [0, -2]], B: [[1, 2], [0, 0]], C: [[1, 1]]}", REG2,
     "plant.B: (A, B) is not controllable"),
    (TF, "{kind: state_regulator, poles: [-6, -8, -9]}", "controller.poles: the transfer_function plant has 2 states"),
    ("{kind: transfer_function, num: [1], den: [1, 3]}", "{kind: pid_servo, poles: [-4, -5, -20]}",
     "controller.poles: must list exactly 2 poles on a first-order transfer_function plant"),
    ("{kind: transfer_function, num: [1], den: [1, 3, 3, 1]}", "{kind: pid_tracking, poles: [-4, -5, -20]}",
     "controller.kind: pid_tracking makes y follow xD through the plant's inverse"),
    ("{kind: transfer_function, num: [1, 1], den: [1, 3, 2]}", "{kind: state_regulator, poles: [-6, -8]}",
     "plant.num: shares a root with plant.den"),
])
def test_designs_the_families_cannot_make_exit_2_with_the_reason(plant, controller, message, tmp_path, capsys):
    assert_bad_input(tmp_path, capsys, _spec(plant, controller), message)


def test_schema_lists_the_linear_plant_kinds(capsys):
    assert main(["schema"]) == 0
    schema = json.loads(capsys.readouterr().out)
    text = json.dumps(schema)
    assert '"transfer_function"' in text and '"state_space"' in text


def test_a_plant_change_moves_the_entries_that_name_the_parameter():
    """From t = 0 the true motor has twice the designed inertia: the simulated step equals python-control's step of
    ``num (K1 + K3 K4) s + K3 num`` over ``s den + num (K2 s^2 + K1 s + K3)`` at the true inertia."""
    from designkit.pipeline import run

    text = ("name: plant-change\nplant: {kind: transfer_function, num: [Kt], den: [J, B, 0], "
            "parameters: {Kt: 0.05, J: 2.0e-4, B: 1.0e-3}}\n"
            "controller: {kind: pid_servo, poles: [-20, -25, -60], zero: -15}\n"
            "simulation: {duration: 1.0, plant_change: {time: 0.0, values: {J: 4.0e-4}}}\n")
    result = run(parse_spec(text))
    K1, K2, K3, K4 = (float(result.design.gains[k]) for k in ("K1", "K2", "K3", "K4"))
    num, den = [0.05], [4.0e-4, 1.0e-3, 0.0]
    closed = control.tf(np.polymul(num, [K1 + K3 * K4, K3]),
                        np.polyadd(np.polymul([1.0, 0.0], den), np.polymul(num, [K2, K1, K3])))
    sim = result.simulation
    t = np.asarray(sim.time)
    ref = control.step_response(closed, t).outputs
    y = np.asarray(sim.state)[:, result.plant.positions[0]]
    step = np.asarray(sim.reference)[:, 0, 0]
    assert np.allclose(step[t > 0], step[-1])  # one step, held
    assert np.max(np.abs(y - step[-1] * ref)) < 1e-4 * abs(step[-1])
    # the designed (nominal) loop differs by much more: the change is in the simulated plant
    nominal = control.tf(np.polymul(num, [K1 + K3 * K4, K3]),
                         np.polyadd(np.polymul([1.0, 0.0], [2.0e-4, 1.0e-3, 0.0]), np.polymul(num, [K2, K1, K3])))
    assert np.max(np.abs(y - step[-1] * control.step_response(nominal, t).outputs)) > 1e-2 * abs(step[-1])
