"""NumPy evaluation: one state or a batch (leading axis N), argument errors that name the argument."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from designkit.errors import ModelError
from designkit.models.batch import MAX_MAPS, evaluate, shape_output
from designkit.models.robots import robot
from tests.models.support import random_states


def test_batches_have_a_leading_axis_and_match_single_calls():
    arm = robot("planar2r", friction=True)
    q, qd, qdd = random_states(np.random.default_rng(43), 2, 4)
    checks = {
        "inverse_dynamics": (lambda *a: arm.inverse_dynamics(*a), (q, qd, qdd), (4, 2)),
        "mass_matrix": (arm.mass_matrix, (q,), (4, 2, 2)),
        "coriolis_matrix": (arm.coriolis_matrix, (q, qd), (4, 2, 2)),
        "gravity_torque": (arm.gravity_torque, (q,), (4, 2)),
        "forward_dynamics": (arm.forward_dynamics, (q, qd, qdd), (4, 2)),
        "regressor": (arm.regressor, (q, qd, qdd), (4, 2, len(arm.parameter_names))),
        "christoffel": (arm.christoffel, (q,), (4, 2, 2, 2)),
        "jacobian_dot_qd": (arm.jacobian_dot_qd, (q, qd), (4, 6)),
    }
    for method, args, shape in checks.values():
        batch = method(*args)
        assert batch.shape == shape
        for k in range(4):
            assert np.array_equal(batch[k], method(*(a[k] for a in args)))
    energy = arm.energy(q, qd)
    assert energy.kinetic.shape == (4,) and isinstance(arm.energy(q[0], qd[0]).total, float)
    # a single state broadcasts against a batch
    assert np.array_equal(arm.inverse_dynamics(q[0], qd, qdd)[1], arm.inverse_dynamics(q[0], qd[1], qdd[1]))


def test_input_errors_name_the_argument():
    arm = robot("planar2r")
    with pytest.raises(ModelError) as info:
        arm.inverse_dynamics(np.zeros(3), np.zeros(2), np.zeros(2))
    assert info.value.path == "q"
    with pytest.raises(ModelError) as info:
        arm.inverse_dynamics(np.zeros((3, 2)), np.zeros((4, 2)), np.zeros(2))
    assert info.value.path == "qd"
    with pytest.raises(ModelError, match="p"):
        robot("planar2r", symbolic=True).mass_matrix(np.zeros(2))
    with pytest.raises(ModelError, match="p"):
        arm.mass_matrix(np.zeros(2), p=[1.0])


def test_mapped_functions_are_memoised_and_the_memo_is_bounded():
    x = ca.SX.sym("x", 2)
    f = ca.Function("f", [x], [ca.sumsqr(x)], ["x"], ["y"])
    maps: dict = {}
    outputs, batch = evaluate(f, [("x", np.ones((3, 2)))], None, symbol_names=(), maps=maps)
    assert batch == 3 and list(maps) == [("f", 3)]
    assert shape_output(outputs[0], "scalar", batch).tolist() == [2.0, 2.0, 2.0]
    for size in range(1, MAX_MAPS + 2):
        evaluate(f, [("x", np.ones((size, 2)))], None, symbol_names=(), maps=maps)
    assert len(maps) <= MAX_MAPS
    single, none = evaluate(f, [("x", [1.0, 2.0])], None, symbol_names=(), maps=maps)
    assert none is None and shape_output(single[0], "scalar", none) == 5.0
