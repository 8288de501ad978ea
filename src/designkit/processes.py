"""What the machine offers for a second process, and independent tasks shared with a forked child.

:func:`available_cores` and :func:`can_fork` cost no import; :func:`run_tasks` runs independent tasks on two cores
(the report's figures, :mod:`designkit.report.parallel`): the child
inherits the finished run (nothing is pickled on the way in), runs the second half of the tasks and sends their
results back through a pipe, while the parent runs the first half.

Safety rules, each a reason to run every task in this process instead:

- ``os.fork`` is missing (not POSIX) or fewer than two cores are available;
- this process runs other Python threads (a thread holding a lock at the fork would leave the
  child deadlocked), e.g. inside a Jupyter kernel -- so the command line asks for two processes,
  the Python API's default is one.  Native thread pools are not seen: tasks that solve with Clarabel
  (whose pool a child inherits locked) must not be run here;
- the child fails in any way (it dies, sends nothing, or a task raises there): the parent then
  runs the tasks it did not get, so an exception is raised here exactly as without the child.

The child leaves with :func:`os._exit` right after sending: no ``atexit`` handler, no flush of
buffers it inherited.  The results are those of a serial run, in the tasks' order.
"""

from __future__ import annotations

import os
import pickle
import threading
from collections.abc import Callable, Sequence
from typing import Any, TypeVar

__all__ = ["available_cores", "can_fork", "run_tasks"]

T = TypeVar("T")


def available_cores() -> int:
    """Cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def can_fork() -> bool:
    """``os.fork`` exists and this process runs no other Python thread (a thread holding a lock at the
    fork would leave the child deadlocked, e.g. inside a Jupyter kernel)."""
    return hasattr(os, "fork") and threading.active_count() == 1


def _can_fork() -> bool:
    return can_fork() and available_cores() >= 2


def _delivered(data: bytes) -> dict[int, Any]:
    """The results the child sent (task index -> result); none when its message is empty or broken."""
    try:
        sent = pickle.loads(data)  # noqa: S301 - our own forked child, a private pipe
    except (pickle.UnpicklingError, EOFError, ValueError, TypeError):
        return {}
    return {k: value for k, ok, value in sent if ok}


def run_tasks(tasks: Sequence[Callable[[], T]], *, processes: int = 1) -> list[T]:
    """``[task() for task in tasks]``, with the second half of the tasks run in a forked child when
    ``processes >= 2`` and forking is safe (module docstring).

    Parameters
    ----------
    tasks : sequence of callables
        Independent, side-effect-free tasks whose results can be pickled.
    processes : int
        1 runs everything here; 2 or more shares the tasks with one forked child.

    Returns
    -------
    list
        The tasks' results, in order.
    """
    tasks = list(tasks)
    if processes < 2 or len(tasks) < 2 or not _can_fork():
        return [task() for task in tasks]
    split = (len(tasks) + 1) // 2
    read_fd, write_fd = os.pipe()
    try:
        pid = os.fork()
    except OSError:
        os.close(read_fd)
        os.close(write_fd)
        return [task() for task in tasks]
    if pid == 0:  # the child: run its half, send it, leave at once
        status = 1
        try:
            os.close(read_fd)
            out: list[tuple[int, bool, Any]] = []
            for k in range(split, len(tasks)):
                try:
                    out.append((k, True, tasks[k]()))
                except BaseException:  # noqa: BLE001 - the parent reruns it and raises it there
                    out.append((k, False, None))
            data = pickle.dumps(out, protocol=pickle.HIGHEST_PROTOCOL)
            with os.fdopen(write_fd, "wb") as pipe:
                pipe.write(data)
            status = 0
        finally:
            os._exit(status)
    os.close(write_fd)
    try:
        results: dict[int, Any] = {k: tasks[k]() for k in range(split)}
    except BaseException:
        os.close(read_fd)
        os.waitpid(pid, 0)
        raise
    with os.fdopen(read_fd, "rb") as pipe:
        data = pipe.read()
    os.waitpid(pid, 0)
    results.update(_delivered(data))
    for k in range(split, len(tasks)):  # whatever the child did not deliver
        if k not in results:
            results[k] = tasks[k]()
    return [results[k] for k in range(len(tasks))]
