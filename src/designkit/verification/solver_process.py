"""Conic solves (cvxpy + Clarabel) in a warm child process, started before the parent needs them.

Why.  Importing cvxpy costs more than every solve of a ``designkit synth`` run together: about
1-2 s on a 2-core machine, because it imports ``scipy.stats`` and ``scipy.optimize`` with it;
the solves themselves take milliseconds.  The command line therefore starts this process first
thing (:func:`start`): the child imports cvxpy on the second core while the parent imports the
rest of the stack, designs and simulates.  The child defers the ``scipy.stats`` that cvxpy
imports without needing it for our problems (:func:`import_cvxpy`), which halves that import.
When a check reaches a solve, the parent sends the problem's NumPy data through a pipe and gets
the solver's answer back.

What it changes.  Nothing in the results: the child runs the same functions
(:func:`designkit.verification.lmi.solve_margin_lmi`, :func:`designkit.verification.lp.solve_lp`)
with the same cvxpy and Clarabel, and what it returns is only a candidate -- every certificate
is re-checked with NumPy in the parent (:mod:`designkit.verification.certificate`), which alone
decides.  Any failure of the channel (the child could not start, died, or answered with an
error) makes the parent solve in-process, as it does when no child runs (the Python API, a
one-core machine, or ``designkit synth --jobs 1``), so an error a solve raises is raised in the
parent exactly as without the child.  A solve in-process imports cvxpy the same way (:func:`cvxpy`).

Waiting.  When a solve is requested before the child has finished importing cvxpy, the parent
would sit idle; work registered with :func:`while_waiting` (the command line registers the imports
of the report's stack) runs then instead, once, before the parent blocks on the answer.

Protocol: length-prefixed pickles over two pipes (private to two processes of the same program);
requests name a function of :data:`SOLVERS`, nothing else.
"""

from __future__ import annotations

import atexit
import contextlib
import os
import pickle
import select
import signal
import struct
import subprocess
import sys
import types
from collections.abc import Callable
from typing import Any, BinaryIO

from designkit.processes import can_fork

__all__ = ["SOLVERS", "SolverProcess", "active", "call", "cvxpy", "serve", "start", "stop", "while_waiting"]

SOLVERS: dict[str, tuple[str, str]] = {
    "margin_lmi": ("designkit.verification.lmi", "solve_margin_lmi"),
    "lp": ("designkit.verification.lp", "solve_lp"),
}
"""Request name -> (module, function) the child may run."""

_HEADER = struct.Struct("<Q")


def _send(stream: BinaryIO, obj: Any) -> None:
    data = pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL)
    stream.write(_HEADER.pack(len(data)) + data)
    stream.flush()


def _receive(stream: BinaryIO) -> Any:
    head = stream.read(_HEADER.size)
    if len(head) < _HEADER.size:
        raise EOFError("solver process closed the pipe")
    (size,) = _HEADER.unpack(head)
    data = stream.read(size)
    if len(data) < size:
        raise EOFError("solver process closed the pipe")
    return pickle.loads(data)  # noqa: S301 - our own child's answer on a private pipe


