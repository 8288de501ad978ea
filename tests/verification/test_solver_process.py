"""The solver process: same answers as in-process solves, the parent never imports cvxpy, any failure
falls back to solving in-process."""

from __future__ import annotations

import io
import json
import os
import signal
import subprocess
import sys

import numpy as np
import pytest

from designkit.verification import lmi, lp, solver_process
from designkit.verification.solver_process import SolverProcess, _receive, _send, serve
from tests.problems import POSSPEED_YAML

A_STABLE = [np.array([[0.0, 1.0], [-2.0, -3.0]]), np.array([[0.0, 1.0], [-3.0, -2.5]])]


@pytest.fixture(params=["spawned", "forked"])
def child(monkeypatch, request):
    proc = SolverProcess(fork=request.param == "forked")
    monkeypatch.setattr(solver_process, "_active", proc)
    yield proc
    monkeypatch.setattr(solver_process, "_active", None)
    proc.close()


def _in_process(monkeypatch, func, *args, **kwargs):
    with monkeypatch.context() as m:
        m.setattr(solver_process, "_active", None)
        return func(*args, **kwargs)


def _fresh_interpreter(script: str) -> dict:
    """The JSON object the last line of ``script``'s output holds, run in a new Python."""
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True, timeout=300)
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_lmi_answers_equal_the_in_process_solve(child, monkeypatch):
    coords = lmi.coordinates(A_STABLE)
    remote = lmi.solve_margin_lmi(coords.Ah)
    assert child.alive  # it answered; nothing failed over
    local = _in_process(monkeypatch, lmi.solve_margin_lmi, coords.Ah)
    assert remote.status == local.status == "optimal"
    np.testing.assert_allclose(remote.Pb, local.Pb, rtol=1e-12, atol=1e-14)
    assert remote.t == pytest.approx(local.t, rel=1e-12)
    assert lmi.lyapunov_recheck(A_STABLE, coords.from_balanced(remote.Pb)).ok  # the parent's NumPy re-check decides


def test_lp_answers_equal_the_in_process_solve(child, monkeypatch):
    c, G, h = np.array([1.0, 2.0]), np.array([[-1.0, 0.0], [0.0, -1.0], [1.0, 1.0]]), np.array([0.0, 0.0, 4.0])
    remote = lp.solve_lp(c, G, h)
    local = _in_process(monkeypatch, lp.solve_lp, c, G, h)
    assert child.alive
    assert remote.status == local.status == "optimal"
    np.testing.assert_allclose(remote.x, local.x, atol=1e-9)
    np.testing.assert_allclose(remote.dual, local.dual, atol=1e-9)


def test_a_dead_child_falls_back_to_the_in_process_solve(child, monkeypatch):
    if child._proc is not None:
        child._proc.kill()
        child._proc.wait()
    else:
        os.kill(child._pid, signal.SIGKILL)
        os.waitpid(child._pid, 0)
    coords = lmi.coordinates(A_STABLE)
    sol = lmi.solve_margin_lmi(coords.Ah)  # the channel fails: solved here instead
    assert sol.status == "optimal" and sol.t > 0
    assert solver_process.active() is None


def test_an_error_in_the_child_is_raised_in_process(child):
    done, value = child.call("margin_lmi", "not matrices")
    assert (done, value) == (False, None)
    assert child.alive  # an error in a solve does not retire the child
    with pytest.raises(Exception):  # noqa: B017 - whatever the solve raises here, it raises in-process too
        lmi.solve_margin_lmi("not matrices")


class _ExitedError(Exception):
    pass


def test_serve_answers_only_the_listed_solvers(monkeypatch):
    requests = io.BytesIO()
    _send(requests, ("lp", (np.array([1.0]), np.array([[-1.0]]), np.array([0.0])), {}))
    _send(requests, ("os.system", ("true",), {}))
    requests.seek(0)
    answers = io.BytesIO()

    def exit_(code: int) -> None:  # serve() ends the child with os._exit at the end of its input
        raise _ExitedError(code)

    monkeypatch.setattr(solver_process.os, "_exit", exit_)
    with pytest.raises(_ExitedError):
        serve(requests, answers)
    answers.seek(0)
    status, value = _receive(answers)
    assert status == "ok" and value.status == "optimal"
    status, value = _receive(answers)
    assert status == "error" and "KeyError" in value


