"""A box of a function's inputs: a closed interval for every scalar input, checked before any work.

A CasADi function's inputs are named (``q``, ``qd``); a :class:`Box` gives every scalar entry of
every input a closed interval ``[lo, hi]`` (a point when ``lo == hi``: the entry is held fixed).
Inputs are flattened in the function's order, each column-major as CasADi stores it.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.errors import SpecError

__all__ = ["Box"]


def _side(value: Any, size: int, path: str) -> np.ndarray:
    try:
        a = np.asarray(value)
    except Exception:  # noqa: BLE001 - ragged nests and exotic objects alike
        raise SpecError(path, f"must be a number or {size} numbers") from None
    if a.dtype.kind not in "iuf" or a.dtype == bool:
        raise SpecError(path, f"must be real numbers, got {a.dtype}")
    a = a.astype(float).reshape(-1)
    if a.size == 1:
        a = np.full(size, a[0])
    if a.size != size:
        raise SpecError(path, f"needs {size} values (one per entry), got {a.size}")
    bad = np.flatnonzero(~np.isfinite(a))
    if bad.size:
        raise SpecError(f"{path}[{bad[0]}]", f"must be finite, got {a[bad[0]]}")
    return a


@dataclass(frozen=True, eq=False)
class Box:
    """Closed intervals ``lower <= x <= upper`` for the scalar inputs of a function.

    Parameters
    ----------
    names : tuple of str
        The function's input names, in order.
    sizes : tuple of int
        Scalar entries of each input.
    lower, upper : ndarray
        One bound per scalar entry, inputs concatenated (read-only), in the inputs' units.
    """

    names: tuple[str, ...]
    sizes: tuple[int, ...]
    lower: np.ndarray
    upper: np.ndarray

    def __post_init__(self) -> None:
        for side in ("lower", "upper"):
            a = np.array(getattr(self, side), dtype=float).reshape(-1)
            a.setflags(write=False)
            object.__setattr__(self, side, a)

    @classmethod
    def of(cls, function: Any, bounds: Mapping[str, Any]) -> Box:
        """The box ``bounds`` gives the inputs of ``function`` (a ``casadi.Function``).

        Parameters
        ----------
        function : casadi.Function
        bounds : Mapping
            Input name -> ``(lo, hi)``, a tuple or list of two sides (each a number or one number per
            entry), or a number or NumPy array (the input held fixed there).

        Raises
        ------
        SpecError
            Naming ``box['name']`` (and the entry): an input left unbounded, an input the function does not
            have, a side of the wrong length or not finite, ``lo > hi``.
        """
        names = tuple(function.name_in(i) for i in range(function.n_in()))
        sizes = tuple(int(function.nnz_in(i)) for i in range(function.n_in()))
        if not isinstance(bounds, Mapping):
            raise SpecError("box", f"must map the inputs {list(names)} to (lo, hi), got {type(bounds).__name__}")
        unknown = sorted(set(bounds) - set(names))
        if unknown:
            raise SpecError(f"box[{unknown[0]!r}]", f"{function.name()} has no input {unknown[0]!r}; its inputs "
                            f"are {list(names)}")
        lows, highs = [], []
        for name, size in zip(names, sizes, strict=True):
            if size == 0:
                continue
            if name not in bounds:
                raise SpecError(f"box[{name!r}]", f"not bounded: {function.name()} depends on its {size} "
                                "entries; give (lo, hi) or a fixed value")
            value = bounds[name]
            pair = isinstance(value, tuple | list) and len(value) == 2
            lo, hi = (value[0], value[1]) if pair else (value, value)
            lo = _side(lo, size, f"box[{name!r}].lo" if pair else f"box[{name!r}]")
            hi = _side(hi, size, f"box[{name!r}].hi" if pair else f"box[{name!r}]")
            wrong = np.flatnonzero(lo > hi)
            if wrong.size:
                k = int(wrong[0])
                raise SpecError(f"box[{name!r}][{k}]", f"lo > hi ({lo[k]:g} > {hi[k]:g})")
            lows.append(lo)
            highs.append(hi)
        low = np.concatenate(lows) if lows else np.zeros(0)
        high = np.concatenate(highs) if highs else np.zeros(0)
        return cls(names, sizes, low, high)

    @property
    def dimension(self) -> int:
        """Scalar entries, fixed ones included."""
        return int(self.lower.size)

    @property
    def free(self) -> np.ndarray:
        """Indices of the entries with ``lo < hi``."""
        return np.flatnonzero(self.upper > self.lower)

    @property
    def widths(self) -> np.ndarray:
        """``upper - lower`` per entry."""
        return self.upper - self.lower

    def label(self, k: int) -> str:
        """``q[2]`` for flattened entry ``k``."""
        for name, size in zip(self.names, self.sizes, strict=True):
            if k < size:
                return f"{name}[{k}]"
            k -= size
        raise IndexError(k)

    def split(self, x: np.ndarray) -> dict[str, np.ndarray]:
        """A flattened point as input name -> its entries."""
        out, start = {}, 0
        for name, size in zip(self.names, self.sizes, strict=True):
            out[name] = np.asarray(x[start:start + size], dtype=float)
            start += size
        return out
