"""NumPy-in/NumPy-out evaluation of a named ``casadi.Function``, one state or a batch.

Each argument is one state (shape ``(size,)``) or a batch (shape ``(N, size)``);
1-D arguments broadcast against a batch.  A batch is evaluated in one call of
``casadi.Function.map(N)``, and the results are stacked along a leading axis
of length ``N``.  The mapped functions are memoised per (name, ``N``) in a
dictionary the caller owns, cleared when it reaches :data:`MAX_MAPS` entries.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import casadi as ca
import numpy as np

from designkit.errors import ModelError

__all__ = ["MAX_MAPS", "evaluate", "shape_output"]

MAX_MAPS = 64
"""Mapped functions kept per caller before the memo is cleared."""


def evaluate(
    function: ca.Function,
    args: Sequence[tuple[str, Any]],
    p: Any,
    *,
    symbol_names: Sequence[str],
    maps: dict[tuple[str, int], ca.Function],
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
    maps : dict
        Memo of mapped functions, keyed by (function name, batch size); updated in place.

    Returns
    -------
    (list of numpy.ndarray, int or None)
        The outputs, 2-D for one state or ``(N, rows, cols)`` for a batch, and ``N`` (``None`` for one state).

    Raises
    ------
    ModelError
        For a wrongly shaped argument, batches of different sizes, or missing/unexpected ``p``.
    """
    arrays: list[np.ndarray] = []
    batch: int | None = None
    for index, (label, value) in enumerate(args):
        size = function.size1_in(index)
        array = np.asarray(value, dtype=float)
        if array.ndim == 1 and array.shape[0] == size:
            arrays.append(array.reshape(size, 1))
        elif array.ndim == 2 and array.shape[1] == size:
            if batch is not None and array.shape[0] != batch:
                raise ModelError(label, f"batch of {array.shape[0]} rows, other inputs have {batch}")
            batch = array.shape[0]
            arrays.append(array.T)
        else:
            raise ModelError(label, f"expected shape ({size},) or (N, {size}), got {array.shape}")
    if symbol_names:
        if p is None:
            raise ModelError("p", f"symbolic robot: give values for {symbol_names}")
        p_array = np.asarray(p, dtype=float).reshape(-1)
        if p_array.shape[0] != len(symbol_names):
            raise ModelError("p", f"expected {len(symbol_names)} values, got {p_array.shape[0]}")
        arrays.append(p_array.reshape(-1, 1))
    elif p is not None:
        raise ModelError("p", "this robot has no symbolic parameters")
    if batch is None:
        outputs = function.call([ca.DM(a) for a in arrays])
        return [np.array(out) for out in outputs], None
    key = (function.name(), batch)
    if key not in maps:
        if len(maps) >= MAX_MAPS:  # a memo, not a store: forget old batch sizes
            maps.clear()
        maps[key] = function.map(batch)
    outputs = maps[key].call([ca.DM(a) for a in arrays])
    shaped = []
    for index, out in enumerate(outputs):
        rows, cols = function.size_out(index)
        shaped.append(np.array(out).reshape(rows, batch, cols).transpose(1, 0, 2))
    return shaped, batch


def shape_output(value: np.ndarray, kind: str, batch: int | None) -> Any:
    """Squeeze ``vector`` results to 1-D and ``scalar`` results to floats (or ``(N,)``).

    ``kind`` is ``"scalar"``, ``"vector"`` or ``"matrix"`` (returned as is); ``batch`` is ``N`` or ``None``.
    """
    if kind == "scalar":
        return float(value[0, 0]) if batch is None else value[:, 0, 0]
    if kind == "vector":
        return value[..., 0]
    return value