class SolverProcess:
    """A child process that imports cvxpy at once, then runs the :data:`SOLVERS` it is sent.

    Parameters
    ----------
    fork : bool
        Fork this process (the child keeps what is already imported, e.g. NumPy and SciPy's linear
        algebra, and only imports cvxpy on top) instead of starting a new interpreter.  Only done
        where ``os.fork`` exists and this process runs no other Python thread; otherwise a new
        interpreter is started.
    """

    def __init__(self, *, fork: bool = False) -> None:
        self.failed = False
        self._pid: int | None = None
        self._proc: subprocess.Popen | None = None
        if fork and can_fork():
            self._fork()
        else:
            self._proc = subprocess.Popen(  # noqa: S603 - this interpreter, a fixed module
                [sys.executable, "-c", "from designkit.verification.solver_process import serve; serve()"],
                stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
            )
            self._requests, self._answers = self._proc.stdin, self._proc.stdout

    def _fork(self) -> None:
        req_r, req_w = os.pipe()
        ans_r, ans_w = os.pipe()
        sys.stdout.flush()
        sys.stderr.flush()
        pid = os.fork()
        if pid == 0:  # the child: quiet (no output, no Ctrl-C traceback), serve, leave without teardown
            try:
                os.close(req_w)
                os.close(ans_r)
                signal.signal(signal.SIGINT, signal.SIG_IGN)
                devnull = os.open(os.devnull, os.O_RDWR)
                for fd in (0, 1, 2):
                    os.dup2(devnull, fd)
                serve(os.fdopen(req_r, "rb"), os.fdopen(ans_w, "wb"))
            finally:
                os._exit(0)
        os.close(req_r)
        os.close(ans_w)
        self._pid = pid
        self._requests, self._answers = os.fdopen(req_w, "wb"), os.fdopen(ans_r, "rb")

    def _running(self) -> bool:
        if self._proc is not None:
            return self._proc.poll() is None
        if self._pid is None:
            return False
        try:
            done, _ = os.waitpid(self._pid, os.WNOHANG)
        except ChildProcessError:
            done = self._pid
        if done:
            self._pid = None
        return not done

    @property
    def alive(self) -> bool:
        """Started, not yet failed, and still running."""
        return not self.failed and self._running()

    def call(self, name: str, *args: Any, **kwargs: Any) -> tuple[bool, Any]:
        """Run solver ``name`` in the child: ``(True, result)``, or ``(False, None)`` when the channel
        failed or the child raised (the caller then solves in-process); a failure retires the child."""
        if not self.alive:
            return False, None
        try:
            _send(self._requests, (name, args, kwargs))
            if _idle_work and not select.select([self._answers], [], [], 0.0)[0]:
                _run_idle_work()  # the answer is not there yet: do something useful meanwhile
            status, value = _receive(self._answers)
        except (OSError, EOFError, pickle.PickleError, ValueError):
            self.failed = True
            return False, None
        if status != "ok":
            return False, None
        return True, value

    def close(self) -> None:
        """End the child now: its pipes are closed and it is killed (it holds nothing to save)."""
        for stream in (self._requests, self._answers):
            with contextlib.suppress(OSError):
                stream.close()
        if self._proc is not None:
            with contextlib.suppress(OSError):
                self._proc.kill()
            self._proc.wait()
        elif self._pid is not None:
            with contextlib.suppress(OSError):
                os.kill(self._pid, signal.SIGKILL)
            with contextlib.suppress(ChildProcessError):
                os.waitpid(self._pid, 0)
            self._pid = None


_active: SolverProcess | None = None
_idle_work: list[Callable[[], Any]] = []


def while_waiting(work: Callable[[], Any]) -> None:
    """Run ``work()`` (once) the first time this process would wait for the solver process's answer.

    Meant for work the program needs later anyway (imports): if no wait happens, it is simply done
    when it is needed.
    """
    _idle_work.append(work)


def _run_idle_work() -> None:
    while _idle_work:
        _idle_work.pop(0)()


def _cores() -> int:
    from designkit.processes import available_cores

    return available_cores()


def start(*, fork: bool = False) -> SolverProcess | None:
    """Start the solver process for this program (once); None when it would not help.

    It helps when a second core can import cvxpy while this process works: on one core it would
    only compete, so none is started; nor when this process has imported cvxpy already.  ``fork``:
    see :class:`SolverProcess`.
    """
    global _active
    if _active is not None:
        return _active
    if _cores() < 2 or "cvxpy" in sys.modules:
        return None
    try:
        _active = SolverProcess(fork=fork)
    except OSError:
        return None
    atexit.register(stop)
    return _active


