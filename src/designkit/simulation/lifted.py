"""A CasADi SX function with its numeric constants lifted into an input: one compiled library for a structure.

A study runs a family's law with other gains, a link of another mass: the loop's functions have the same operations
and differ only in the numbers written into them.  Compiled as they are, each variant is another C source, hence
another compilation (about 0.2 s for a link's loop) and another cached library.  :func:`lift_constants` rewrites a
function ``f(x...)`` as ``f_lifted(x..., G)`` whose every constant is read from ``G`` (the values returned beside it),
operation for operation: the same instructions in the same order, so the C code is that of the structure alone and
gives the same numbers (a constant read from memory and a literal are the same double; the library is compiled
without reassociation or fused multiply-add).  The exponent of a power stays written in (a compiler may turn
``pow(x, 2.0)`` into ``x * x``).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

__all__ = ["lift_constants"]

_KEEP = {ca.OP_POW, ca.OP_CONSTPOW}
"""Operations whose second operand stays a literal when it is a constant (an exponent)."""


def lift_constants(functions: tuple[ca.Function, ...], name: str = "G") -> tuple[tuple[ca.Function, ...], np.ndarray]:
    """The SX ``functions`` with one more input ``name`` holding their constants, and those constants.

    Parameters
    ----------
    functions : tuple of casadi.Function
        SX functions (``is_a("SXFunction")``) without free variables or calls.
    name : str
        Name of the added last input (a column of every function's constants, in order).

    Returns
    -------
    (tuple of casadi.Function, ndarray)
        The rewritten functions (same names, inputs and outputs, plus ``name``) and the constants' values, such that
        ``lifted(*args, G) == f(*args)`` for every ``f``.

    Raises
    ------
    ValueError
        A function that is not an SX function, or holds an instruction this rewriting does not know (a call, a free
        parameter).
    """
    plans = [_plan(f) for f in functions]
    values = np.array([v for _, consts in plans for v in consts], dtype=float)
    g = ca.SX.sym(name, values.size)
    out, start = [], 0
    for f, (program, consts) in zip(functions, plans, strict=True):
        out.append(_replay(f, program, g, start, name))
        start += len(consts)
    return tuple(out), values


def _plan(f: ca.Function) -> tuple[list[tuple[int, list[int], list[int], float | None]], list[float]]:
    """``f``'s instructions and the constants to lift, in order."""
    if not f.is_a("SXFunction"):
        raise ValueError(f"{f.name()} is not an SX function")
    if f.has_free():
        raise ValueError(f"{f.name()} has free variables")
    program, consts = [], []
    kept: set[int] = set()  # instructions whose constant stays written in
    last_const: dict[int, int] = {}  # work index -> the instruction that last wrote a constant there
    rows = [(f.instruction_id(k), list(f.instruction_input(k)), list(f.instruction_output(k))) for k in
            range(f.n_instructions())]
    for k, (op, ins, outs) in enumerate(rows):
        if op in _KEEP and len(ins) == 2 and ins[1] in last_const:
            kept.add(last_const[ins[1]])
        if op == ca.OP_CONST:
            last_const[outs[0]] = k
        elif op != ca.OP_OUTPUT:
            for w in outs:
                last_const.pop(w, None)
    for k, (op, ins, outs) in enumerate(rows):
        if op in (ca.OP_CALL, ca.OP_PARAMETER):
            raise ValueError(f"{f.name()}: instruction {k} ({op}) cannot be rewritten")
        value = None
        if op == ca.OP_CONST:
            value = float(f.instruction_constant(k))
            if k not in kept:
                consts.append(value)
                value = None  # read from G
        program.append((op, ins, outs, value))
    return program, consts


def _replay(f: ca.Function, program: list, g: ca.SX, start: int, name: str) -> ca.Function:
    """``f`` rebuilt from ``program``, its lifted constants read from ``g[start:]``, ``g`` its last input."""
    inputs = [ca.SX.sym(f.name_in(i), f.sparsity_in(i)) for i in range(f.n_in())]
    outputs = [[ca.SX(0)] * f.sparsity_out(i).nnz() for i in range(f.n_out())]
    work: dict[int, ca.SX] = {}
    j = start
    for op, ins, outs, value in program:
        if op == ca.OP_CONST:
            if value is None:
                work[outs[0]] = g[j]
                j += 1
            else:
                work[outs[0]] = ca.SX(value)
        elif op == ca.OP_INPUT:
            work[outs[0]] = inputs[ins[0]].nz[ins[1]]
        elif op == ca.OP_OUTPUT:
            outputs[outs[0]][outs[1]] = work[ins[0]]
        elif len(ins) == 1:
            work[outs[0]] = ca.SX.unary(op, work[ins[0]])
        else:
            work[outs[0]] = ca.SX.binary(op, work[ins[0]], work[ins[1]])
    results = [ca.SX(f.sparsity_out(i), ca.vertcat(*outputs[i]) if outputs[i] else ca.SX(0, 1))
               for i in range(f.n_out())]
    return ca.Function(f.name(), [*inputs, g], results, [*f.name_in(), name], f.name_out())
