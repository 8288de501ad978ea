"""Text summary of a robot model: joints, parameters, operation counts, evaluation cost.

:func:`model_command` is the body of the CLI command ``designkit model ROBOT``;
:func:`model_summary` formats any :class:`~designkit.models.robot.Robot`.
Operation counts are read from the CasADi ``SX`` instruction list
(:func:`operation_counts`); evaluation cost is measured (:func:`evaluation_cost`),
interpreted and as compiled C (:mod:`designkit.models.codegen`).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import casadi
import numpy as np

from designkit.models.codegen import compile_function

__all__ = ["EvaluationCost", "OperationCounts", "evaluation_cost", "model_command", "model_summary",
           "operation_counts"]

_ADD = {casadi.OP_ADD, casadi.OP_SUB, casadi.OP_TWICE}
_MUL = {casadi.OP_MUL, casadi.OP_SQ}
_DIV = {casadi.OP_DIV, casadi.OP_INV}
_TRIG = {casadi.OP_SIN, casadi.OP_COS, casadi.OP_TAN, casadi.OP_ATAN2, casadi.OP_ASIN, casadi.OP_ACOS,
         casadi.OP_ATAN}
_MOVE = {casadi.OP_INPUT, casadi.OP_OUTPUT, casadi.OP_CONST, casadi.OP_ASSIGN, casadi.OP_PARAMETER}

SUMMARY_FUNCTIONS: tuple[str, ...] = (
    "fkine", "jacobian", "mass_matrix", "coriolis_matrix", "gravity_torque", "inverse_dynamics",
    "forward_dynamics", "regressor",
)
"""Functions whose operation counts :func:`model_summary` lists."""


@dataclass(frozen=True)
class OperationCounts:
    """Operations of an ``SX`` Function, from its instruction list.

    Parameters
    ----------
    instructions : int
        ``Function.n_instructions()``: every instruction, inputs, outputs and constants included.
    multiplications : int
        ``*`` and squares.
    additions : int
        ``+``, ``-`` and doublings (negations excluded).
    divisions : int
        ``/`` and reciprocals.
    trigonometric : int
        ``sin``, ``cos`` and other trigonometric functions.
    other : int
        Remaining arithmetic (negation, sign, sqrt, ...).
    """

    instructions: int
    multiplications: int
    additions: int
    divisions: int
    trigonometric: int
    other: int


def operation_counts(f: casadi.Function) -> OperationCounts:
    """Count the operations of a CasADi Function (MX Functions are expanded to SX first).

    Examples
    --------
    >>> x = casadi.SX.sym("x", 2)
    >>> operation_counts(casadi.Function("f", [x], [x[0] * x[1] + casadi.sin(x[0])])).multiplications
    1
    """
    sx = f if f.is_a("SXFunction") else f.expand()
    ops = [sx.instruction_id(k) for k in range(sx.n_instructions())]
    counted = _ADD | _MUL | _DIV | _TRIG | _MOVE
    return OperationCounts(
        instructions=len(ops),
        multiplications=sum(op in _MUL for op in ops),
        additions=sum(op in _ADD for op in ops),
        divisions=sum(op in _DIV for op in ops),
        trigonometric=sum(op in _TRIG for op in ops),
        other=sum(op not in counted for op in ops),
    )


@dataclass(frozen=True)
class EvaluationCost:
    """Measured evaluation cost of a Function (microseconds).

    Parameters
    ----------
    single_us : float
        One call from Python (``Function.call``), best of several repeats, Python overhead included.
    batched_us : float
        Per evaluation in one mapped (serial) call over ``batch`` states.
    batch : int
        Number of states in the mapped call.
    compiled : bool
        True when the timed Function ran generated C.
    """

    single_us: float
    batched_us: float
    batch: int
    compiled: bool


def evaluation_cost(f: casadi.Function, *, batch: int = 10_000, repeats: int = 5, seed: int = 0,
                    compiled: bool = False) -> EvaluationCost:
    """Time one call and a batched call of ``f`` on random inputs.

    Parameters
    ----------
    f : casadi.Function
        Function with dense column-vector inputs.
    batch : int
        States in the mapped call.
    repeats : int
        Repeats; the best time is kept.
    seed : int
        Seed of the random inputs.
    compiled : bool
        Recorded in the result (the caller says whether ``f`` is compiled code).
    """
    rng = np.random.default_rng(seed)
    single_args = [casadi.DM(rng.uniform(-1, 1, (f.size1_in(i), 1))) for i in range(f.n_in())]
    batch_args = [casadi.DM(rng.uniform(-1, 1, (f.size1_in(i), batch))) for i in range(f.n_in())]
    best_single = math.inf
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(100):
            f.call(single_args)
        best_single = min(best_single, (time.perf_counter() - start) / 100)
    mapped = f.map(batch)
    best_batch = math.inf
    for _ in range(repeats):
        start = time.perf_counter()
        mapped.call(batch_args)
        best_batch = min(best_batch, (time.perf_counter() - start) / batch)
    return EvaluationCost(best_single * 1e6, best_batch * 1e6, batch, compiled)


def _table(header: list[str], rows: list[list[str]]) -> list[str]:
    widths = [max(len(str(c)) for c in col) for col in zip(header, *rows, strict=True)]
    line = "  ".join(h.ljust(w) for h, w in zip(header, widths, strict=True))
    out = [line, "  ".join("-" * w for w in widths)]
    out += ["  ".join(_justify(str(c), w) for c, w in zip(row, widths, strict=True)) for row in rows]
    return out


def _justify(text: str, width: int) -> str:
    """Numbers to the right, words to the left."""
    try:
        float(text)
    except ValueError:
        return text.ljust(width)
    return text.rjust(width)


def _num(x: object) -> str:
    try:
        return f"{float(x):.6g}"  # type: ignore[arg-type]
    except (TypeError, ValueError, RuntimeError):
        return str(x)


def model_summary(robot: object, *, timing: bool = True, compiled: bool = True, base: bool = True) -> str:
    """Multi-line text summary of a robot model.

    Parameters
    ----------
    robot : Robot
        The model.
    timing : bool
        Measure evaluation cost of ``inverse_dynamics`` and ``mass_matrix``.
    compiled : bool
        Also time the compiled C versions (compiled once, cached).
    base : bool
        Compute the number of base inertial parameters (:mod:`designkit.models.base_parameters`).

    Returns
    -------
    str
        Joints table, parameter table, operation counts and evaluation cost.
    """
    d = robot.description  # type: ignore[attr-defined]
    gravity = ", ".join(_num(g) for g in d.gravity)
    lines = [f"{d.name}: {d.n} joints, {d.convention} DH, gravity ({gravity}) m/s^2"]
    if d.source:
        lines.append(f"source: {d.source}")
    lines += ["", "Joints (m, rad)"]
    rows = []
    for i, link in enumerate(d.links, start=1):
        lim = "-" if link.qlim is None else f"[{_num(link.qlim[0])}, {_num(link.qlim[1])}]"
        variable = "theta" if link.joint == "revolute" else "d"
        fixed = _num(link.d) if link.joint == "revolute" else _num(link.theta)
        rows.append([str(i), link.name or "-", link.joint, _num(link.a), _num(link.alpha), fixed,
                     f"{variable}=q+{_num(link.offset)}", lim])
    lines += _table(["#", "name", "type", "a", "alpha", "d|theta", "variable", "limits"], rows)

    names, values = robot.parameter_names, robot.parameters  # type: ignore[attr-defined]
    lines += ["", f"Parameters P ({len(names)}; kg, kg*m, kg*m^2 about the link-frame origin)"]
    per_link = [names[10 * i: 10 * i + 10] for i in range(d.n)]
    header = ["link", *(nm.rstrip("0123456789") for nm in per_link[0])]
    if values is None:
        lines.append("symbolic: " + ", ".join(robot.symbol_names))  # type: ignore[attr-defined]
    else:
        rows = [[str(i + 1), *(_num(v) for v in values[10 * i: 10 * i + 10])] for i in range(d.n)]
        lines += _table(header, rows)
        extra = [f"{nm}={_num(v)}" for nm, v in zip(names[10 * d.n:], values[10 * d.n:], strict=True)]
        if extra:
            lines.append("joint parameters: " + ", ".join(extra))
    if base and values is not None:
        from designkit.models.base_parameters import base_parameters

        bp = base_parameters(robot)
        lines.append(f"base parameters: {bp.count} of {len(names)} (identifiable combinations)")
    if values is not None:
        from designkit.models.physical import check_inertia

        lines += ["", "Physical consistency of the inertial parameters", *check_inertia(d).sentences()]

    lines += ["", "Operation counts (CasADi SX)"]
    rows = []
    for name in SUMMARY_FUNCTIONS:
        c = operation_counts(robot.functions[name])  # type: ignore[attr-defined]
        rows.append([name, str(c.instructions), str(c.multiplications), str(c.additions), str(c.divisions),
                     str(c.trigonometric)])
    lines += _table(["function", "instructions", "mul", "add/sub", "div", "trig"], rows)

    if timing:
        lines += ["", "Evaluation cost (us per evaluation; one Python call / batched over 10000 states)"]
        rows = []
        for name in ("inverse_dynamics", "mass_matrix"):
            f = robot.functions[name]  # type: ignore[attr-defined]
            interp = evaluation_cost(f)
            row = [name, f"{interp.single_us:.2f}", f"{interp.batched_us:.3f}"]
            if compiled:
                cf = compile_function(f)
                if cf.compiled:
                    comp = evaluation_cost(cf.function, compiled=True)
                    row += [f"{comp.single_us:.2f}", f"{comp.batched_us:.3f}"]
                else:
                    row += ["n/a", f"n/a ({cf.reason})"]
            rows.append(row)
        header = ["function", "interp. call", "interp. batch"]
        if compiled:
            header += ["C call", "C batch"]
        lines += _table(header, rows)
    return "\n".join(lines)


def model_command(name: str, *, timing: bool = True) -> str:
    """Output of ``designkit model NAME`` for a built-in robot (:func:`designkit.models.robots.robot`).

    Raises
    ------
    ModelError
        For an unknown robot name.
    """
    from designkit.models.robots import robot

    return model_summary(robot(name), timing=timing)
