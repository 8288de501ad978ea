"""Model summary: operation counts, tables, timing section, CLI entry point."""

from __future__ import annotations

import shutil

import casadi
import pytest

from designkit.errors import ModelError
from designkit.models.robots import robot
from designkit.models.summary import evaluation_cost, model_command, model_summary, operation_counts


@pytest.fixture(autouse=True)
def private_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("DESIGNKIT_CACHE_DIR", str(tmp_path))


def test_operation_counts_of_a_known_expression():
    x = casadi.SX.sym("x", 3)
    y = x[0] * x[1] - x[2] * x[2] + casadi.sin(x[0]) / x[1] + 3 * casadi.cos(x[2])  # x*x is OP_SQ: a multiplication
    c = operation_counts(casadi.Function("f", [x], [y]))
    assert (c.multiplications, c.additions, c.divisions, c.trigonometric) == (3, 3, 1, 2)
    twice = operation_counts(casadi.Function("t", [x], [2 * x[0]]))  # CasADi writes 2*x as x+x
    assert (twice.multiplications, twice.additions) == (0, 1)
    assert c.instructions == casadi.Function("f", [x], [y]).n_instructions()


def test_operation_counts_expand_mx():
    x = casadi.MX.sym("x", 2)
    c = operation_counts(casadi.Function("g", [x], [x[0] * x[1] + x[0]]))
    assert (c.multiplications, c.additions) == (1, 1)


def test_puma_inverse_dynamics_is_small():
    """Goal from the project brief: at most 730 CasADi instructions (the notes' RNEA: 852 mul, 738 add)."""
    c = operation_counts(robot("puma560").functions["inverse_dynamics"])
    assert c.instructions <= 730
    assert c.multiplications < 852 and c.additions < 738


def test_summary_without_timing():
    text = model_summary(robot("planar2r"), timing=False)
    assert text.startswith("planar2r: 2 joints, standard DH, gravity (0, -9.81, 0) m/s^2")
    assert "joint1" in text and "joint2" in text
    assert "base parameters: 6 of 20" in text
    assert "inverse_dynamics" in text and "Evaluation cost" not in text
    rows = [line.split() for line in text.splitlines() if line.split()[:1] == ["inverse_dynamics"]]
    ops = operation_counts(robot("planar2r").functions["inverse_dynamics"])
    assert rows[0][1:4] == [str(ops.instructions), str(ops.multiplications), str(ops.additions)]


def test_summary_with_timing_compiled():
    text = model_summary(robot("onelink"))
    section = text.split("Evaluation cost")[1]
    assert "C batch" in section
    row = next(line for line in section.splitlines() if line.startswith("inverse_dynamics")).split()
    assert len(row) == 5 and all(float(v) > 0 for v in row[1:])


def test_summary_without_compiler(monkeypatch):
    monkeypatch.setattr(shutil, "which", lambda name: None)
    text = model_summary(robot("onelink"), base=False)
    assert "n/a (no C compiler found" in text


def test_model_command():
    text = model_command("scara", timing=False)
    assert text.splitlines()[0].startswith("scara: 4 joints")
    assert "prismatic" in text
    with pytest.raises(ModelError, match="unknown robot"):
        model_command("r2d2")


def test_evaluation_cost_is_positive():
    x = casadi.SX.sym("x", 2)
    cost = evaluation_cost(casadi.Function("f", [x], [x * x]), batch=100, repeats=2)
    assert cost.single_us > 0 and cost.batched_us > 0 and cost.batch == 100 and not cost.compiled
