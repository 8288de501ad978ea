"""A CasADi SX function's instruction list, evaluated in Arb ball arithmetic (python-flint).

CasADi stores an ``SXFunction`` as a straight-line program: a list of instructions, each an
operation code, the work registers it reads and the register it writes (``Function.instruction_id``,
``instruction_input``, ``instruction_output``, ``instruction_constant``).  :func:`compile_tape`
reads that list once into a :class:`Tape`; :func:`evaluate` runs it with every register an
``arb`` ball (midpoint, radius), so each result is a ball that contains the exact value of the
operation for every real argument in its argument balls, with the rounding of every operation
accounted for by Arb (F. Johansson, "Arb: efficient arbitrary-precision midpoint-radius interval
arithmetic", IEEE Trans. Computers 66(8), 2017).  Evaluated on balls covering a box, the outputs
enclose the function's range on the box (the natural interval extension).

Where Arb's own operation would be needlessly wide on a ball, the enclosure is taken from the
endpoints instead, still with Arb's rounding: integer powers and squares (``[-1, 1]^2`` is
``[0, 1]``, not the ``[-1, 1]`` of ``x * x``), ``|x|``, ``sign`` and the comparisons (an undecided
comparison is the ball ``[0, 1]``).

Width.  A product of balls ``(m1 +- r1)(m2 +- r2) = m1 m2 +- (|m1| r2 + |m2| r1 + r1 r2)`` is wider than
the interval product by up to ``2 r1 r2`` (up to half its width when a factor contains zero): a
second-order excess, negligible on the small boxes a search ends with, kept because the product is
the commonest operation (taking it from the endpoints made the PUMA 560 benchmark four times
slower).  Arb keeps a ball's radius to 30 bits, so the ball of an interval is wider than it by about
1e-9 of its width, and the operations carry that on: an enclosure is tight to about 1e-9 relative
of its width, not to the last bit (which is why :mod:`designkit.bounds.search` bisects to a
tolerance, never to the rounding).

Domain.  ``sqrt`` and a non-integer power are evaluated on the non-negative part of their
argument, ``log`` and ``acos``/``asin`` as Arb defines them (an argument ball leaving the domain
gives an infinite or NaN enclosure, never a wrong finite one): the enclosure is of the values the
expression takes where it is defined.  A division by a ball containing zero is unbounded.

Operations outside :data:`UNARY`, :data:`BINARY` and the special cases below (calls of other
functions, ``fmod``, ``remainder``, ...) are refused with :class:`~designkit.errors.SpecError`
naming the operation.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import casadi as ca

from designkit.errors import SpecError

__all__ = ["Tape", "compile_tape", "evaluate", "lower_float", "point_ball", "span_ball", "upper_float"]


def _arb() -> Any:
    from flint import arb

    return arb


def span_ball(lo: float, hi: float) -> Any:
    """The Arb ball covering the interval ``[lo, hi]`` (its radius is rounded up)."""
    arb = _arb()
    return arb(lo) if lo == hi else arb(lo).union(arb(hi))


def point_ball(x: float) -> Any:
    """The exact ball ``[x, x]``."""
    return _arb()(float(x))


def lower_float(b: Any) -> float:
    """A float ``<= every point of`` the ball ``b`` (``-inf`` for an unbounded or NaN ball)."""
    arb = _arb()
    if not b.is_finite():
        return -math.inf
    v = float(b.mid() - b.rad())
    while not arb(v) <= b:
        v = math.nextafter(v, -math.inf)
    return v


def upper_float(b: Any) -> float:
    """A float ``>= every point of`` the ball ``b`` (``inf`` for an unbounded or NaN ball)."""
    arb = _arb()
    if not b.is_finite():
        return math.inf
    v = float(b.mid() + b.rad())
    while not arb(v) >= b:
        v = math.nextafter(v, math.inf)
    return v


# ----------------------------------------------------------------------------- operations on balls


def _endpoints(x: Any) -> tuple[Any, Any]:
    return x.lower(), x.upper()


def _int_power(x: Any, n: int) -> Any:
    """``x**n`` for an integer ``n`` from the endpoints (monotone pieces)."""
    arb = _arb()
    if n == 0:
        return arb(1)
    if n < 0:
        return 1 / _int_power(x, -n)
    if not x.is_finite():
        return arb("nan")
    lo, hi = _endpoints(x)
    if n % 2 == 1:
        return (lo ** n).union(hi ** n)
    if lo >= 0:
        return (lo ** n).union(hi ** n)
    if hi <= 0:
        return (hi ** n).union(lo ** n)
    return arb(0).union(x.abs_upper() ** n)


def _pow(x: Any, y: Any) -> Any:
    if y.is_exact() and y.is_integer() and abs(float(y)) < 2 ** 31:
        return _int_power(x, int(float(y)))
    return x.nonnegative_part() ** y


def _abs(x: Any) -> Any:
    return x.abs_lower().union(x.abs_upper())


def _sign(x: Any) -> Any:
    arb = _arb()
    if x > 0:
        return arb(1)
    if x < 0:
        return arb(-1)
    if x.is_zero():
        return arb(0)
    lo = arb(-1) if not x >= 0 else arb(0)
    hi = arb(1) if not x <= 0 else arb(0)
    return lo.union(hi)


def _truth(decided_true: bool, decided_false: bool) -> Any:
    arb = _arb()
    if decided_true:
        return arb(1)
    if decided_false:
        return arb(0)
    return arb(0).union(arb(1))


def _if_else_zero(c: Any, x: Any) -> Any:
    if c.is_zero():
        return _arb()(0)
    if not c.contains(0):
        return x
    return x.union(_arb()(0))


UNARY: dict[int, Callable[[Any], Any]] = {
    ca.OP_NEG: operator.neg, ca.OP_ASSIGN: lambda x: x, ca.OP_TWICE: lambda x: 2 * x, ca.OP_INV: lambda x: 1 / x,
    ca.OP_SQ: lambda x: _int_power(x, 2), ca.OP_SQRT: lambda x: x.nonnegative_part().sqrt(),
    ca.OP_SIN: lambda x: x.sin(), ca.OP_COS: lambda x: x.cos(), ca.OP_TAN: lambda x: x.tan(),
    ca.OP_EXP: lambda x: x.exp(), ca.OP_LOG: lambda x: x.log(), ca.OP_FABS: _abs, ca.OP_SIGN: _sign,
    ca.OP_TANH: lambda x: x.tanh(), ca.OP_SINH: lambda x: x.sinh(), ca.OP_COSH: lambda x: x.cosh(),
    ca.OP_ATAN: lambda x: x.atan(), ca.OP_ASIN: lambda x: x.asin(), ca.OP_ACOS: lambda x: x.acos(),
    ca.OP_ASINH: lambda x: x.asinh(), ca.OP_ACOSH: lambda x: x.acosh(), ca.OP_ATANH: lambda x: x.atanh(),
    ca.OP_ERF: lambda x: x.erf(), ca.OP_FLOOR: lambda x: x.floor(), ca.OP_CEIL: lambda x: x.ceil(),
    ca.OP_NOT: lambda x: _truth(x.is_zero(), not x.contains(0)),
    ca.OP_LOG1P: lambda x: x.log1p(), ca.OP_EXPM1: lambda x: x.expm1(),
}
"""CasADi unary operation code -> its enclosure on a ball."""

BINARY: dict[int, Callable[[Any, Any], Any]] = {
    ca.OP_ADD: operator.add, ca.OP_SUB: operator.sub, ca.OP_MUL: operator.mul, ca.OP_DIV: operator.truediv,
    ca.OP_POW: _pow, ca.OP_CONSTPOW: _pow,
    ca.OP_FMIN: lambda x, y: x.min(y), ca.OP_FMAX: lambda x, y: x.max(y),
    ca.OP_ATAN2: lambda y, x: _arb().atan2(y, x),
    ca.OP_HYPOT: lambda x, y: (_int_power(x, 2) + _int_power(y, 2)).sqrt(),
    ca.OP_IF_ELSE_ZERO: _if_else_zero,
    ca.OP_LT: lambda x, y: _truth(bool(x < y), bool(x >= y)),
    ca.OP_LE: lambda x, y: _truth(bool(x <= y), bool(x > y)),
    ca.OP_EQ: lambda x, y: _truth(x.is_exact() and y.is_exact() and bool(x == y), not x.overlaps(y)),
    ca.OP_NE: lambda x, y: _truth(not x.overlaps(y), x.is_exact() and y.is_exact() and bool(x == y)),
    ca.OP_AND: lambda x, y: _truth(not x.contains(0) and not y.contains(0), x.is_zero() or y.is_zero()),
    ca.OP_OR: lambda x, y: _truth(not x.contains(0) or not y.contains(0), x.is_zero() and y.is_zero()),
}
"""CasADi binary operation code -> its enclosure on two balls."""

_OP_NAMES = {getattr(ca, n): n.removeprefix("OP_").lower() for n in dir(ca) if n.startswith("OP_")}


# ----------------------------------------------------------------------------- the tape


_INLINE_BINARY = {ca.OP_ADD: "{a} + {b}", ca.OP_SUB: "{a} - {b}", ca.OP_MUL: "{a} * {b}", ca.OP_DIV: "{a} / {b}"}
_INLINE_UNARY = {ca.OP_NEG: "-{a}", ca.OP_ASSIGN: "{a}", ca.OP_SIN: "{a}.sin()", ca.OP_COS: "{a}.cos()",
                 ca.OP_EXP: "{a}.exp()", ca.OP_TWICE: "2 * {a}"}


@dataclass(frozen=True)
class Tape:
    """A function's straight-line program, as generated Python over Arb balls.

    Parameters
    ----------
    name : str
        The CasADi function's name.
    n_inputs : int
        Number of scalar inputs (the function's inputs' nonzeros, concatenated in order).
    n_outputs : int
        Number of scalar outputs (the first output's nonzeros).
    n_instructions : int
        CasADi instructions (operations, inputs, constants and outputs).
    run : callable
        ``run(x) -> list``: the output balls for the input balls ``x`` (one Python statement per
        instruction, generated once: no interpretation loop).
    """

    name: str
    n_inputs: int
    n_outputs: int
    n_instructions: int
    run: Callable[[Sequence[Any]], list[Any]]


def compile_tape(f: ca.Function) -> Tape:
    """The :class:`Tape` of the first output of ``f`` (an MX function is expanded to SX first).

    Raises
    ------
    SpecError
        ``function``: an operation this module cannot enclose (named), or a function that cannot be
        expanded to SX.
    """
    if not f.is_a("SXFunction"):
        try:
            f = f.expand()
        except RuntimeError as exc:
            raise SpecError("function", f"{f.name()} cannot be expanded to an SX function: {exc}") from None
    offsets = [0]
    for i in range(f.n_in()):
        offsets.append(offsets[-1] + f.nnz_in(i))
    arb = _arb()
    constants: list[Any] = []
    functions: list[Callable[..., Any]] = []
    lines = ["def run(x):"]
    outputs = ["Z"] * f.nnz_out(0)
    for k in range(f.n_instructions()):
        op = f.instruction_id(k)
        ins, outs = f.instruction_input(k), f.instruction_output(k)
        if op == ca.OP_INPUT:
            lines.append(f"    w{outs[0]} = x[{offsets[ins[0]] + ins[1]}]")
        elif op == ca.OP_CONST:
            constants.append(arb(float(f.instruction_constant(k))))
            lines.append(f"    w{outs[0]} = C[{len(constants) - 1}]")
        elif op == ca.OP_OUTPUT:
            if outs[0] == 0:
                outputs[outs[1]] = f"o{outs[1]}"
                lines.append(f"    o{outs[1]} = w{ins[0]}")
        elif op in _INLINE_UNARY:
            lines.append(f"    w{outs[0]} = " + _INLINE_UNARY[op].format(a=f"w{ins[0]}"))
        elif op in _INLINE_BINARY:
            lines.append(f"    w{outs[0]} = " + _INLINE_BINARY[op].format(a=f"w{ins[0]}", b=f"w{ins[1]}"))
        elif op in UNARY:
            functions.append(UNARY[op])
            lines.append(f"    w{outs[0]} = F[{len(functions) - 1}](w{ins[0]})")
        elif op in BINARY:
            functions.append(BINARY[op])
            lines.append(f"    w{outs[0]} = F[{len(functions) - 1}](w{ins[0]}, w{ins[1]})")
        else:
            raise SpecError("function", f"{f.name()}: operation {_OP_NAMES.get(op, op)!r} has no ball enclosure "
                            "here (supported: arithmetic, powers, sqrt, exp, log, trigonometric and hyperbolic "
                            "functions and their inverses, abs, sign, min, max, comparisons, if_else)")
    lines.append("    return [" + ", ".join(outputs) + "]")
    namespace: dict[str, Any] = {"C": tuple(constants), "F": tuple(functions), "Z": arb(0)}
    exec(compile("\n".join(lines), f"<ball tape of {f.name()}>", "exec"), namespace)  # noqa: S102 - generated here
    return Tape(f.name(), offsets[-1], f.nnz_out(0), f.n_instructions(), namespace["run"])


def evaluate(tape: Tape, x: Sequence[Any]) -> list[Any]:
    """The tape's outputs (one ball per output nonzero) for the input balls ``x``.

    Outputs the function never writes (structural zeros) are exact zeros.
    """
    if len(x) != tape.n_inputs:
        raise ValueError(f"{tape.name}: {len(x)} input balls for {tape.n_inputs} inputs")
    return tape.run(x)