def test_start_is_off_on_one_core_and_when_cvxpy_is_loaded(monkeypatch):
    monkeypatch.setattr(solver_process, "_active", None)
    monkeypatch.setattr(solver_process, "_cores", lambda: 1)
    assert solver_process.start() is None
    monkeypatch.setattr(solver_process, "_cores", lambda: 2)
    monkeypatch.setitem(sys.modules, "cvxpy", sys.modules.get("cvxpy", object()))
    assert solver_process.start() is None  # nothing to gain: this process has cvxpy already


def test_a_synth_run_with_the_solver_process_never_imports_cvxpy_in_the_parent(tmp_path):
    """What the command line does: start the process, run a spec whose Lyapunov check solves an LMI."""
    spec = tmp_path / "posspeed.yaml"
    spec.write_text(POSSPEED_YAML)
    script = (
        "import json, sys\n"
        "from designkit.verification import solver_process\n"
        "import numpy, scipy.linalg\n"
        "proc = solver_process.start(fork=True)\n"
        "from designkit.pipeline import run\n"
        "from designkit.schema.loader import load_spec\n"
        f"r = run(load_spec({str(spec)!r}))\n"
        "lyap = [c for c in r.checks if c.name == 'lyapunov'][0]\n"
        "print(json.dumps({'started': proc is not None, 'alive': solver_process.active() is not None,\n"
        "                  'cvxpy': 'cvxpy' in sys.modules, 'lyapunov': lyap.passed,\n"
        "                  'margin': lyap.margin, 'verified': r.verified}))\n"
    )
    got = _fresh_interpreter(script)
    if not got["started"]:
        pytest.skip("one core: no solver process is started")
    assert got == {**got, "alive": True, "cvxpy": False, "lyapunov": True, "verified": True}
    assert got["margin"] > 0


def test_import_cvxpy_defers_scipy_stats_and_leaves_the_real_module_importable():
    """Run in a fresh interpreter: the stand-in must not outlive the import, and the deferred
    function must give scipy's answer when called."""
    script = (
        "import sys, json\n"
        "from designkit.verification.solver_process import import_cvxpy\n"
        "import_cvxpy()\n"
        "loaded_during = 'scipy.stats' in sys.modules\n"
        "from cvxpy.atoms.quantum_rel_entr import entropy\n"
        "value = entropy([0.25, 0.75])\n"
        "import scipy.stats\n"
        "print(json.dumps({'during': loaded_during, 'value': float(value),\n"
        "                  'real': scipy.stats.entropy([0.25, 0.75]), 'is_module': hasattr(scipy.stats, 'norm')}))\n"
    )
    got = _fresh_interpreter(script)
    assert got["during"] is False  # deferred: not imported by `import cvxpy`
    assert got["is_module"] is True  # the real scipy.stats afterwards
    expected = -(0.25 * np.log(0.25) + 0.75 * np.log(0.75))  # nats, computed here
    assert got["value"] == pytest.approx(expected, rel=1e-15) and got["real"] == pytest.approx(expected, rel=1e-15)


def test_an_in_process_solve_imports_cvxpy_without_scipy_stats(tmp_path):
    """No solver process (the Python API, ``--jobs 1``): the Lyapunov LMI is solved here, cvxpy imported with
    ``scipy.stats`` deferred, and the certificate is the one the check passes on."""
    spec = tmp_path / "posspeed.yaml"
    spec.write_text(POSSPEED_YAML)
    script = (
        "import json, sys\n"
        "from designkit.pipeline import run\n"
        "from designkit.schema.loader import load_spec\n"
        f"r = run(load_spec({str(spec)!r}))\n"
        "lyap = [c for c in r.checks if c.name == 'lyapunov'][0]\n"
        "print(json.dumps({'cvxpy': 'cvxpy' in sys.modules, 'stats': 'scipy.stats' in sys.modules,\n"
        "                  'lyapunov': lyap.passed, 'margin': lyap.margin}))\n"
    )
    got = _fresh_interpreter(script)
    assert got == {**got, "cvxpy": True, "stats": False, "lyapunov": True}
    assert got["margin"] > 0
