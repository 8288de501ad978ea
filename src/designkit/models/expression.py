"""A tiny arithmetic grammar over named plant parameters, parsed into CasADi expressions (no ``eval``).

An entry of a linear plant's matrices or polynomials may be a number or a text such as ``"b"``, ``"-a"``,
``"2*a"``, ``"(k + 1)/tau"``.  The grammar::

    expr   := term (("+" | "-") term)*
    term   := factor (("*" | "/") factor)*
    factor := ("+" | "-") factor | atom
    atom   := number | name | "(" expr ")"

``number`` is a decimal literal (``2``, ``0.5``, ``1e-3``); ``name`` one of the plant's parameter names.  Nothing
else is read: no function calls, no attributes, no powers.  Each name becomes the CasADi symbol of its parameter,
so an entry is an expression in the parameter vector ``p`` of the plant's ODE and follows every parameter value a
robustness box or a plant change gives.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping

import casadi as ca

from designkit.errors import ModelError

__all__ = ["MAX_LENGTH", "parse_entry"]

MAX_LENGTH = 200
"""Longest entry text (characters)."""

_TOKEN = re.compile(r"\s*(?:(?P<number>(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)|(?P<name>[A-Za-z_][A-Za-z_0-9]*)"
                    r"|(?P<op>[-+*/()]))")


def _tokens(text: str, field: str) -> list[tuple[str, str]]:
    out: list[tuple[str, str]] = []
    pos = 0
    stripped = text.rstrip()
    while pos < len(stripped):
        m = _TOKEN.match(stripped, pos)
        if m is None:
            raise ModelError(field, f"cannot read {text!r} at character {pos + 1}: an entry is a number, a parameter "
                                    "name, + - * / and parentheses")
        kind = m.lastgroup or ""
        out.append((kind, m.group(kind)))
        pos = m.end()
    return out


class _Parser:
    def __init__(self, text: str, symbols: Mapping[str, ca.SX], field: str) -> None:
        self.text, self.symbols, self.field = text, symbols, field
        self.tokens = _tokens(text, field)
        self.i = 0

    def _peek(self) -> tuple[str, str] | None:
        return self.tokens[self.i] if self.i < len(self.tokens) else None

    def _fail(self, what: str) -> ModelError:
        return ModelError(self.field, f"cannot read {self.text!r}: {what}")

    def parse(self) -> ca.SX:
        if not self.tokens:
            raise self._fail("empty entry")
        value = self._expr()
        if self._peek() is not None:
            raise self._fail(f"unexpected {self._peek()[1]!r}")  # type: ignore[index]
        return value

    def _expr(self) -> ca.SX:
        value = self._term()
        while (tok := self._peek()) is not None and tok[1] in "+-" and tok[0] == "op":
            self.i += 1
            rhs = self._term()
            value = value + rhs if tok[1] == "+" else value - rhs
        return value

    def _term(self) -> ca.SX:
        value = self._factor()
        while (tok := self._peek()) is not None and tok[0] == "op" and tok[1] in "*/":
            self.i += 1
            rhs = self._factor()
            value = value * rhs if tok[1] == "*" else value / rhs
        return value

    def _factor(self) -> ca.SX:
        tok = self._peek()
        if tok is not None and tok[0] == "op" and tok[1] in "+-":
            self.i += 1
            inner = self._factor()
            return -inner if tok[1] == "-" else inner
        return self._atom()

    def _atom(self) -> ca.SX:
        tok = self._peek()
        if tok is None:
            raise self._fail("ends where a number, a name or '(' is expected")
        self.i += 1
        kind, text = tok
        if kind == "number":
            value = float(text)
            if not math.isfinite(value):
                raise self._fail(f"the number {text} is not finite")
            return ca.SX(value)
        if kind == "name":
            if text not in self.symbols:
                known = ", ".join(self.symbols) or "none"
                raise ModelError(self.field, f"unknown parameter {text!r} in {self.text!r}; the plant's parameters "
                                             f"are: {known} (declare it under plant.parameters)")
            return self.symbols[text]
        if text == "(":
            value = self._expr()
            close = self._peek()
            if close is None or close[1] != ")":
                raise self._fail("a '(' is not closed")
            self.i += 1
            return value
        raise self._fail(f"unexpected {text!r}")


def parse_entry(entry: float | int | str, symbols: Mapping[str, ca.SX], field: str) -> ca.SX:
    """One matrix or polynomial entry as a CasADi expression in the parameter symbols.

    Parameters
    ----------
    entry : float, int or str
        A finite number, or a text in the grammar of the module docstring (at most :data:`MAX_LENGTH` characters).
    symbols : Mapping[str, casadi.SX]
        Parameter name -> its scalar symbol.
    field : str
        The entry's key path under ``plant`` (``"A[1][2]"``, ``"den[0]"``), named by any error.

    Returns
    -------
    casadi.SX
        A scalar expression (constant for a number).

    Raises
    ------
    ModelError
        At ``field``: a non-finite number, an unreadable text, an unknown parameter name.

    Examples
    --------
    >>> a, b = ca.SX.sym("a"), ca.SX.sym("b")
    >>> f = ca.Function("f", [a, b], [parse_entry("-(2*a - b)/4", {"a": a, "b": b}, "x")])
    >>> float(f(3.0, 2.0))
    -1.0
    """
    if isinstance(entry, bool):
        raise ModelError(field, f"must be a number or a text over the parameters, got {entry!r}")
    if isinstance(entry, int | float):
        value = float(entry)
        if not math.isfinite(value):
            raise ModelError(field, f"must be finite, got {entry!r}")
        return ca.SX(value)
    if not isinstance(entry, str):
        raise ModelError(field, f"must be a number or a text over the parameters, got {entry!r}")
    if len(entry) > MAX_LENGTH:
        raise ModelError(field, f"is longer than {MAX_LENGTH} characters")
    return _Parser(entry, symbols, field).parse()
