"""One-state model calls (designkit.models.one_state, designkit.models.native): values against Pinocchio, the
same bits as the general path on every route (interpreted, compiled through the native binding, compiled
through CasADi's buffers), arguments the fast path does not take still validated and named, the compile
policy, threads, copies."""

from __future__ import annotations

import copy
import pickle
import subprocess
import threading

import casadi as ca
import numpy as np
import pytest

from designkit.errors import ModelError, NameNotFoundError
from designkit.models import codegen, native, one_state
from designkit.models.robots import robot
from tests.models.support import TOL_EXACT, ZOO, pinocchio_model, random_states, scaled_error

needs_cc = pytest.mark.skipif(codegen.find_compiler() is None, reason="no C compiler on PATH")

ROUTES = ("interpreted", "native", "buffers")


@pytest.fixture(scope="module")
def module_cache(tmp_path_factory):
    """One private code-generation cache for the module (the compiled routes compile each function once)."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("DESIGNKIT_CACHE_DIR", str(tmp_path_factory.mktemp("cache")))
        yield


@pytest.fixture
def cache(tmp_path, monkeypatch):
    """A private, empty code-generation cache for one test."""
    monkeypatch.setenv("DESIGNKIT_CACHE_DIR", str(tmp_path))
    return tmp_path / "codegen"


def on_route(route: str, monkeypatch, arm, names) -> None:
    """Put the one-state calls of ``names`` on ``route``, and check that they are on it."""
    if route == "interpreted":
        monkeypatch.setattr(codegen, "find_compiler", lambda: None)
    elif codegen.find_compiler() is None:
        pytest.skip("no C compiler on PATH")
    if route == "buffers":
        monkeypatch.setattr(native, "_state", {"module": None, "reason": "switched off in this test"})
    if route == "native" and native._module() is None:
        pytest.skip(f"no native binding: {native.unavailable_reason()}")
    for name in names:
        compiled = arm.one_state(name).compile()
        assert compiled == (route != "interpreted"), arm.one_state(name).why
        assert route.replace("buffers", "CasADi's buffers").replace("interpreted", "no C compiler") \
            in arm.one_state(name).why


# ----------------------------------------------------------------------------- against Pinocchio


@needs_cc
@pytest.mark.parametrize("name", ZOO)
def test_one_state_calls_match_pinocchio_on_the_zoo(name, module_cache):
    pin = pytest.importorskip("pinocchio")
    arm = robot(name)
    for fn in ("inverse_dynamics", "mass_matrix", "gravity_torque", "forward_dynamics"):
        assert arm.one_state(fn).compile()  # the default path once compiled: native binding where available
    model, _ = pinocchio_model(arm.description)
    data = model.createData()
    q, qd, qdd = random_states(np.random.default_rng(21), arm.n, 25)
    for k in range(25):
        tau = pin.rnea(model, data, q[k], qd[k], qdd[k])
        assert scaled_error(arm.inverse_dynamics(q[k], qd[k], qdd[k]), tau) < TOL_EXACT
        M = pin.crba(model, data, q[k])
        M = np.triu(M) + np.triu(M, 1).T  # Pinocchio may fill only the upper triangle
        assert scaled_error(arm.mass_matrix(q[k]), M) < TOL_EXACT
        assert scaled_error(arm.gravity_torque(q[k]), pin.computeGeneralizedGravity(model, data, q[k])) < TOL_EXACT
        assert scaled_error(arm.forward_dynamics(q[k], qd[k], tau), qdd[k]) < 1e-8  # through M^-1: cond(M)


# ----------------------------------------------------------------------------- against the general path

PLANAR_CALLS = {
    "fkine": lambda a, q, qd, qdd, p: a.fkine(q, p=p),
    "fkine_all": lambda a, q, qd, qdd, p: a.fkine_all(q, p=p),
    "jacobian": lambda a, q, qd, qdd, p: a.jacobian(q, p=p),
    "jacobian_dot_qd": lambda a, q, qd, qdd, p: a.jacobian_dot_qd(q, qd, p=p),
    "analytic_jacobian_rpy": lambda a, q, qd, qdd, p: a.analytic_jacobian(q, "rpy", p=p),
    "analytic_jacobian_zyz": lambda a, q, qd, qdd, p: a.analytic_jacobian(q, "zyz", p=p),
    "inverse_dynamics": lambda a, q, qd, qdd, p: a.inverse_dynamics(q, qd, qdd, p=p),
    "mass_matrix": lambda a, q, qd, qdd, p: a.mass_matrix(q, p=p),
    "christoffel": lambda a, q, qd, qdd, p: a.christoffel(q, p=p),
    "coriolis_matrix": lambda a, q, qd, qdd, p: a.coriolis_matrix(q, qd, p=p),
    "gravity_torque": lambda a, q, qd, qdd, p: a.gravity_torque(q, p=p),
    "friction_torque": lambda a, q, qd, qdd, p: a.friction_torque(qd, p=p),
    "forward_dynamics": lambda a, q, qd, qdd, p: a.forward_dynamics(q, qd, qdd, p=p),
    "regressor": lambda a, q, qd, qdd, p: a.regressor(q, qd, qdd, p=p),  # a sparse output
    "kinetic_energy": lambda a, q, qd, qdd, p: a.energy(q, qd, p=p).kinetic,
    "potential_energy": lambda a, q, qd, qdd, p: a.energy(q, qd, p=p).potential,
}


@pytest.mark.parametrize("route", ROUTES)
@pytest.mark.parametrize("symbolic", [False, True], ids=["numeric", "symbolic"])
def test_every_method_gives_the_general_paths_bits(route, symbolic, module_cache, monkeypatch):
    arm = robot("planar2r", friction=True, motor_inertia=True, symbolic=symbolic)
    on_route(route, monkeypatch, arm, PLANAR_CALLS)
    rng = np.random.default_rng(22)
    q, qd, qdd = random_states(rng, 2, 6)
    p = rng.uniform(0.5, 2.0, len(arm.symbol_names)) if symbolic else None
    for k in range(6):
        for name, call in PLANAR_CALLS.items():
            fast = call(arm, q[k], qd[k], qdd[k], p)
            # the general path: lists (converted and validated) and a batch of one row
            plain = call(arm, list(q[k]), list(qd[k]), list(qdd[k]), None if p is None else list(p))
            row = call(arm, q[k][None], qd[k][None], qdd[k][None], p)
            assert np.shape(fast) == np.shape(plain) == np.shape(row)[1:], name
            np.testing.assert_array_equal(fast, plain, err_msg=name)
            np.testing.assert_array_equal(fast, row[0], err_msg=name)
            assert isinstance(fast, float) if name.endswith("energy") else isinstance(fast, np.ndarray), name
    if route != "interpreted":
        assert arm.one_state("inverse_dynamics").library is not None


@needs_cc
def test_compiled_puma_gives_the_interpreted_bits(module_cache):
    interpreted, compiled = robot("puma560"), robot("puma560")
    names = ("inverse_dynamics", "mass_matrix", "gravity_torque", "forward_dynamics")
    for name in names:
        assert compiled.one_state(name).compile()
    q, qd, qdd = random_states(np.random.default_rng(23), 6, 40)
    for k in range(40):
        for name, args in (("inverse_dynamics", (q[k], qd[k], qdd[k])), ("mass_matrix", (q[k],)),
                           ("gravity_torque", (q[k],)), ("forward_dynamics", (q[k], qd[k], qdd[k]))):
            want = getattr(interpreted, name)(*(list(a) for a in args))  # general path, interpreted (no library)
            np.testing.assert_array_equal(getattr(compiled, name)(*args), want, err_msg=name)
    assert not interpreted.evaluator("mass_matrix").compiled


# ----------------------------------------------------------------------------- what the fast path does not take


@pytest.mark.parametrize("route", ROUTES)
def test_arguments_off_the_fast_path_are_validated_or_converted(route, module_cache, monkeypatch):
    arm = robot("puma560")
    on_route(route, monkeypatch, arm, ["inverse_dynamics"])
    q, qd, qdd = random_states(np.random.default_rng(24), 6, 1)
    q, qd, qdd = q[0], qd[0], qdd[0]
    want = arm.inverse_dynamics(q, qd, qdd)
    for bad, label in ((qd[:5], "qd"), (np.zeros(7), "qd"), (np.zeros((6, 1)), "qd"), (np.float64(1.0), "qd"),
                       (qd > 0, "qd"), (qd + 0j, "qd"), (qd.astype(str), "qd")):
        with pytest.raises(ModelError) as info:
            arm.inverse_dynamics(q, bad, qdd)
        assert info.value.field == label
    with pytest.raises(ModelError) as info:
        arm.inverse_dynamics(q, qd, qdd, p=np.ones(2))
    assert info.value.field == "p"
    # taken by the general path, same numbers
    wide = np.zeros((6, 2))
    wide[:, 0] = q
    for other in (list(q), q.astype(">f8"), wide[:, 0], pickle.loads(pickle.dumps(q))):
        np.testing.assert_array_equal(arm.inverse_dynamics(other, qd, qdd), want)
    readonly = q.copy()
    readonly.flags.writeable = False
    np.testing.assert_array_equal(arm.inverse_dynamics(readonly, qd, qdd), want)
    np.testing.assert_array_equal(arm.inverse_dynamics(np.round(q).astype(int), qd, qdd),
                                  arm.inverse_dynamics(np.round(q), qd, qdd))
    assert arm.inverse_dynamics(q[None], qd, qdd).shape == (1, 6)  # a batch of one row stays a batch
    np.testing.assert_array_equal(q, q.copy())  # the inputs are not written
    symbolic = robot("planar2r", symbolic=True)
    with pytest.raises(ModelError) as info:
        symbolic.inverse_dynamics(np.zeros(2), np.zeros(2), np.zeros(2))
    assert info.value.field == "p"


# ----------------------------------------------------------------------------- when it compiles


@needs_cc
def test_the_compile_policy(cache, monkeypatch):
    monkeypatch.setattr(one_state, "LOOKUP_CALLS", 3)
    monkeypatch.setattr(one_state, "COMPILE_CALLS", 6)
    arm = robot("planar2r")
    q = random_states(np.random.default_rng(25), 2, 1)[0][0]
    one = arm.one_state("gravity_torque")
    first = arm.gravity_torque(q)
    assert not one.compiled and "looked up at one-state call 3" in one.why and one.calls == 1
    for _ in range(2):
        np.testing.assert_array_equal(arm.gravity_torque(q), first)  # the 3rd call looks the cache up
    assert not one.compiled and "compiled at one-state call 6" in one.why and not cache.exists()
    for _ in range(2):
        arm.gravity_torque(q)
    assert not one.compiled and one.calls == 5
    np.testing.assert_array_equal(arm.gravity_torque(q), first)  # the 6th call compiles
    assert one.compiled and "built at one-state call 6" in one.why and one.library.parent == cache
    np.testing.assert_array_equal(arm.gravity_torque(q), first)

    def no_compiler(*args, **kwargs):
        raise AssertionError("the compiler ran although the library is cached")

    monkeypatch.setattr(subprocess, "run", no_compiler)
    second = robot("planar2r")  # a new robot: its 3rd one-state call loads the library
    for _ in range(3):
        np.testing.assert_array_equal(second.gravity_torque(q), first)
    assert second.one_state("gravity_torque").compiled
    assert "loaded from the cache" in second.one_state("gravity_torque").why
    assert second.one_state("gravity_torque").library == one.library


def test_without_a_compiler_one_state_calls_stay_interpreted(cache, monkeypatch):
    monkeypatch.setattr(codegen, "find_compiler", lambda: None)
    monkeypatch.setattr(one_state, "LOOKUP_CALLS", 2)
    monkeypatch.setattr(one_state, "COMPILE_CALLS", 3)
    arm = robot("planar2r")
    q, qd, qdd = random_states(np.random.default_rng(26), 2, 1)
    for _ in range(4):
        tau = arm.inverse_dynamics(q[0], qd[0], qdd[0])
    one = arm.one_state("inverse_dynamics")
    assert not one.compiled and "no C compiler" in one.why and not one.compile() and not cache.exists()
    np.testing.assert_array_equal(tau, arm.inverse_dynamics(q, qd, qdd)[0])
    with pytest.raises(NameNotFoundError):  # an unknown name, as for arm.functions
        arm.one_state("nope")


# ----------------------------------------------------------------------------- threads, copies


@needs_cc
def test_threads_calling_across_the_compilation_get_the_right_numbers(cache, monkeypatch):
    monkeypatch.setattr(one_state, "LOOKUP_CALLS", 100)
    monkeypatch.setattr(one_state, "COMPILE_CALLS", 300)
    arm = robot("puma560")
    states = random_states(np.random.default_rng(27), 6, 8)
    want = arm.inverse_dynamics(*states)  # a batch: the general path, not counted
    got: dict[int, list] = {}
    start = threading.Barrier(4)

    def work(i: int) -> None:
        start.wait()
        got[i] = [arm.inverse_dynamics(*(s[(i + k) % 8] for s in states)) for k in range(200)]

    threads = [threading.Thread(target=work, args=(i,)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert arm.one_state("inverse_dynamics").compiled  # 800 calls: compiled while the threads ran
    for i, rows in got.items():
        assert len(rows) == 200
        for k, row in enumerate(rows):
            np.testing.assert_array_equal(row, want[(i + k) % 8])


@pytest.mark.parametrize("route", ("interpreted", "native"))
def test_a_robot_after_one_state_calls_can_be_copied_and_pickled(route, module_cache, monkeypatch):
    arm = robot("planar2r")
    on_route(route, monkeypatch, arm, ["inverse_dynamics"])
    q, qd, qdd = (np.array([0.3, -0.2]), np.array([1.0, 0.5]), np.array([-0.4, 2.0]))
    tau = arm.inverse_dynamics(q, qd, qdd)
    with ca.global_pickle_context():  # CasADi's SX need its context
        data = pickle.dumps(arm)
    with ca.global_unpickle_context():
        unpickled = pickle.loads(data)
    for twin in (unpickled, copy.deepcopy(arm)):
        assert twin.one_state("inverse_dynamics") is not arm.one_state("inverse_dynamics")
        np.testing.assert_array_equal(twin.inverse_dynamics(q, qd, qdd), tau)
