"""NumPy evaluation: one state or a batch (leading axis N), argument errors that name the argument, and the
fast path (zero-copy buffers, compiled blocks): same results as the interpreted Function, its compilation
policy, the on-disk cache, and the fallback without a compiler."""

from __future__ import annotations

import copy
import subprocess

import casadi as ca
import numpy as np
import pytest

from designkit.errors import ModelError
from designkit.models import batch, codegen
from designkit.models.batch import BLOCK, CHUNK, MAX_MAPS, Evaluator, evaluate, shape_output
from designkit.models.robots import robot
from tests.models.support import random_states, scaled_error

needs_cc = pytest.mark.skipif(codegen.find_compiler() is None, reason="no C compiler on PATH")

TOL_COMPILED = 1e-12
"""Compiled vs interpreted (scaled); with ``codegen.EXACT_FLAGS`` they agree bit for bit (test_codegen.py)."""

SIZES = (1, 5, BLOCK, 3 * BLOCK + 5, CHUNK + BLOCK + 3)
"""Batch sizes: one row, part of a block, one block, whole blocks plus a part (all copied into the evaluator's
arrays), and a batch evaluated in place with a last part."""


@pytest.fixture(autouse=True)
def cache(tmp_path, monkeypatch):
    """A private, empty code-generation cache for every test."""
    monkeypatch.setenv("DESIGNKIT_CACHE_DIR", str(tmp_path))
    return tmp_path / "codegen"


def libraries(cache) -> list:
    return sorted(cache.glob("*.so")) if cache.exists() else []


def reference(function: ca.Function, rows: tuple[np.ndarray, ...], p: np.ndarray | None = None) -> np.ndarray:
    """The independent route: ``function.map(N)`` called on ``casadi.DM`` columns, stacked ``(N, r, c)``."""
    count = rows[0].shape[0]
    extra = [] if p is None else [ca.DM(np.tile(np.asarray(p, dtype=float).reshape(-1, 1), (1, count)))]
    out = function.map(count)(*[ca.DM(x.T) for x in rows], *extra)
    r, c = function.size_out(0)
    return np.array(ca.densify(out if function.n_out() == 1 else out[0])).reshape(r, count, c).transpose(1, 0, 2)


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
        batch_out = method(*args)
        assert batch_out.shape == shape
        for k in range(4):
            assert np.array_equal(batch_out[k], method(*(a[k] for a in args)))
    energy = arm.energy(q, qd)
    assert energy.kinetic.shape == (4,) and isinstance(arm.energy(q[0], qd[0]).total, float)
    # a single state broadcasts against a batch
    assert np.array_equal(arm.inverse_dynamics(q[0], qd, qdd)[1], arm.inverse_dynamics(q[0], qd[1], qdd[1]))
    assert arm.inverse_dynamics(np.zeros((0, 2)), np.zeros((0, 2)), np.zeros((0, 2))).shape == (0, 2)


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
    evaluators: dict = {}
    outputs, n = evaluate(f, [("x", np.ones((3, 2)))], None, symbol_names=(), evaluators=evaluators)
    assert n == 3 and list(evaluators) == ["f"]
    assert shape_output(outputs[0], "scalar", n).tolist() == [2.0, 2.0, 2.0]
    for size in range(2, MAX_MAPS + 3):
        evaluate(f, [("x", np.ones((size, 2)))], None, symbol_names=(), evaluators=evaluators)
    assert 0 < len(evaluators["f"]._runners) <= MAX_MAPS
    single, none = evaluate(f, [("x", [1.0, 2.0])], None, symbol_names=(), evaluators=evaluators)
    assert none is None and shape_output(single[0], "scalar", none) == 5.0


# ----------------------------------------------------------------------------- the fast path

PUMA_CASES = {  # name -> inputs (by position in (q, qd, qdd))
    "inverse_dynamics": 3, "mass_matrix": 1, "gravity_torque": 1, "forward_dynamics": 3,
    "regressor": 3,  # sparse output
    "fkine_all": 1, "kinetic_energy": 2,
}


def _check_all_sizes(arm, name: str, inputs: int, rng: np.random.Generator, p=None) -> None:
    f = arm.functions[name]
    evaluator = arm.evaluator(name)
    for count in SIZES:
        rows = random_states(rng, arm.n, count)[:inputs]
        out, _ = evaluate(f, [(str(k), x) for k, x in enumerate(rows)], p, symbol_names=arm.symbol_names,
                          evaluators=arm._evaluators)
        assert out[0].shape == (count, *f.size_out(0))
        assert scaled_error(out[0], reference(f, rows, p)) < TOL_COMPILED, (name, count, evaluator.why)
    single = [x[0] for x in random_states(rng, arm.n, 1)[:inputs]]
    out, n = evaluate(f, [(str(k), x) for k, x in enumerate(single)], p, symbol_names=arm.symbol_names,
                      evaluators=arm._evaluators)
    assert n is None and out[0].shape == f.size_out(0)
    assert scaled_error(out[0], reference(f, tuple(x[None] for x in single), p)[0]) < TOL_COMPILED


@needs_cc
@pytest.mark.parametrize("name", sorted(PUMA_CASES))
def test_fast_path_gives_the_interpreted_results(name, cache):
    arm = robot("puma560", friction=True, motor_inertia=True)
    rng = np.random.default_rng(sum(map(ord, name)))
    _check_all_sizes(arm, name, PUMA_CASES[name], rng)  # interpreted (nothing cached, small batches)
    assert not arm.evaluator(name).compiled and libraries(cache) == []
    assert arm.evaluator(name).compile(), arm.evaluator(name).why
    _check_all_sizes(arm, name, PUMA_CASES[name], rng)  # compiled blocks
    assert len(libraries(cache)) == 1


