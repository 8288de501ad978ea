"""C code generation: compiled == interpreted, batched maps, the cache, and the no-compiler fallback."""

from __future__ import annotations

import shutil
import subprocess

import casadi
import numpy as np
import pytest

from designkit.models import codegen
from designkit.models.codegen import compile_function
from designkit.models.robots import robot
from tests.models.support import TOL_EXACT, random_states, scaled_error

needs_cc = pytest.mark.skipif(codegen.find_compiler() is None, reason="no C compiler on PATH")


@pytest.fixture(scope="module")
def puma():
    return robot("puma560", friction=True, motor_inertia=True)


@pytest.fixture(scope="module")
def compiled_id(puma, tmp_path_factory):
    """PUMA inverse dynamics (friction and rotors on), compiled once for the module."""
    return compile_function(puma.functions["inverse_dynamics"], directory=tmp_path_factory.mktemp("cg"))


@needs_cc
def test_compiled_matches_interpreted(puma, compiled_id):
    assert compiled_id.compiled, compiled_id.reason
    assert compiled_id.library is not None and compiled_id.library.exists()
    f = puma.functions["inverse_dynamics"]
    q, qd, qdd = random_states(np.random.default_rng(1), 6, 50)
    for k in range(50):
        ref = np.asarray(f(q[k], qd[k], qdd[k]))
        out = compiled_id(q[k], qd[k], qdd[k])["tau"]
        assert scaled_error(out, ref) < TOL_EXACT


@needs_cc
def test_compiled_keeps_names(puma, compiled_id):
    f = puma.functions["inverse_dynamics"]
    g = compiled_id.function
    assert (g.name(), g.name_in(), g.name_out()) == (f.name(), f.name_in(), f.name_out())


@pytest.mark.parametrize("mode", ["serial", "thread"])
def test_batch_matches_single_calls(puma, compiled_id, mode):
    q, qd, qdd = random_states(np.random.default_rng(2), 6, 200)
    batch = compiled_id.evaluate_batch(q, qd, qdd, parallelization=mode, threads=2)["tau"]
    assert batch.shape == (200, 6, 1)
    ref = puma.inverse_dynamics(q, qd, qdd)
    assert scaled_error(batch[:, :, 0], ref) < TOL_EXACT


def test_batch_of_matrix_output(tmp_path):
    x = casadi.SX.sym("x", 3)
    f = casadi.Function("outer", [x], [casadi.mtimes(x, x.T)[:, :2]], ["x"], ["M"])
    X = np.random.default_rng(3).normal(size=(7, 3))
    out = compile_function(f, directory=tmp_path).evaluate_batch(X)["M"]
    assert out.shape == (7, 3, 2)
    np.testing.assert_allclose(out, np.einsum("ni,nj->nij", X, X)[:, :, :2], rtol=1e-14, atol=1e-14)


@needs_cc
def test_cache_hit_does_not_recompile(puma, compiled_id, monkeypatch):
    def no_compiler(*args, **kwargs):
        raise AssertionError("compiler called on a cache hit")

    monkeypatch.setattr(subprocess, "run", no_compiler)
    again = compile_function(puma.functions["inverse_dynamics"], directory=compiled_id.library.parent)
    assert again.compiled and again.library == compiled_id.library


@needs_cc
def test_cache_key_depends_on_source(tmp_path):
    x = casadi.SX.sym("x")
    a = compile_function(casadi.Function("f", [x], [2 * x]), directory=tmp_path)
    b = compile_function(casadi.Function("f", [x], [3 * x]), directory=tmp_path)
    assert a.library != b.library
    assert float(a(1.5)["o0"][0, 0]) == 3.0 and float(b(1.5)["o0"][0, 0]) == 4.5


def test_fallback_without_compiler(puma, tmp_path, monkeypatch):
    monkeypatch.setattr(shutil, "which", lambda name: None)
    f = puma.functions["inverse_dynamics"]
    cf = compile_function(f, directory=tmp_path)
    assert not cf.compiled and "no C compiler" in cf.reason
    assert cf.function is f and cf.library is None
    assert list(tmp_path.iterdir()) == []
    q, qd, qdd = random_states(np.random.default_rng(4), 6, 10)
    out = cf.evaluate_batch(q, qd, qdd)["tau"][:, :, 0]
    assert scaled_error(out, puma.inverse_dynamics(q, qd, qdd)) < TOL_EXACT


@needs_cc
def test_fallback_on_compiler_error(tmp_path):
    x = casadi.SX.sym("x")
    cf = compile_function(casadi.Function("f", [x], [x]), directory=tmp_path, flags=("-fPIC", "-shared", "-Wl,--bogus"))
    assert not cf.compiled and cf.reason.startswith("compilation failed")
    assert "\n" not in cf.reason
    assert not list(tmp_path.glob("*.so"))


@needs_cc
def test_exact_flags_reproduce_the_interpreter_bit_for_bit(puma, tmp_path):
    f = puma.functions["inverse_dynamics"]
    mapped = f.map("inverse_dynamics_exact", "serial", 200, [], [])
    cf = compile_function(mapped, directory=tmp_path, flags=codegen.EXACT_FLAGS)
    assert cf.compiled, cf.reason
    q, qd, qdd = random_states(np.random.default_rng(5), 6, 200)
    args = [casadi.DM(x.T) for x in (q, qd, qdd)]
    assert np.array_equal(np.asarray(cf.function(*args)), np.asarray(mapped(*args)))


@needs_cc
def test_load_cached_never_compiles(tmp_path, monkeypatch):
    x = casadi.SX.sym("x", 2)
    f = casadi.Function("cube", [x], [x**3], ["x"], ["y"])
    assert codegen.load_cached(f, directory=tmp_path, flags=codegen.EXACT_FLAGS) is None
    assert not list(tmp_path.iterdir())  # a lookup writes nothing
    built = compile_function(f, directory=tmp_path, flags=codegen.EXACT_FLAGS)

    def no_compiler(*args, **kwargs):
        raise AssertionError("compiler called by load_cached")

    monkeypatch.setattr(subprocess, "run", no_compiler)
    loaded = codegen.load_cached(f, directory=tmp_path, flags=codegen.EXACT_FLAGS)
    assert loaded is not None and loaded.compiled and loaded.library == built.library
    assert loaded(np.array([2.0, -1.0]))["y"].ravel().tolist() == [8.0, -1.0]
    assert codegen.load_cached(f, directory=tmp_path) is None  # other flags, other library
    monkeypatch.setattr(codegen, "find_compiler", lambda: None)
    assert codegen.load_cached(f, directory=tmp_path, flags=codegen.EXACT_FLAGS) is None
