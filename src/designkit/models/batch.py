"""NumPy-in/NumPy-out evaluation of a named ``casadi.Function``, one state or a batch.

Each argument is one state (shape ``(size,)``) or a batch (shape ``(N, size)``); 1-D arguments
broadcast against a batch.  Outputs come back 2-D for one state, or stacked along a leading axis of
length ``N`` for a batch.

How a call runs (the default path is the fast path)
---------------------------------------------------
One :class:`Evaluator` per function and robot evaluates through CasADi's buffer interface
(``casadi.Function.buffer``): CasADi reads and writes NumPy arrays directly, with no ``casadi.DM``
conversions.  What it evaluates is

* **compiled C** when available: the function mapped over a block of :data:`BLOCK` states
  (``Function.map``), written out by ``casadi.CodeGenerator`` and compiled by the system C compiler
  with :data:`~designkit.models.codegen.EXACT_FLAGS` (``-O1 -ffp-contract=off``: no reassociation,
  no fused multiply-add, so the results are bit-identical to the interpreter's);
* otherwise the **interpreted** Function, in blocks of one state.

A batch of more than :data:`CHUNK` states is evaluated in place, ``CHUNK`` states per call of one
``map`` of the block, and its last ``N mod CHUNK`` states like a small batch.  A small batch, a single
state included, is copied into arrays the evaluator keeps, bound to CasADi once per number of blocks,
and evaluated in whole blocks (the rows past ``N`` hold earlier inputs; their results are dropped).

When is the C compiled?  Deterministic, never in the background:

1. The first call of a function of a robot looks its compiled block up in the on-disk cache of
   :mod:`designkit.models.codegen` (:func:`~designkit.models.codegen.load_cached`, which generates the
   C source to hash it: 1-40 ms for the PUMA 560's functions, once per robot and function).  If the
   library is there it is loaded and used from then on, for batches and single states alike.
2. A batch of at least :data:`COMPILE_MIN_STATES` states compiles the block if it is not cached
   (0.1-2 s for the PUMA 560's functions, once per machine: the library is cached under a content
   hash of the C source, compiler and flags, in ``$DESIGNKIT_CACHE_DIR/codegen`` or
   ``~/.cache/designkit/codegen``) and uses it.
3. Smaller batches and single states never compile: without a cached library they run interpreted.
   :meth:`Evaluator.compile` compiles ahead of time.
4. Without a C compiler (none of ``cc``, ``gcc``, ``clang`` on ``PATH``), when compiling fails or
   the cache directory is not writable, calls run interpreted; the failure is remembered for the
   evaluator, not retried at every call.  Functions without per-state inputs (``parameters``) are
   never compiled.  :attr:`Evaluator.why` says which path runs and why.
"""

from __future__ import annotations

import threading
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from designkit.errors import ModelError
from designkit.models import codegen

__all__ = ["BLOCK", "CHUNK", "COMPILE_MIN_STATES", "MAX_MAPS", "Evaluator", "evaluate", "evaluator_for",
           "shape_output"]

BLOCK = 16
"""States per compiled block.  Each call of the block from CasADi's outer ``map`` costs about 0.1 us,
shared by ``BLOCK`` states; the last, partial block of a call evaluates at most ``BLOCK - 1`` unused rows
(about 3 us for the PUMA 560's inverse dynamics)."""

COMPILE_MIN_STATES = 10_000
"""A batch of at least this many states compiles the function when its library is not cached yet.
Compiling costs 0.1-2 s (PUMA 560, ``-O1``), about what the interpreter spends on 2e4-1e5 states of the
same function; it is paid once per machine, the library being cached on disk."""

CHUNK = 1024
"""States per evaluation call into CasADi (a multiple of :data:`BLOCK`).  A batch of at most ``CHUNK`` states
is copied into arrays the evaluator keeps, bound to CasADi once per number of blocks, so that a call makes two
CasADi calls (evaluate, check) rather than one more per argument; a larger batch is evaluated in place,
``CHUNK`` states per call, its last part copied.  One ``map`` of ``CHUNK`` states serves every batch size:
building a ``map`` over ``n`` compiled blocks costs about 0.25 s for ``n = 6250`` (1e5 states)."""

MAX_MAPS = 64
"""Mapped functions (with their buffers) kept per evaluator before the memo is cleared."""


