"""Checks of the Python API's arguments at the boundary: one rule per kind of argument, shared by every entry point.

Each check returns the argument in the form the code below it expects (a plain ``str``, an ``int``, a ``float``, a
``bool``, a :class:`~pathlib.Path`) or raises a :class:`~designkit.errors.DesignkitError` whose ``path`` is the
argument's name (by default a :class:`~designkit.errors.SpecError`; ``error`` picks the class an entry point
documents, e.g. :class:`~designkit.errors.OutputError` for an output folder).  Nothing is read or written here,
so an entry point that checks its arguments first writes nothing on bad input.

The rules:

* text (:func:`text`): a ``str`` (a subclass is read as its plain value), encodable as UTF-8 (no lone surrogate),
  without NUL characters;
* file system paths (:func:`path`): a ``str`` or an ``os.PathLike`` of ``str``, not empty, under the same rules as
  text (the operating system cannot take a NUL or a lone surrogate);
* integers (:func:`integer`): an ``int`` or NumPy integer, never a ``bool`` nor a float, within the given range;
* numbers (:func:`number`): a real number (``int``, ``float``, NumPy), never a ``bool`` nor text, finite unless
  told, within the given range;
* flags (:func:`flag`): ``True`` or ``False`` (NumPy booleans too), nothing merely truthy;
* choices (:func:`choice`): one of the given strings;
* objects (:func:`instance`): an instance of the class the function works on.

Examples
--------
>>> integer(3, "trials", low=1)
3
>>> integer(1.5, "chunk", low=1)
Traceback (most recent call last):
...
designkit.errors.SpecError: chunk: must be an integer, got float 1.5
"""

from __future__ import annotations

import math
import numbers
import os
from collections.abc import Iterable
from pathlib import Path

from designkit.errors import DesignkitError, SpecError, short_repr

__all__ = ["choice", "flag", "instance", "integer", "number", "path", "text"]

ErrorType = type[DesignkitError]


def _got(value: object) -> str:
    """``<type> <value>``, the value quoted briefly."""
    return f"{type(value).__name__} {short_repr(value, 40)}"


def _plain(value: str, name: str, error: ErrorType, what: str) -> str:
    """``value`` as a plain ``str`` after the text rules (UTF-8 encodable, no NUL)."""
    value = str.__str__(value)  # a subclass's own methods are never called below
    bad = next((k for k, c in enumerate(value) if "\ud800" <= c <= "\udfff"), None)
    if bad is not None:
        raise error(name, f"{what} holds a lone surrogate at character {bad} (not encodable as UTF-8)")
    if "\0" in value:
        raise error(name, f"{what} holds a NUL character at character {value.index(chr(0))}")
    return value


def text(value: object, name: str, *, error: ErrorType = SpecError, empty: bool = True) -> str:
    """``value`` as a plain ``str``; refused when not text, not UTF-8 encodable, holding a NUL, or empty (unless
    ``empty``)."""
    if not isinstance(value, str):
        raise error(name, f"must be text (str), got {_got(value)}")
    value = _plain(value, name, error, "the text")
    if not empty and not value.strip():
        raise error(name, "must not be empty")
    return value


def path(value: object, name: str, *, error: ErrorType = SpecError, what: str = "a file path") -> Path:
    """``value`` as a :class:`~pathlib.Path`: a ``str`` or ``os.PathLike`` of ``str``, not empty, no NUL, UTF-8
    encodable.  Whether it exists is for the caller to say (with its own words)."""
    if isinstance(value, bytes | bytearray) or not isinstance(value, str | os.PathLike):
        raise error(name, f"must be {what} (str or os.PathLike), got {type(value).__name__}")
    try:
        raw = os.fspath(value)
    except Exception:  # noqa: BLE001 - a user's __fspath__ may raise anything
        raise error(name, f"must be {what}: its __fspath__ failed") from None
    if not isinstance(raw, str):
        raise error(name, f"must be {what} (str or os.PathLike of str), got a path of {type(raw).__name__}")
    raw = _plain(raw, name, error, "the path")
    if not raw:
        raise error(name, f"must be {what}, got an empty path")
    return Path(raw)


def integer(value: object, name: str, *, low: int | None = None, high: int | None = None,
            error: ErrorType = SpecError) -> int:
    """``value`` as an ``int`` in ``[low, high]``; floats (even whole ones), booleans and text are refused."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise error(name, f"must be an integer, got {_got(value)}")
    value = int(value)
    if (low is not None and value < low) or (high is not None and value > high):
        raise error(name, f"must be an integer {_range(low, high)}, got {short_repr(value, 40)}")
    return value


def number(value: object, name: str, *, low: float | None = None, high: float | None = None,
           positive: bool = False, finite: bool = True, error: ErrorType = SpecError) -> float:
    """``value`` as a ``float`` in ``[low, high]`` (and ``> 0`` with ``positive``); NaN is always refused, the
    infinities unless ``not finite``; booleans, text and complex numbers are refused."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise error(name, f"must be a real number, got {_got(value)}")
    try:
        out = float(value)
    except OverflowError:
        raise error(name, f"must be a real number of floating-point size, got {short_repr(value, 40)}") from None
    if math.isnan(out) or (finite and math.isinf(out)):
        raise error(name, f"must be a finite number, got {out!r}")
    if positive and not out > 0:
        raise error(name, f"must be positive, got {out!r}")
    if (low is not None and out < low) or (high is not None and out > high):
        raise error(name, f"must be a number {_range(low, high)}, got {out!r}")
    return out


def flag(value: object, name: str, *, error: ErrorType = SpecError) -> bool:
    """``value`` as a ``bool``: only ``True`` and ``False`` (NumPy booleans too)."""
    if isinstance(value, bool) or (type(value).__module__ == "numpy" and type(value).__name__ in ("bool", "bool_")):
        return bool(value)
    raise error(name, f"must be True or False, got {_got(value)}")


def instance(value: object, name: str, kind: type | tuple[type, ...], what: str, *, error: ErrorType = SpecError,
             optional: bool = False) -> object:
    """``value`` when it is a ``kind`` (or None with ``optional``); ``what`` names the expected object."""
    if (optional and value is None) or isinstance(value, kind):
        return value
    raise error(name, f"must be {what}, got {type(value).__name__}")


def choice(value: object, name: str, options: Iterable[str], *, error: ErrorType = SpecError) -> str:
    """``value``, one of ``options`` (compared as plain text)."""
    options = tuple(options)
    if isinstance(value, str) and str.__str__(value) in options:
        return str.__str__(value)
    raise error(name, f"must be one of {', '.join(map(repr, options))}, got {_got(value)}")


def _range(low: float | None, high: float | None) -> str:
    if low is not None and high is not None:
        return f"from {low:,} to {high:,}"
    return f"of at least {low:,}" if low is not None else f"of at most {high:,}"
