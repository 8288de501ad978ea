"""One-state evaluation of a model function from Python at close to the cost of the call itself.

A :class:`Robot <designkit.models.robot.Robot>` method called on ONE state given as float64 NumPy
arrays of shape ``(size,)`` (and, for a symbolic robot, ``p`` as a float64 array) runs through the
function's :class:`OneState`, by one of three routes with the same results:

* **native binding** (the default once the function is compiled, where this interpreter's headers and a
  C compiler are present): the robot's method calls a :mod:`designkit.models.native` ``Caller``, which
  checks the arrays (exact ``ndarray``, float64, native order, aligned, C-contiguous, shape), points the
  compiled function's argument array at their data (no copy), allocates the output and calls the C, in one
  C call; about 1 us for the PUMA 560's inverse dynamics, below ``pinocchio.rnea`` called from Python;
* **CasADi's buffers** on the compiled function, when the binding cannot be built: the arguments are
  copied into arrays bound once per thread to the function's ``buffer()`` (the copy through a
  ``memoryview`` is also the check: it takes only a float64 buffer of the input's shape), the output
  copied out;
* the same buffers on the **interpreted** function, before it is compiled or without a compiler.

Any other argument (a list, an int array, a batch, a wrong shape, a non-contiguous array on the native
route) makes the call return ``None``, and the method takes the general path of
:mod:`designkit.models.batch`, which converts, validates and names the argument in its errors.

Why compiled, and why one C call (PUMA inverse dynamics, one state, the loaded development machine): CasADi's
interpreted virtual machine costs 5-7 us a call where the compiled function through the same buffer costs
0.35 us, and the Python around a call adds its own: three ``isinstance``/dtype/shape checks 1.7 us, a NumPy
slice assignment 0.5-0.9 us per argument, the output copy 0.4 us; the native binding does the checks, the
argument pointers and the output in one C call.  ``buffer.ret()`` is not read on the buffer routes:
it costs more than the compiled call, and the model functions are ``SX`` functions, whose evaluation
has no failure to report (it is read for any other kind of function; the native binding reads the
return code at no cost).

When is the C compiled?  Deterministic, never in the background, once per machine:

1. The first :data:`LOOKUP_CALLS` - 1 one-state calls of a function run interpreted; the
   :data:`LOOKUP_CALLS`-th looks its library up in the on-disk cache
   (:func:`~designkit.models.codegen.load_cached`, which generates the C to hash it: 1-90 ms for
   the PUMA 560's functions, once per robot and function) and uses it from then on.
2. Otherwise calls stay interpreted, and the :data:`COMPILE_CALLS`-th one-state call compiles the
   function (0.2-4 s for the PUMA 560's functions at ``-O1``, cached under the content hash of
   its C source; the library is separate from the batched block of :mod:`designkit.models.batch`).
3. Without a C compiler, when compiling fails or the cache is not writable, calls stay
   interpreted (the failure is remembered, not retried); functions without per-state inputs
   (``parameters``) never compile.  :meth:`OneState.compile` compiles ahead of time;
   :attr:`OneState.why` says which path runs and why.

The compiled code is built with :data:`~designkit.models.codegen.EXACT_FLAGS` (no reassociation,
no fused multiply-add), so the results are bit-identical to the interpreter's and to the batched
path's (``tests/models/test_one_state.py`` checks every method on every route).

Thread safety: the bound arrays of the buffer routes are per thread (``threading.local``); the native
binding holds the GIL from the argument pointers to its return, so its preallocated pointer arrays are
used by one call at a time.  Compiling swaps the function for all threads under a lock; a call already
running in another thread finishes on what it started with.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Mapping
from typing import Any

import casadi as ca
import numpy as np

from designkit.errors import ModelError
from designkit.models import codegen, native

__all__ = ["COMPILE_CALLS", "LOOKUP_CALLS", "OneState", "OneStateTable"]

LOOKUP_CALLS = 100
"""One-state calls of a function (per robot) after which its compiled library is looked up in the cache.
The lookup generates the C source to hash it (1-90 ms for the PUMA 560's functions), as much as 10^2-10^4
interpreted calls: a robot called a few times (a test, a check at a handful of points) never pays it, a
loop pays it once, in its first hundred calls."""

COMPILE_CALLS = 1000
"""One-state calls of a function (per robot) after which it is compiled when not cached.  The
interpreter spends 1-60 us per call on the PUMA 560's functions, so 1000 calls cost 1-60 ms before
a compilation of 0.2-4 s that happens once per machine: a program that makes a thousand calls of
one function is expected to make many more, and later runs load the library from the cache."""


class OneState:
    """Evaluate one ``casadi.Function`` at one state, through compiled C when possible.

    Parameters
    ----------
    function : casadi.Function
        Dense column-vector inputs: the per-state inputs, then ``shared`` inputs (the symbol
        values ``p`` of a symbolic robot).  Only output 0 is computed.
    shared : int
        Number of trailing shared inputs (0 or 1).
    kind : {"vector", "matrix", "scalar"}
        How output 0 is returned: shape ``(rows,)``, ``(rows, cols)`` or a float.

    Attributes
    ----------
    compiled : bool
        True when calls run compiled C.
    why : str
        Which path runs and why (the policy of the module docstring).
    library : pathlib.Path or None
        The shared library, when ``compiled``.
    calls : int
        One-state calls counted by the policy (:data:`LOOKUP_CALLS`, :data:`COMPILE_CALLS`); counting stops
        once the route is settled.
    """

    def __init__(self, function: ca.Function, shared: int, kind: str,
                 route: Callable[[Callable[..., Any]], None] | None = None) -> None:
        self.function = function
        self.shared = shared
        self.kind = kind
        self.compiled = False
        self.library = None
        self.calls = 0
        self.why = f"interpreted: the on-disk cache is looked up at one-state call {LOOKUP_CALLS}"
        self._shapes = tuple((function.size1_in(k),) for k in range(function.n_in()))
        self._per_state = function.n_in() - shared
        pattern = function.sparsity_out(0)
        self._rows, self._cols, self._nnz = pattern.size1(), pattern.size2(), pattern.nnz()
        self._flat = None if pattern.is_dense() else (  # column-major index of each nonzero
            np.array(pattern.row(), dtype=np.intp) + pattern.size1() * np.array(pattern.get_col(), dtype=np.intp))
        self._vector = kind == "vector" and self._flat is None
        self._check_return = not function.is_a("SXFunction")
        self._target = function
        self._native: Callable[..., Any] | None = None
        self._route = route
        self._looked_up = False
        self._counting = True  # until the path is settled (compiled, or compiling ruled out)
        self._lock = threading.Lock()
        self._local = threading.local()

    def __reduce__(self) -> tuple[Any, ...]:
        """Copies start afresh: bound arrays, lock and library are per evaluator (the cache is looked up again)."""
        return (OneState, (self.function, self.shared, self.kind))

    def __call__(self, *args: Any) -> Any:
        """Output 0 at one state, or None when the arguments do not fit the fast path.

        Parameters
        ----------
        *args
            The per-state inputs, then ``p`` (``None`` for a function without shared inputs).
            Each must be a float64 array (a buffer of format ``"d"``) of its input's shape ``(size,)``.

        Returns
        -------
        numpy.ndarray, float or None
            A new array (or a float for ``kind="scalar"``); None when an argument is of another type,
            dtype or shape, or ``p`` is given to a function without shared inputs or missing
            (the caller's general path then validates and names the argument).
        """
        if self._native is not None:
            return self._native(*args)
        if args[-1] is None:
            if self.shared:
                return None
            args = args[:-1]
        elif not self.shared:
            return None
        try:
            buffer, run, views, out = self._local.bound
        except AttributeError:
            buffer, run, views, out = self._bind()
        try:  # the check: a memoryview takes only a buffer of format "d" (float64, native order) and shape (size,)
            for view, a in zip(views, args, strict=True):
                view[:] = a
        except (TypeError, ValueError, NotImplementedError, BufferError):
            return None
        run()
        if self._counting:
            self._count()
        if self._check_return and buffer.ret() != 0:
            raise ModelError(f"evaluation of {self.function.name()!r} failed (return code {buffer.ret()})")
        if self._vector:
            return out.copy()
        return self._shape(out)

    def _shape(self, out: np.ndarray) -> Any:
        """A matrix ``(rows, cols)`` or a float from the column-major nonzeros in ``out``."""
        if self._flat is not None:
            dense = np.zeros(self._rows * self._cols)
            dense[self._flat] = out
            out = dense
        if self.kind == "scalar":
            return float(out[0])
        if self.kind == "vector":
            return out.copy()
        return out.reshape(self._cols, self._rows).copy().T  # Fortran order, as CasADi writes it

    def _bind(self) -> tuple[Any, Any, list[np.ndarray], np.ndarray]:
        """This thread's arrays, bound to the current function's buffer."""
        with self._lock:
            target, local = self._target, self._local
        views = [memoryview(np.zeros(shape)) for shape in self._shapes]
        out = np.zeros(self._nnz)
        buffer, run = target.buffer()
        for k, view in enumerate(views):
            buffer.set_arg(k, view)
        buffer.set_res(0, memoryview(out))
        local.bound = (buffer, run, views, out)
        return local.bound

    def _look_up(self) -> None:
        """Step 1 of the policy (under the lock): a cached library, else say what happens next."""
        self._looked_up = True
        if self._per_state == 0:
            self._counting = False
            self.why = "interpreted: no per-state inputs, nothing to compile"
            return
        if codegen.find_compiler() is None:
            self._counting = False
            self.why = "interpreted: no C compiler on PATH"
            return
        cached = codegen.load_cached(self.function, flags=codegen.EXACT_FLAGS)
        if cached is not None:
            self._use(cached, "compiled C, loaded from the cache")
        else:
            self.why = f"interpreted: no cached library; compiled at one-state call {COMPILE_CALLS}"

    def _count(self) -> None:
        self.calls += 1
        if self.calls >= LOOKUP_CALLS and (not self._looked_up or self.calls >= COMPILE_CALLS):
            with self._lock:
                if not self._counting:
                    return
                if not self._looked_up:
                    self._look_up()
                elif self.calls >= COMPILE_CALLS:
                    self._compile(f"compiled C, built at one-state call {COMPILE_CALLS}")

    def _compile(self, why: str) -> None:
        """Compile (or load from the cache) under the lock; one attempt per evaluator."""
        self._counting = False
        try:
            result = codegen.compile_function(self.function, flags=codegen.EXACT_FLAGS)
        except RuntimeError as exc:  # casadi.external could not load the library
            self.why = f"interpreted: cannot load the compiled library ({str(exc).splitlines()[0]})"
            return
        if result.compiled:
            self._use(result, why)
        else:
            self.why = f"interpreted: {result.reason}"

    def _use(self, result: codegen.CompiledFunction, why: str) -> None:
        self._target = result.function
        self.compiled, self.library = True, result.library
        self._counting = False
        self._local = threading.local()  # every thread binds the compiled function at its next call
        kind = 2 if self.kind == "scalar" else 0 if self.kind == "vector" and self._cols == 1 else 1
        caller = native.binding(result.library, self.function.name(), tuple(s for (s,) in self._shapes),
                                self.shared, kind, self._rows, self._cols, self._flat)
        if caller is None:
            self.why = f"{why}; called through CasADi's buffers ({native.unavailable_reason() or 'no binding'})"
            return
        self.why = f"{why}; called through the native binding"
        self._native = caller
        if self._route is not None:
            self._route(caller)

    def compile(self) -> bool:
        """Compile now, or load from the cache; True when compiled C is then in use."""
        with self._lock:
            if not self._looked_up:
                self._look_up()
            if not self.compiled and self._per_state > 0 and codegen.find_compiler() is not None:
                self._compile("compiled C, built or loaded on request")
            return self.compiled


class OneStateTable(dict):
    """Name -> the callable behind one-state calls of a robot's function, created on first use.

    The value is the function's :class:`OneState`, replaced by its native binding (a
    :mod:`designkit.models.native` ``Caller``, same call and results) once it has one: a call then
    goes from the robot's method straight to C.

    Parameters
    ----------
    functions : Mapping of str to casadi.Function
        The robot's function table.
    shared : int
        1 for a symbolic robot (last input ``p``), else 0.
    kinds : Mapping of str to str
        Output kind of each function name (``"vector"``, ``"matrix"``, ``"scalar"``).
    """

    def __init__(self, functions: Mapping[str, ca.Function], shared: int, kinds: Mapping[str, str]) -> None:
        super().__init__()
        self._functions, self._shared, self._kinds = functions, shared, kinds
        self.states: dict[str, OneState] = {}

    def __missing__(self, name: str) -> Callable[..., Any]:
        return self.state(name)

    def state(self, name: str) -> OneState:
        """The :class:`OneState` of function ``name``."""
        one = self.states.get(name)
        if one is None:
            def route(caller: Callable[..., Any]) -> None:
                self[name] = caller

            one = self.states.setdefault(name, OneState(self._functions[name], self._shared, self._kinds[name], route))
            self.setdefault(name, one)
        return one

    def __reduce__(self) -> tuple[Any, ...]:
        """Copies start empty (each :class:`OneState` is rebuilt on first use)."""
        return (OneStateTable, (self._functions, self._shared, self._kinds))
