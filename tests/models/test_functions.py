"""The function table: every entry a named casadi.Function with named inputs and outputs."""

from __future__ import annotations

import pytest

from designkit.models.functions import FUNCTION_SPECS
from designkit.models.robots import robot


def test_every_function_is_named_with_named_inputs_and_outputs():
    arm = robot("puma560")
    assert set(arm.functions) >= {
        "fkine", "fkine_all", "jacobian", "jacobian_dot_qd", "analytic_jacobian", "inverse_dynamics",
        "mass_matrix", "coriolis_matrix", "christoffel", "gravity_torque", "forward_dynamics", "regressor",
        "kinetic_energy", "potential_energy",
    }
    for key in arm.functions:
        f = arm.functions[key]
        assert f.name() == key
        assert all(f.name_in()) and all(f.name_out())
    assert arm.functions["inverse_dynamics"].name_in() == ["q", "qd", "qdd"]
    assert arm.functions["forward_dynamics"].name_out() == ["qdd"]


def test_table_lists_every_spec_and_rejects_unknown_names():
    arm = robot("planar2r", symbolic=True)
    assert list(arm.functions) == list(FUNCTION_SPECS) and len(arm.functions) == len(FUNCTION_SPECS)
    assert "nonsense" not in arm.functions
    with pytest.raises(KeyError, match=r"functions\['nonsense'\]: no such function"):
        arm.functions["nonsense"]
    for name, spec in FUNCTION_SPECS.items():
        f = arm.functions[name]
        assert f.name_in() == [*spec.inputs, "p"] and tuple(f.name_out()) == spec.outputs
        assert len(spec.kinds) == len(spec.outputs)