@needs_cc
def test_fast_path_of_a_symbolic_robot_takes_p(cache):
    arm = robot("planar2r", symbolic=True, friction=True)
    rng = np.random.default_rng(7)
    values = [rng.uniform(0.5, 2.0, len(arm.symbol_names)) for _ in range(2)]
    for name, inputs in (("inverse_dynamics", 3), ("mass_matrix", 1), ("coriolis_matrix", 2)):
        for compiled in (False, True):
            if compiled:
                assert arm.evaluator(name).compile(), arm.evaluator(name).why
            for p in values:  # p changes between calls: the shared input is refreshed
                _check_all_sizes(arm, name, inputs, rng, p)
            assert arm.evaluator(name).compiled == compiled
    q, qd, qdd = random_states(rng, 2, 40)
    tau = arm.inverse_dynamics(q, qd, qdd, p=values[0])
    assert scaled_error(tau[:, :, None], reference(arm.functions["inverse_dynamics"], (q, qd, qdd), values[0])) \
        < TOL_COMPILED


@needs_cc
def test_small_batches_never_compile_and_large_ones_do(cache, monkeypatch):
    monkeypatch.setattr(batch, "COMPILE_MIN_STATES", 2 * BLOCK + 1)
    arm = robot("puma560")
    q, qd, qdd = random_states(np.random.default_rng(8), 6, 2 * BLOCK + 1)
    small = arm.inverse_dynamics(q[:2 * BLOCK], qd[:2 * BLOCK], qdd[:2 * BLOCK])
    arm.inverse_dynamics(q[0], qd[0], qdd[0])
    evaluator = arm.evaluator("inverse_dynamics")
    assert not evaluator.compiled and "do not compile" in evaluator.why and libraries(cache) == []
    large = arm.inverse_dynamics(q, qd, qdd)
    assert evaluator.compiled and "built" in evaluator.why and evaluator.library in libraries(cache)
    assert scaled_error(large[:2 * BLOCK], small) < TOL_COMPILED


@needs_cc
def test_a_cached_library_is_loaded_not_compiled(cache, monkeypatch):
    first = robot("puma560")
    assert first.evaluator("mass_matrix").compile()
    built = libraries(cache)

    def no_compiler(*args, **kwargs):
        raise AssertionError("the compiler ran although the library is cached")

    monkeypatch.setattr(subprocess, "run", no_compiler)
    second = robot("puma560")  # a new robot, same function: a small batch finds the library
    q = random_states(np.random.default_rng(9), 6, 3)[0]
    M = second.mass_matrix(q[:2])  # (single states have their own library: test_one_state.py)
    evaluator = second.evaluator("mass_matrix")
    assert evaluator.compiled and "cache" in evaluator.why and evaluator.library == built[0]
    assert libraries(cache) == built
    assert scaled_error(M, reference(second.functions["mass_matrix"], (q[:2],))) < TOL_COMPILED


def test_without_a_compiler_everything_runs_interpreted(cache, monkeypatch):
    monkeypatch.setattr(codegen, "find_compiler", lambda: None)
    monkeypatch.setattr(batch, "COMPILE_MIN_STATES", BLOCK)
    arm = robot("puma560")
    rows = random_states(np.random.default_rng(10), 6, 3 * BLOCK + 5)
    tau = arm.inverse_dynamics(*rows)
    evaluator = arm.evaluator("inverse_dynamics")
    assert not evaluator.compiled and "no C compiler" in evaluator.why
    assert not evaluator.compile() and not cache.exists()
    assert scaled_error(tau[:, :, None], reference(arm.functions["inverse_dynamics"], rows)) < TOL_COMPILED


@needs_cc
def test_a_failed_compilation_falls_back_once(cache, monkeypatch):
    monkeypatch.setattr(codegen, "EXACT_FLAGS", ("-fPIC", "-shared", "-Wl,--bogus-flag"))
    monkeypatch.setattr(batch, "COMPILE_MIN_STATES", BLOCK)
    calls = []
    real_run = subprocess.run
    monkeypatch.setattr(subprocess, "run", lambda *a, **k: calls.append(a) or real_run(*a, **k))
    arm = robot("planar2r")
    rows = random_states(np.random.default_rng(11), 2, 2 * BLOCK)
    first = arm.gravity_torque(rows[0])
    again = arm.gravity_torque(rows[0])
    evaluator = arm.evaluator("gravity_torque")
    assert not evaluator.compiled and "compilation failed" in evaluator.why and len(calls) == 1
    assert np.array_equal(first, again) and libraries(cache) == []
    assert scaled_error(first[:, :, None], reference(arm.functions["gravity_torque"], rows[:1])) < TOL_COMPILED


def test_an_evaluator_without_per_state_inputs_stays_interpreted():
    p = ca.SX.sym("p", 2)
    f = ca.Function("params", [p], [2 * p], ["p"], ["P"])
    evaluator = Evaluator(f, shared=1)
    out = evaluator([], [np.array([1.0, 3.0])], 1)
    assert out[0].tolist() == [[[2.0], [6.0]]] and not evaluator.compile()
    assert robot("planar2r", symbolic=True).parameter_values(p=np.ones(9)).shape == (20,)


def test_a_copied_robot_gets_its_own_evaluators():
    arm = robot("planar2r")
    q, qd, qdd = random_states(np.random.default_rng(12), 2, 3)
    tau = arm.inverse_dynamics(q, qd, qdd)
    twin = copy.deepcopy(arm)
    assert twin.evaluator("inverse_dynamics") is not arm.evaluator("inverse_dynamics")
    assert np.array_equal(twin.inverse_dynamics(q, qd, qdd), tau)
