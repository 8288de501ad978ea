"""Named-parameter overrides shared by the built-in robots."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import casadi as ca

from designkit.errors import ModelError

__all__ = ["resolve"]


def resolve(
    robot: str, defaults: Mapping[str, float], overrides: Mapping[str, Any], symbolic: bool | tuple[str, ...]
) -> tuple[dict[str, Any], tuple[tuple[str, Any], ...]]:
    """Merge ``overrides`` into ``defaults`` and collect symbolic parameters.

    Parameters
    ----------
    robot : str
        Robot name, for error messages.
    defaults : mapping
        Parameter name -> default value (SI units).
    overrides : mapping
        Parameter name -> number or scalar ``casadi.SX`` symbol.
    symbolic : bool or tuple of str
        ``True`` makes every parameter a symbol named after it; a tuple names some of them.

    Returns
    -------
    (dict, tuple)
        The values, and the ``(name, symbol)`` pairs for ``ChainDescription.symbols``,
        in the order of ``defaults``.

    Raises
    ------
    ModelError
        For an unknown name or a value that is neither a finite number nor a symbol.
    """
    names = tuple(defaults) if symbolic is True else tuple(symbolic or ())
    for key in (*overrides, *names):
        if key not in defaults:
            raise ModelError(f"{robot}.{key}", f"unknown parameter; choose from {sorted(defaults)}")
    values: dict[str, Any] = dict(defaults)
    for key, value in overrides.items():
        if isinstance(value, ca.SX):
            if not (value.numel() == 1 and value.is_symbolic()):
                raise ModelError(f"{robot}.{key}", "a symbolic override must be a scalar casadi.SX symbol")
            values[key] = value
            continue
        try:
            values[key] = float(value)
        except (TypeError, ValueError):
            raise ModelError(f"{robot}.{key}", f"must be a number or a casadi.SX symbol, got {value!r}") from None
    for key in names:
        if key not in overrides:
            values[key] = ca.SX.sym(key)
    symbols = tuple((key, values[key]) for key in defaults if isinstance(values[key], ca.SX))
    return values, symbols
