"""Figures on two cores: the same results as one core, the child's half really drawn elsewhere, and
every failure of the child made up in the parent.

Whether :func:`run_tasks` forks depends on the whole process (no other Python thread may run), and a
test worker that has run a Dask sweep keeps Dask's offload thread for its lifetime.  The tests that
need the fork therefore run in a fresh interpreter (:func:`_fresh_run`), where the precondition is
checked rather than assumed; the tests of the serial fallbacks run here.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
import threading
from pathlib import Path

import pytest

from designkit.report.parallel import available_cores, run_tasks

pytestmark = pytest.mark.skipif(not hasattr(os, "fork") or available_cores() < 2, reason="needs fork and two cores")

ROOT = Path(__file__).resolve().parents[2]

_SCRIPT = textwrap.dedent("""
    import json, os
    from designkit.processes import can_fork
    from designkit.report.figures import design_figures
    from designkit.report.parallel import run_tasks
    from tests.report.conftest import make_result

    out = {"here": os.getpid(), "fork_safe": can_fork()}
    out["pids"] = run_tasks([(lambda k=k: (k, os.getpid())) for k in range(5)], processes=2)

    def only_here(parent=os.getpid()):
        if os.getpid() != parent:
            raise RuntimeError("fails in the child")
        return "drawn here"

    out["rerun"] = run_tasks([lambda: 1, lambda: 2, only_here], processes=2)
    result = make_result()
    serial = design_figures(result)
    forked = design_figures(result, processes=2)
    out["figures"] = len(serial)
    out["same_bytes"] = forked == serial
    print(json.dumps(out))
""")


@pytest.fixture(scope="module")
def fresh() -> dict:
    """What the tasks did in a fresh interpreter with no other thread."""
    done = subprocess.run([sys.executable, "-c", _SCRIPT], cwd=ROOT, capture_output=True, text=True, timeout=300,
                          check=False)
    assert done.returncode == 0, done.stderr[-2000:]
    out = json.loads(done.stdout.strip().splitlines()[-1])
    assert out["fork_safe"], "a fresh interpreter should be able to fork"
    return out


def _pid(k: int):
    return lambda: (k, os.getpid())


def test_the_second_half_runs_in_a_child_and_the_order_is_kept(fresh):
    out = fresh["pids"]
    assert [k for k, _ in out] == list(range(5))
    here = fresh["here"]
    assert all(pid == here for _, pid in out[:3])
    children = {pid for _, pid in out[3:]}
    assert len(children) == 1 and here not in children


def test_a_task_failing_in_the_child_is_rerun_here(fresh):
    assert fresh["rerun"] == [1, 2, "drawn here"]


def test_figures_drawn_on_two_cores_are_the_same_bytes(fresh):
    assert fresh["figures"] >= 4
    assert fresh["same_bytes"]


def test_one_process_runs_everything_here():
    assert {pid for _, pid in run_tasks([_pid(k) for k in range(4)], processes=1)} == {os.getpid()}


def test_an_error_is_raised_here_as_without_the_child():
    def broken():
        raise ValueError("bad figure")

    with pytest.raises(ValueError, match="bad figure"):
        run_tasks([lambda: 1, broken], processes=2)


def test_no_fork_while_another_thread_runs():
    stop = threading.Event()
    t = threading.Thread(target=stop.wait)
    t.start()
    try:
        out = run_tasks([_pid(k) for k in range(4)], processes=2)
    finally:
        stop.set()
        t.join()
    assert {pid for _, pid in out} == {os.getpid()}
