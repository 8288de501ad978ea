"""Constants lifted out of a loop's compiled code: one library per structure, the numbers of each loop's own."""

from __future__ import annotations

import functools

import casadi as ca
import numpy as np
import pytest

from designkit.models.codegen import find_compiler
from designkit.simulation import run as sim_run
from designkit.simulation.dopri5 import build_dopri5
from designkit.simulation.lifted import lift_constants
from designkit.simulation.run import build
from tests.simulation.helpers import design_of, make_spec

needs_cc = pytest.mark.skipif(find_compiler() is None, reason="the Dormand-Prince pair runs compiled only")


def test_a_lifted_function_reads_its_constants_from_the_added_input():
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p")
    f = ca.Function("f", [x, p], [ca.cse(ca.vertcat(3.5 * x[0] * x[1] + ca.sin(2.25 * x[0]) - p,
                                                      ca.fmax(x[1], 0.7) ** 2, ca.if_else(x[0] > 1.5, 4.0, x[1]),
                                                      x[0] ** 3.3))], ["x", "p"], ["y"])
    h = ca.Function("h", [x], [7.0 * x])
    (fl, hl), constants = lift_constants((f, h))
    assert sorted(constants.tolist()) == [0.7, 1.5, 2.25, 3.5, 4.0, 7.0]  # the exponent 3.3 stays written in
    assert fl.name_in() == ["x", "p", "G"] and fl.name_out() == ["y"] and hl.n_in() == 2
    rng = np.random.default_rng(3)
    for _ in range(20):
        xv, pv = rng.uniform(0.1, 3, 2), rng.uniform(-1, 1)  # x[0] > 0: x[0] ** 3.3 is real
        assert np.array_equal(np.array(fl(xv, pv, constants)), np.array(f(xv, pv)))
        assert np.array_equal(np.array(hl(xv, constants)), np.array(h(xv)))
    other = constants.copy()
    other[constants.tolist().index(7.0)] = 2.0  # another value of a constant: another function of one structure
    assert np.array_equal(np.array(hl([1.0, 3.0], other)), [[2.0], [6.0]])


def test_a_function_that_is_not_sx_is_refused():
    x = ca.MX.sym("x")
    with pytest.raises(ValueError, match="not an SX function"):
        lift_constants((ca.Function("m", [x], [2 * x]),))


@needs_cc
def test_variants_of_a_law_share_one_library_and_run_as_their_own_library_does(tmp_path, monkeypatch):
    """Two PID servos of other gains (a gain study's variants): one compiled library serves both, and the second
    runs as a library compiled for it alone, its constants written in, to 1e-12."""
    monkeypatch.setenv("DESIGNKIT_CACHE_DIR", str(tmp_path))
    specs = [make_spec({"kind": "pid_servo", "poles": poles, "zero": -3}, duration=3.0)
             for poles in ([-4, -5, -20], [-6, -7, -25])]
    first, second = (build(spec, design_of(spec)) for spec in specs)
    assert first.dopri5.library is not None and first.dopri5.library == second.dopri5.library
    assert first.dopri5.compiled_now and not second.dopri5.compiled_now
    assert first.dopri5.constants.size == second.dopri5.constants.size > 0
    assert not np.array_equal(first.dopri5.constants, second.dopri5.constants)
    monkeypatch.setattr(sim_run, "build_dopri5", functools.partial(build_dopri5, lift=False))
    own = build(specs[1], design_of(specs[1]))
    assert own.dopri5.library not in (None, second.dopri5.library) and own.dopri5.constants.size == 0
    shared_run, own_run = second.run(), own.run()
    scale = 1.0 + np.abs(own_run.state)
    assert np.max(np.abs(shared_run.state - own_run.state) / scale) <= 1e-12
    assert np.max(np.abs(shared_run.u_command - own_run.u_command) / (1.0 + np.abs(own_run.u_command))) <= 1e-12
