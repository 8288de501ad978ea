"""What the machine offers for a second process: available cores and whether forking is safe.

Kept apart from the modules that use it (:mod:`designkit.verification.solver_process`,
:mod:`designkit.report.parallel`) so that asking costs no import.
"""

from __future__ import annotations

import os
import threading

__all__ = ["available_cores", "can_fork"]


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