def stop() -> None:
    """End the solver process, if any."""
    global _active
    if _active is not None:
        _active.close()
        _active = None


def active() -> SolverProcess | None:
    """The running solver process, or None."""
    return _active if _active is not None and _active.alive else None


def call(name: str, *args: Any, **kwargs: Any) -> tuple[bool, Any]:
    """``(True, result)`` of solver ``name`` run in the solver process, or ``(False, None)`` when none
    runs or it failed (then solve in-process)."""
    proc = active()
    if proc is None:
        return False, None
    return proc.call(name, *args, **kwargs)


class _DeferredAttribute:
    """A function of a module not yet imported: the module is imported at the first call."""

    def __init__(self, module: str, name: str) -> None:
        self._module, self._name = module, name

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        import importlib

        return getattr(importlib.import_module(self._module), self._name)(*args, **kwargs)


class _DeferredModule(types.ModuleType):
    """Stands in for a module while another one is imported: ``from <module> import f`` gets a
    :class:`_DeferredAttribute` of ``f``; dunder lookups (the import system's) are refused."""

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__"):
            raise AttributeError(name)
        return _DeferredAttribute(self.__name__, name)


DEFERRED_AT_CVXPY_IMPORT = ("scipy.stats",)
"""Modules cvxpy imports at load time but a designkit solve never calls into (cvxpy 1.9 takes
``scipy.stats.entropy`` for its quantum relative-entropy atom): importing ``scipy.stats`` is about
0.7 s, more than half of ``import cvxpy``."""


def import_cvxpy() -> Any:
    """``import cvxpy`` with the modules of :data:`DEFERRED_AT_CVXPY_IMPORT` deferred.

    While cvxpy is imported, each such module is a stand-in (:class:`_DeferredModule`) whose
    functions import the real module when first called; the stand-in is removed from
    ``sys.modules`` afterwards, so any later import gets the real module.  Should a cvxpy release
    need more of such a module at import time, its import fails here and the parent solves
    in-process (module docstring): slower, never different.
    """
    standins = {name: _DeferredModule(name) for name in DEFERRED_AT_CVXPY_IMPORT if name not in sys.modules}
    sys.modules.update(standins)
    try:
        import cvxpy
    finally:
        for name, standin in standins.items():
            if sys.modules.get(name) is standin:
                del sys.modules[name]
    return cvxpy


def cvxpy() -> Any:
    """The cvxpy module for a solve in this process: imported by :func:`import_cvxpy` (its deferred modules left
    unimported) the first time, by a plain import should that fail."""
    module = sys.modules.get("cvxpy")
    if module is not None:
        return module
    try:
        return import_cvxpy()
    except Exception:  # noqa: BLE001 - a cvxpy release that needs a deferred module at import: import it whole
        for name in [m for m in sys.modules if m == "cvxpy" or m.startswith("cvxpy.")]:
            del sys.modules[name]
        import cvxpy as module

        return module


def serve(stdin: BinaryIO | None = None, stdout: BinaryIO | None = None) -> None:
    """The child's loop: import cvxpy (:func:`import_cvxpy`), then answer requests until stdin closes."""
    import importlib

    import_cvxpy()  # the point of this process: import it while the parent works

    stdin = stdin if stdin is not None else sys.stdin.buffer
    stdout = stdout if stdout is not None else sys.stdout.buffer
    while True:
        try:
            name, args, kwargs = _receive(stdin)
        except EOFError:  # the parent is done: exit without the interpreter's slow teardown of cvxpy and SciPy
            stdout.flush()
            os._exit(0)
        try:
            module, func = SOLVERS[name]
            value = getattr(importlib.import_module(module), func)(*args, **kwargs)
            answer: tuple[str, Any] = ("ok", value)
        except Exception as exc:  # noqa: BLE001 - reported; the parent then solves in-process
            answer = ("error", f"{type(exc).__name__}: {exc}")
        _send(stdout, answer)
