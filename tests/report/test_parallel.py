"""Figures on two cores: the same results as one core, the child's half really drawn elsewhere, and
every failure of the child made up in the parent."""

from __future__ import annotations

import os
import threading

import pytest

from designkit.report.figures import design_figures
from designkit.report.parallel import available_cores, run_tasks

pytestmark = pytest.mark.skipif(not hasattr(os, "fork") or available_cores() < 2, reason="needs fork and two cores")


def _pid(k: int):
    return lambda: (k, os.getpid())


def test_the_second_half_runs_in_a_child_and_the_order_is_kept():
    out = run_tasks([_pid(k) for k in range(5)], processes=2)
    assert [k for k, _ in out] == list(range(5))
    here = os.getpid()
    assert all(pid == here for _, pid in out[:3])
    children = {pid for _, pid in out[3:]}
    assert len(children) == 1 and here not in children


def test_one_process_runs_everything_here():
    assert {pid for _, pid in run_tasks([_pid(k) for k in range(4)], processes=1)} == {os.getpid()}


def test_a_task_failing_in_the_child_is_rerun_here():
    parent = os.getpid()

    def only_here():
        if os.getpid() != parent:
            raise RuntimeError("fails in the child")
        return "drawn here"

    assert run_tasks([lambda: 1, lambda: 2, only_here], processes=2) == [1, 2, "drawn here"]


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


def test_figures_drawn_on_two_cores_are_the_same_bytes(servo_result):
    serial = design_figures(servo_result)
    forked = design_figures(servo_result, processes=2)
    assert len(serial) >= 4
    assert forked == serial