class Evaluator:
    """Evaluates one ``casadi.Function`` on NumPy rows, through compiled C when possible.

    Parameters
    ----------
    function : casadi.Function
        Dense column-vector inputs: first the per-state ("mapped") inputs, then ``shared`` inputs
        that are the same for every state (the symbol values ``p`` of a symbolic robot).
    shared : int
        Number of trailing shared inputs.

    Attributes
    ----------
    compiled : bool
        True when calls run compiled C.
    why : str
        Which path runs and why (the policy of the module docstring).
    library : pathlib.Path or None
        The shared library, when ``compiled``.
    """

    def __init__(self, function: ca.Function, shared: int = 0) -> None:
        self.function = function
        self.mapped = function.n_in() - shared
        self._shared = list(range(self.mapped, function.n_in()))
        self.compiled = False
        self.library: Path | None = None
        self.why = "interpreted: not called yet"
        self._block = function
        self._size = 1
        self._looked_up = False
        self._may_compile = self.mapped > 0
        self.sizes = tuple(function.size1_in(k) for k in range(self.mapped))
        self._runners: dict[tuple[int, bool], tuple[ca.Function, Any, Any]] = {}
        self._scratch: tuple[list[np.ndarray], list[np.ndarray], list[np.ndarray]] | None = None
        self._lock = threading.RLock()
        self._layout = []
        for k in range(function.n_out()):
            pattern = function.sparsity_out(k)
            flat = None if pattern.is_dense() else (  # column-major index of each nonzero
                np.array(pattern.row(), dtype=np.intp) + pattern.size1() * np.array(pattern.get_col(), dtype=np.intp))
            self._layout.append((pattern.size1(), pattern.size2(), pattern.nnz(), flat))

    def __getstate__(self) -> dict[str, Any]:
        """Copies start afresh (buffers, lock and compiled library are per evaluator; the cache is looked up again)."""
        return {"function": self.function, "shared": len(self._shared)}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__init__(state["function"], state["shared"])  # type: ignore[misc]

    def block_function(self) -> ca.Function:
        """The function mapped over :data:`BLOCK` states (shared inputs not mapped): what gets compiled."""
        name = f"{self.function.name()}_block{BLOCK}"
        return self.function.map(name, "serial", BLOCK, self._shared, [])

    def compile(self) -> bool:
        """Compile the block now, or load it from the cache; True when compiled C is then in use."""
        with self._lock:
            if self.compiled or self.mapped == 0:
                return self.compiled
            self._looked_up = self._may_compile = True
            self._compile("compiled C, built or loaded on request")
            return self.compiled

    def _compile(self, why: str) -> None:
        self._may_compile = False  # one attempt per evaluator: a failure is not retried at every call
        try:
            result = codegen.compile_function(self.block_function(), flags=codegen.EXACT_FLAGS)
        except RuntimeError as exc:  # casadi.external could not load the library
            self.why = f"interpreted: cannot load the compiled library ({str(exc).splitlines()[0]})"
            return
        if result.compiled:
            self._use(result, why)
        else:
            self.why = f"interpreted: {result.reason}"

    def _use(self, result: codegen.CompiledFunction, why: str) -> None:
        self._block, self._size = result.function, BLOCK
        self.compiled, self.library, self.why = True, result.library, why
        self._runners.clear()
        self._scratch = None

    def _prepare(self, states: int) -> None:
        """Apply the compilation policy (module docstring) before evaluating ``states`` states."""
        if self.compiled or self.mapped == 0:
            return
        if not self._looked_up:
            self._looked_up = True
            if codegen.find_compiler() is None:
                self._may_compile = False
                self.why = "interpreted: no C compiler on PATH"
                return
            cached = codegen.load_cached(self.block_function(), flags=codegen.EXACT_FLAGS)
            if cached is not None:
                self._use(cached, "compiled C, loaded from the cache")
                return
            self.why = f"interpreted: no cached library, and batches under {COMPILE_MIN_STATES} states do not compile"
        if states >= COMPILE_MIN_STATES and self._may_compile:
            self._compile(f"compiled C, built for a batch of {states} states")

    def _runner(self, blocks: int, kept: bool) -> tuple[ca.Function, Any, Any]:
        """``(function, buffer, run)`` for ``blocks`` blocks; ``kept``: bound once to the evaluator's own arrays."""
        runner = self._runners.get((blocks, kept))
        if runner is None:
            if len(self._runners) >= MAX_MAPS:  # a memo, not a store: forget old batch sizes
                self._runners.clear()
            # The plain map: every input mapped, shared ones repeated per block.  (A map with non-mapped inputs,
            # Function.map(name, parallelization, n, reduce_in, reduce_out), wraps n calls in an MX Function;
            # the block uses it, with n = BLOCK.)
            fn = self._block if blocks == 1 else self._block.map(blocks, "serial")
            buffer, run = fn.buffer()
            if kept:
                if self._scratch is None:
                    most = CHUNK // self._size  # blocks
                    self._scratch = ([np.zeros((most * self._size, size)) for size in self.sizes],
                                     [np.zeros((most, self.function.size1_in(k))) for k in self._shared],
                                     [np.zeros((most * self._size, nnz)) for _, _, nnz, _ in self._layout])
                args, params, outs = self._scratch
                end = blocks * self._size
                for index, array in enumerate([*(a[:end] for a in args), *(p[:blocks] for p in params)]):
                    buffer.set_arg(index, memoryview(array))
                for index, array in enumerate(outs):
                    buffer.set_res(index, memoryview(array[:end]))
            runner = self._runners[(blocks, kept)] = (fn, buffer, run)
        return runner

    def _run_kept(self, inputs: Sequence[np.ndarray], shared: Sequence[np.ndarray],
                  results: Sequence[np.ndarray], start: int, count: int) -> None:
        """Evaluate rows ``start:count`` (at most :data:`CHUNK`) through the evaluator's own arrays.

        The rows of the last block past ``count`` hold earlier inputs (zeros at first); their results are dropped.
        """
        rows = count - start
        blocks = -(-rows // self._size)
        fn, buffer, run = self._runner(blocks, kept=True)
        args, params, outs = self._scratch  # type: ignore[misc]  # made by _runner
        for arg, array in zip(args, inputs, strict=True):
            arg[:rows] = array[start:]
        for param, array in zip(params, shared, strict=True):
            param[:blocks] = array
        run()
        if buffer.ret() != 0:
            raise ModelError(f"evaluation of {fn.name()!r} failed (return code {buffer.ret()})")
        for result, out in zip(results, outs, strict=True):
            result[start:] = out[:rows]

    def _run_in_place(self, inputs: Sequence[np.ndarray], shared: Sequence[np.ndarray],
                      results: Sequence[np.ndarray], done: int) -> None:
        """Evaluate rows ``0:done`` (a multiple of :data:`CHUNK`) in place, ``CHUNK`` rows per call."""
        fn, buffer, run = self._runner(CHUNK // self._size, kept=False)
        repeated = [np.tile(array, CHUNK // self._size) for array in shared]  # once per block
        for index, array in enumerate(repeated):
            buffer.set_arg(self.mapped + index, memoryview(array))
        for start in range(0, done, CHUNK):
            for index, array in enumerate(inputs):
                buffer.set_arg(index, memoryview(array[start:start + CHUNK]))
            for index, array in enumerate(results):
                buffer.set_res(index, memoryview(array[start:start + CHUNK]))
            run()
            if buffer.ret() != 0:
                raise ModelError(f"evaluation of {fn.name()!r} failed (return code {buffer.ret()})")

    def __call__(self, inputs: Sequence[np.ndarray], shared: Sequence[np.ndarray], count: int) -> list[np.ndarray]:
        """Evaluate ``count`` states.

        Parameters
        ----------
        inputs : sequence of numpy.ndarray
            Per mapped input, a C-contiguous float array of shape ``(count, size)``.
        shared : sequence of numpy.ndarray
            Per shared input, a C-contiguous float array of its size.
        count : int
            Number of states.

        Returns
        -------
        list of numpy.ndarray
            Per output, shape ``(count, rows, cols)``.
        """
        with self._lock:
            self._prepare(count)
            results = [np.empty((count, nnz)) for _, _, nnz, _ in self._layout]
            done = 0 if count <= CHUNK else count // CHUNK * CHUNK
            if done:  # whole chunks in place
                self._run_in_place(inputs, shared, results, done)
            if count > done:  # a small batch, or the last part of a large one
                self._run_kept(inputs, shared, results, done, count)
        shaped = []
        for (rows, cols, _, flat), result in zip(self._layout, results, strict=True):
            if flat is not None:  # scatter the nonzeros of a sparse output
                dense = np.zeros((count, rows * cols))
                dense[:, flat] = result
                result = dense
            shaped.append(result.reshape(count, cols, rows).transpose(0, 2, 1))  # column-major per state
        return shaped


def evaluator_for(function: ca.Function, evaluators: dict[str, Evaluator], shared: int) -> Evaluator:
    """The :class:`Evaluator` of ``function`` in ``evaluators`` (keyed by function name), created on first use."""
    evaluator = evaluators.get(function.name())
    if evaluator is None or evaluator.function is not function:
        evaluator = evaluators[function.name()] = Evaluator(function, shared)
    return evaluator


def _real_array(value: Any, label: str) -> np.ndarray:
    """``value`` as a float array; booleans, complex numbers, text and other objects are refused by name."""
    try:
        raw = np.asarray(value)
    except (TypeError, ValueError):
        raise ModelError(label, "must be real numbers (a number, a list or an array)") from None
    kind = raw.dtype.kind
    if kind == "b":
        raise ModelError(label, "must be real numbers, got booleans")
    if kind == "c":
        raise ModelError(label, "must be real numbers, got complex numbers (the imaginary part would be lost)")
    if kind in "USa":
        raise ModelError(label, "must be real numbers, got text")
    if kind == "O":
        import numbers

        if not all(isinstance(v, numbers.Real) and not isinstance(v, bool) for v in raw.reshape(-1)):
            raise ModelError(label, "must be real numbers, got other objects (None, text, booleans or nested lists)")
        return raw.astype(float)
    if kind not in "iuf":
        raise ModelError(label, f"must be real numbers, got {raw.dtype} entries")
    return raw.astype(float, copy=False)


def evaluate(
    function: ca.Function,
    args: Sequence[tuple[str, Any]],
    p: Any,
    *,
    symbol_names: Sequence[str],
    evaluators: dict[str, Evaluator],
) -> tuple[list[np.ndarray], int | None]:
    """Evaluate ``function`` on NumPy arguments.

    Parameters
    ----------
    function : casadi.Function
        Column-vector inputs in the order of ``args``, then ``"p"`` when ``symbol_names`` is not empty.
    args : sequence of (str, array_like)
        ``(label, value)`` per input; the label names the argument in a :class:`ModelError`.
    p : array_like or None
        Values of the symbolic parameters, in the order of ``symbol_names``.
    symbol_names : sequence of str
        Names of the symbolic parameters (empty for a numeric model).
    evaluators : dict
        The caller's :class:`Evaluator` per function name; updated in place.

    Returns
    -------
    (list of numpy.ndarray, int or None)
        The outputs, 2-D for one state or ``(N, rows, cols)`` for a batch, and ``N`` (``None`` for one state).

    Raises
    ------
    ModelError
        For a wrongly shaped argument, batches of different sizes, or missing/unexpected ``p``.
    """
    evaluator = evaluator_for(function, evaluators, 1 if symbol_names else 0)
    arrays: list[np.ndarray] = []
    batch: int | None = None
    for (label, value), size in zip(args, evaluator.sizes, strict=True):
        array = _real_array(value, label)
        if array.ndim == 1 and array.shape[0] == size:
            arrays.append(array)
        elif array.ndim == 2 and array.shape[1] == size:
            if batch is not None and array.shape[0] != batch:
                raise ModelError(label, f"batch of {array.shape[0]} rows, other inputs have {batch}")
            batch = array.shape[0]
            arrays.append(array)
        else:
            raise ModelError(label, f"expected shape ({size},) or (N, {size}), got {array.shape}")
    shared: list[np.ndarray] = []
    if symbol_names:
        if p is None:
            raise ModelError("p", f"symbolic robot: give values for {symbol_names}")
        p_array = np.ascontiguousarray(_real_array(p, "p").reshape(-1))
        if p_array.shape[0] != len(symbol_names):
            raise ModelError("p", f"expected {len(symbol_names)} values, got {p_array.shape[0]}")
        shared.append(p_array)
    elif p is not None:
        raise ModelError("p", "this robot has no symbolic parameters")
    if batch is None:
        outputs = evaluator([a.reshape(1, -1) for a in arrays], shared, 1)
        return [out[0] for out in outputs], None
    rows = [np.ascontiguousarray(a if a.ndim == 2 else np.broadcast_to(a, (batch, a.shape[0]))) for a in arrays]
    return evaluator(rows, shared, batch), batch


def shape_output(value: np.ndarray, kind: str, batch: int | None) -> Any:
    """Squeeze ``vector`` results to 1-D and ``scalar`` results to floats (or ``(N,)``).

    ``kind`` is ``"scalar"``, ``"vector"`` or ``"matrix"`` (returned as is); ``batch`` is ``N`` or ``None``.
    """
    if kind == "scalar":
        return float(value[0, 0]) if batch is None else value[:, 0, 0]
    if kind == "vector":
        return value[..., 0]
    return value
