"""Enclosures of one scalar function on one box: the natural extension, tightened by the mean-value form.

For a scalar ``f`` and a box ``X`` with centre ``c``, two enclosures of ``f(X) = {f(x) : x in X}``
are computed from one tape holding ``f`` and its exact gradient (CasADi's ``gradient``, with respect
to the free entries of the box):

* the **natural extension** ``F(X)``: the tape of ``f`` evaluated on the box's balls;
* the **mean-value form** ``f(c) + sum_j G_j(X) (X_j - c_j)``, ``G(X)`` the gradient's natural
  extension: by the mean-value theorem ``f(x) = f(c) + grad f(xi) . (x - c)`` for some ``xi`` on the
  segment ``[c, x]``, which lies in ``X``, so ``grad f(xi)`` is in ``G(X)``.

Their intersection is returned.  The natural extension overestimates by the *dependency effect*
(``x - x`` on ``[0, 1]`` is ``[-1, 1]``), proportional to the box's width; the mean-value form's
overestimate is quadratic in the width, so it wins on small boxes and decides the convergence of the
search (:mod:`designkit.bounds.search`).

The gradient enclosure also gives **monotonicity**: where ``G_j(X) >= 0`` the maximum over ``X`` lies
on the face ``x_j = hi_j`` (and the minimum on ``x_j = lo_j``), so the search reduces the box to
that face before it bisects.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from designkit.bounds.tape import Tape, compile_tape, evaluate, lower_float, point_ball, span_ball, upper_float

__all__ = ["BoxValue", "ScalarProblem", "scalar_expression"]


@dataclass(frozen=True, eq=False)
class BoxValue:
    """``sign f`` bounded above on one box, its gradient's enclosure, and the centre's value.

    Parameters
    ----------
    upper : float
        ``sign f(x) <= upper`` for every ``x`` of the box (rounded outward).
    grad_lower, grad_upper : ndarray
        The enclosure of ``sign df/dx_j`` per free entry ``j``.
    centre : ndarray
        The mean-value form's centre (flat), a point of the box.
    centre_lower : float
        ``sign f(centre) >= centre_lower`` (rigorous).
    centre_value : float
        ``f(centre)`` (the ball's midpoint).
    """

    upper: float
    grad_lower: np.ndarray
    grad_upper: np.ndarray
    centre: np.ndarray
    centre_lower: float
    centre_value: float


class ScalarProblem:
    """One scalar SX expression of a flat input vector, ready for ball evaluation on boxes.

    Parameters
    ----------
    expression : casadi.SX
        Scalar.
    x : casadi.SX
        The purely symbolic input vector (all scalar inputs, in the box's order).
    free : ndarray of int
        Entries of ``x`` that vary over the box; the gradient is taken with respect to them.
    """

    def __init__(self, expression: ca.SX, x: ca.SX, free: np.ndarray) -> None:
        self.free = np.asarray(free, dtype=int)
        grad = ca.gradient(expression, x)[self.free.tolist()] if self.free.size else ca.SX(0, 1)
        self.value_tape: Tape = compile_tape(ca.Function("f", [x], [expression]))
        self.tape: Tape = compile_tape(ca.Function("f_grad", [x], [ca.vertcat(expression, grad)]))
        self.numeric = ca.Function("f_num", [x], [expression, grad])
        from flint import arb

        self._arb = arb

    def point(self, x: np.ndarray) -> tuple[float, float, float]:
        """``(lower, value, upper)`` of ``f`` at the point ``x``: a rigorous ball around the float value."""
        ball = evaluate(self.value_tape, [point_ball(v) for v in x])[0]
        return lower_float(ball), float(ball.mid()), upper_float(ball)

    def value_and_gradient(self, x: np.ndarray) -> tuple[float, np.ndarray]:
        """``f(x)`` and its gradient over the free entries, in floating point (for the local search)."""
        value, grad = self.numeric(x)
        return float(value), np.asarray(grad, dtype=float).reshape(-1)

    def on_box(self, lo: np.ndarray, hi: np.ndarray, sign: float = 1.0) -> BoxValue:
        """An upper bound of ``sign f`` on ``[lo, hi]``: the smaller of the natural and mean-value forms.

        The mean-value form is taken about Baumann's optimal centre for an upper bound: per free entry
        with ``sign df/dx_j`` in ``[a, b]``, ``a < 0 < b``, ``c_j = (b hi_j - a lo_j)/(b - a)`` (the
        centre that minimises ``max(b (hi_j - c_j), a (lo_j - c_j))``); ``hi_j`` when ``a >= 0``,
        ``lo_j`` when ``b <= 0`` (E. Baumann, "Optimal centered forms", BIT 28, 1988).
        """
        arb = self._arb
        balls = [span_ball(a, b) for a, b in zip(lo, hi, strict=True)]
        out = self.tape.run(balls)
        natural, grads = out[0], out[1:]
        if sign < 0:
            natural, grads = -natural, [-g for g in grads]
        g_lo = np.array([lower_float(g) for g in grads])
        g_hi = np.array([upper_float(g) for g in grads])
        centre = 0.5 * (lo + hi)
        for k, j in enumerate(self.free):
            a, b = g_lo[k], g_hi[k]
            if a >= 0:
                centre[j] = hi[j]
            elif b <= 0:
                centre[j] = lo[j]
            elif math.isfinite(a) and math.isfinite(b):
                centre[j] = min(max((b * hi[j] - a * lo[j]) / (b - a), lo[j]), hi[j])
        f_c = self.value_tape.run([arb(v) for v in centre])[0]
        s_c = f_c if sign > 0 else -f_c
        mean_value = s_c
        for k, j in enumerate(self.free):
            if hi[j] == lo[j]:
                continue
            a, b = g_lo[k], g_hi[k]
            if not (math.isfinite(a) and math.isfinite(b)):
                mean_value = arb("inf")
                break
            up, down = arb(hi[j]) - arb(centre[j]), arb(lo[j]) - arb(centre[j])
            terms = [arb(b) * up, arb(a) * down, arb(b) * down, arb(a) * up]
            mean_value = mean_value + max(upper_float(t) for t in terms)
        upper = min(upper_float(natural), upper_float(mean_value))
        if math.isnan(upper):
            upper = math.inf
        return BoxValue(upper, g_lo, g_hi, centre, lower_float(s_c), float(f_c.mid()))

    def __repr__(self) -> str:
        return f"ScalarProblem({self.tape.n_instructions} instructions, {self.free.size} free entries)"


def scalar_expression(function: ca.Function, output: int | str, index: Any) -> tuple[ca.SX, ca.SX, str]:
    """The SX scalar ``function``'s output ``output`` holds at ``index``, the flat input vector and a label.

    ``index``: None for a scalar output, an int (flat, column-major) or ``(row, column)``.
    """
    from designkit.errors import SpecError

    f = function if function.is_a("SXFunction") else function.expand()
    names_out = [f.name_out(i) for i in range(f.n_out())]
    k = names_out.index(output) if isinstance(output, str) and output in names_out else output
    if not isinstance(k, int) or not 0 <= k < f.n_out():
        raise SpecError("output", f"{f.name()} has outputs {names_out}, got {output!r}")
    inputs = [ca.SX.sym(f.name_in(i), f.sparsity_in(i)) for i in range(f.n_in())]
    result = f.call(inputs)[k]
    shape = result.shape
    if index is None:
        if result.numel() != 1:
            raise SpecError("index", f"{f.name()}'s output {names_out[k]!r} is {shape[0]}x{shape[1]}: name an entry")
        expr, label = result[0, 0], f"{names_out[k]}"
    else:
        try:
            rc = (int(index[0]), int(index[1])) if isinstance(index, tuple | list) else None
            flat = int(index) if rc is None else None
        except (TypeError, ValueError, IndexError):
            raise SpecError("index", f"must be an entry number or (row, column), got {index!r}") from None
        if rc is not None and not (0 <= rc[0] < shape[0] and 0 <= rc[1] < shape[1]):
            raise SpecError("index", f"({rc[0]}, {rc[1]}) is outside the {shape[0]}x{shape[1]} output")
        if flat is not None and not 0 <= flat < result.numel():
            raise SpecError("index", f"{flat} is outside the output's {result.numel()} entries")
        expr = result[rc] if rc is not None else result[flat]
        label = f"{names_out[k]}[{rc[0]}, {rc[1]}]" if rc is not None else f"{names_out[k]}[{flat}]"
    entries = [e for s in inputs for e in s.nonzeros()]
    x = ca.vertcat(*entries) if entries else ca.SX(0, 1)
    return expr, x, label
