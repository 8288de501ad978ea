"""The PID position servo of any single-input linear plant, placed through the closed-loop characteristic polynomial.

Plant ``x' = A x + b (u + xi)``, position ``y = c x`` (a state of the realisation,
:mod:`designkit.models.linear_plant`).  Law, with the integral ``x_I' = y - xD`` and the output's rate read from the
state as ``r x`` (``r = c A``: ``y' = c A x + c b u``, so ``r x = y'`` at relative degree 2 or more)::

    u = -K1 (y - xD) - K2 r x - K3 x_I + K3 K4 xD

**Characteristic polynomial.**  The loop is the augmented plant ``[x; x_I]`` under the state feedback
``k = [K1 c + K2 r, K3]``.  For one input, ``det(sI - A_a + b_a k) = det(sI - A_a) + k adj(sI - A_a) b_a`` (the
matrix determinant lemma), so the ``n + 1`` coefficients after the leading 1 are *affine* in ``(K1, K2, K3)``:
``a(K) = a0 + M K``, ``M`` (``(n + 1) x 3``) formed with Faddeev's recursion ``adj(sI - A) = sum_k s^(n-1-k) N_k``,
``N_0 = I``, ``N_k = A N_(k-1) + a_k I`` (:func:`characteristic_map`).

**Placement** (:func:`place`).  The requested poles are roots of ``a_K(s)`` exactly when their monic polynomial
``P(s)`` divides ``a_K(s)``: the remainder of ``a_K`` modulo ``P`` (degree below ``deg P``) is affine in the gains, so
the placement is the square linear system "remainder = 0" (real arithmetic; repeated and complex poles alike).

* Order ``n = 2``: a loop of order 3, three poles, three gains; the remainder is ``a_K - P``: coefficient matching,
  every pole placed.
* Order ``n = 1``: a loop of order 2.  ``r x = c A x`` is then a multiple of ``y``, so ``K2`` would only duplicate
  ``K1``: ``K2 = 0`` and ``K1``, ``K3`` place **two** poles (a PI with reference feedforward); three requested
  poles are refused.
* Order ``n >= 3``: a loop of order ``n + 1 > 3`` whose ``n + 1`` coefficients three gains do not set in general.
  The three requested poles are placed exactly (three remainder equations, three gains) and the other ``n - 2``
  are **left** where the quotient ``a_K(s)/P(s)`` puts them: the design lists them, says so, and the generic
  checks (Routh-Hurwitz on the loop, Lyapunov, the time-domain requirements) judge the loop with them.

**Solvability.**  The remainder system is refused at ``controller.poles`` with its reason when its matrix is
singular to :data:`SINGULAR_TOL` (Hadamard's ratio): a requested pole at a plant zero, or a zero cancelling a
plant pole, leaves a gain with nothing to move.  A placed ``K3 = 0`` (a pole at 0) is refused too.

**Zero.**  ``y/xD = N(s) ((K1 + K3 K4) s + K3) / a_K(s)`` with ``N(s)`` the plant's numerator: the requested zero
``z`` gives ``K4 = -(K3 + K1 z)/(K3 z)`` as on the link (:mod:`designkit.synthesis.pid`); the plant's own zeros are
zeros of the loop too.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.errors import SpecError
from designkit.synthesis.closed_loop import with_closed_loop
from designkit.synthesis.design import Design, Gain, Gains
from designkit.synthesis.law import Law, integral_law

__all__ = ["Placement", "characteristic_map", "linear_servo_design", "linear_servo_law", "pid_poles", "pid_spec_rule",
           "place", "plant_zeros"]

SINGULAR_TOL = 1e-10
"""Hadamard ratio of the placement's linear system below which it is refused (a gain would be unbounded)."""


def characteristic_map(A: np.ndarray, b: np.ndarray, c: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``a0`` and ``M`` with the loop's characteristic coefficients (after the leading 1) ``a0 + M [K1, K2, K3]``.

    Parameters
    ----------
    A : numpy.ndarray
        ``n x n`` plant matrix (1/s).
    b : numpy.ndarray
        Input column (length ``n``).
    c, r : numpy.ndarray
        The position row and the rate row (length ``n``).

    Returns
    -------
    a0 : numpy.ndarray
        ``n + 1`` coefficients of ``s det(sI - A)`` after its leading 1.
    M : numpy.ndarray
        ``(n + 1) x 3``: the coefficients' sensitivities to ``K1``, ``K2``, ``K3``.
    """
    A = np.asarray(A, float)
    n = A.shape[0]
    Aa = np.zeros((n + 1, n + 1))
    Aa[:n, :n] = A
    Aa[n, :n] = np.asarray(c, float)
    ba = np.concatenate([np.asarray(b, float).reshape(n), [0.0]])
    N = np.eye(n + 1)
    terms = [N @ ba]
    coeffs = [1.0]
    for k in range(1, n + 1):  # Faddeev-LeVerrier: a_k = -tr(A N_(k-1))/k, N_k = A N_(k-1) + a_k I
        AN = Aa @ N
        a_k = -np.trace(AN) / k
        coeffs.append(a_k)
        N = AN + a_k * np.eye(n + 1)
        terms.append(N @ ba)
    coeffs.append(-np.trace(Aa @ N) / (n + 1))
    adj_b = np.array(terms)  # row k: the coefficient of s^(n - k) in adj(sI - A_a) b_a
    rows = [np.concatenate([c, [0.0]]), np.concatenate([r, [0.0]]), np.eye(n + 1)[n]]
    M = np.column_stack([adj_b @ k for k in rows])  # coefficient of s^(n - k), k = 0..n
    return np.array(coeffs[1:]), M


def plant_zeros(A: np.ndarray, b: np.ndarray, c: np.ndarray) -> tuple[complex, ...]:
    """The finite zeros (1/s) of ``c (sI - A)^-1 b``: the finite generalised eigenvalues of the Rosenbrock pencil
    ``[[A, b], [c, 0]] - s [[I, 0], [0, 0]]`` (QZ), as many as ``n`` less the relative degree ``r`` (the first
    ``k`` with ``c A^(k-1) b`` nonzero to ``1e-12`` of ``|c| |A|^(k-1) |b|``), the smallest in modulus."""
    from scipy.linalg import eigvals

    A = np.asarray(A, float)
    n = A.shape[0]
    b, c = np.asarray(b, float).reshape(n), np.asarray(c, float).reshape(n)
    r, v, scale = None, b.copy(), float(np.linalg.norm(b) * np.linalg.norm(c))
    for k in range(1, n + 1):
        if abs(float(c @ v)) > 1e-12 * max(scale, 1e-300):
            r = k
            break
        v, scale = A @ v, scale * max(float(np.linalg.norm(A, 2)), 1e-300)
    if r is None or r == n:
        return ()
    L = np.block([[A, b[:, None]], [c[None, :], np.zeros((1, 1))]])
    M = np.zeros_like(L)
    M[:n, :n] = np.eye(n)
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.asarray(eigvals(L, M), dtype=complex)
    z = z[np.isfinite(z)]
    return tuple(complex(q) for q in sorted(z, key=abs)[: n - r])


def _hadamard(M: np.ndarray) -> float:
    norms = np.linalg.norm(M, axis=0)
    return 0.0 if np.any(norms == 0) else float(abs(np.linalg.det(M / norms)))


@dataclass(frozen=True)
class Placement:
    """The PID gains placing requested poles on a linear plant (module docstring, "Placement").

    Attributes
    ----------
    K1, K2, K3 : float
        Proportional, rate and integral gains (the plant's input unit per output unit, per its rate, per its
        integral).
    placed : tuple of complex
        The requested poles (1/s), roots of the loop's characteristic polynomial.
    left : tuple of complex
        The loop's other poles (1/s): the roots of ``a_K(s)/P(s)``; empty on plants of order 1 and 2.
    conditioning : float
        Hadamard's ratio of the remainder system (1: orthogonal columns, 0: singular).
    statement : str
        What was placed and what was left, in words.
    """

    K1: float
    K2: float
    K3: float
    placed: tuple[complex, ...]
    left: tuple[complex, ...]
    conditioning: float
    statement: str

    @property
    def poles(self) -> tuple[complex, ...]:
        """Every pole of the loop (1/s): the placed ones, then the left ones."""
        return (*self.placed, *self.left)


def _remainder(p: np.ndarray, P: np.ndarray) -> np.ndarray:
    """The ``deg P`` coefficients of ``p mod P`` (highest power first, zero-padded)."""
    k = len(P) - 1
    _, rem = np.polydiv(p, P)
    rem = np.atleast_1d(rem)
    return np.concatenate([np.zeros(max(k - len(rem), 0)), rem[-k:]])


def _fmt(poles: Sequence[complex]) -> str:
    return ", ".join(f"{complex(q).real:.4g}" if abs(complex(q).imag) < 1e-12 else f"{complex(q):.4g}"
                     for q in poles)


def place(A: np.ndarray, b: np.ndarray, c: np.ndarray, r: np.ndarray, poles: Sequence[complex]) -> Placement:
    """The gains whose loop has ``poles`` among its roots (module docstring, "Placement" and "Solvability").

    Parameters
    ----------
    A : numpy.ndarray
        ``n x n`` plant matrix (1/s).
    b : numpy.ndarray
        Input column (length ``n``).
    c, r : numpy.ndarray
        The position row and the rate row (length ``n``).
    poles : sequence of complex
        Requested poles (1/s): 2 on a plant of order 1, 3 otherwise; complex ones in conjugate pairs.

    Raises
    ------
    SpecError
        At ``controller.poles``: a pole count the plant's order does not take, or a remainder system singular to
        :data:`SINGULAR_TOL`.
    """
    A = np.asarray(A, float)
    n = A.shape[0]
    free = [0, 2] if n == 1 else [0, 1, 2]
    if len(poles) != len(free):
        why = ("a first-order plant gives a PID loop of order 2 (the rate c A x is a multiple of y there, so K2 would "
               "duplicate K1): give 2 poles" if n == 1 else
               f"three gains place three poles on a plant of order {n}: give 3 poles")
        raise SpecError("controller.poles", f"{why}, got {len(poles)}")
    a0, M = characteristic_map(A, b, c, r)
    full = np.concatenate([[1.0], a0])
    cols = [np.concatenate([[0.0], M[:, j]]) for j in free]
    P = np.real(np.poly(np.asarray(poles, complex)))
    E = np.column_stack([_remainder(m, P) for m in cols])
    f = _remainder(full, P)
    ratio = _hadamard(E)
    if ratio < SINGULAR_TOL:
        raise SpecError("controller.poles", f"the gains cannot place these poles on this plant (the placement's "
                        f"linear system is singular, Hadamard ratio {ratio:.3g}): a plant zero cancels one of them, "
                        "or a requested pole sits on a plant zero")
    sol = np.linalg.solve(E, -f)
    K = np.zeros(3)
    K[free] = sol
    if K[2] == 0:
        raise SpecError("controller.poles", "places a pole at 0 (K3 = 0): the integral would not act")
    aK = full + np.concatenate([[0.0], M @ K])
    quotient = np.atleast_1d(np.polydiv(aK, P)[0])
    left = tuple(complex(q) for q in sorted(np.roots(quotient), key=lambda z: (z.real, z.imag))) if n > 2 else ()
    placed = tuple(complex(p) for p in poles)
    if n == 1:
        statement = (f"A first-order plant: the loop has order 2; K1 and K3 place the 2 requested poles {_fmt(placed)} "
                     "1/s exactly, K2 = 0 (the rate c A x is a multiple of y on this plant).")
    elif n == 2:
        statement = f"Every pole of the loop of order 3 placed: {_fmt(placed)} 1/s (coefficient matching)."
    else:
        unstable = [q for q in left if q.real >= 0]
        statement = (f"The loop has order {n + 1}: three gains place the 3 requested poles {_fmt(placed)} 1/s exactly "
                     f"(the remainder of the characteristic polynomial modulo theirs is 0); the other {n - 2} are left "
                     f"where the quotient puts them: {_fmt(left)} 1/s"
                     + (" -- UNSTABLE: the loop diverges; slow the requested poles or use a state feedback "
                        "(state_regulator), which places one pole per state." if unstable else "."))
    return Placement(float(K[0]), float(K[1]), float(K[2]), placed, left, ratio, statement)


def pid_spec_rule(spec: Any, linear: Sequence[str] = ("transfer_function", "state_space")) -> None:
    """Spec rule of the PID families (read when the spec is loaded): ``controller.poles`` or the requirements
    (:func:`~designkit.synthesis.requirements.poles_or_requirements`), and a pole count the plant takes: 2 on a
    first-order linear plant (its order read from ``den`` or ``A``), 3 on any other.

    Raises
    ------
    ValueError
        ``"controller.poles: ..."`` (the loader turns it into a SpecError with that key path).
    """
    from designkit.synthesis.requirements import poles_or_requirements

    poles_or_requirements(spec)
    poles = spec.controller.poles
    if poles is None:
        return
    plant = spec.plant
    order = (len(plant.den) - 1 if plant.kind == "transfer_function" else len(plant.A) if plant.kind == "state_space"
             else None)
    want = 2 if plant.kind in linear and order == 1 else 3
    if len(poles) != want:
        where = (f"a first-order {plant.kind} plant (its PID loop has order 2)" if want == 2 else
                 f"a {plant.kind} plant" + ("" if plant.kind in linear else
                                            " (2 only on a first-order transfer_function or state_space plant)"))
        raise ValueError(f"controller.poles: must list exactly {want} poles on {where}, got {len(poles)}")


def pid_poles(controller: Any, requirements: Any, plant: Any,
              linear: Sequence[str] = ("transfer_function", "state_space")) -> tuple[tuple[complex, ...],
                                                                                  tuple[str, ...], dict[str, float]]:
    """The poles a PID family places on ``plant``: given, or derived from the requirements
    (:func:`~designkit.synthesis.requirements.poles_from_spec`), the dominant pair alone on a first-order linear
    plant; 2 given poles are refused at ``controller.poles`` on a plant of another kind.

    Returns
    -------
    poles, notes, extra
        As :func:`~designkit.synthesis.requirements.poles_from_spec`.
    """
    from designkit.synthesis.requirements import poles_from_spec

    poles, notes, extra = poles_from_spec(controller, requirements)
    first_order = plant.kind in linear and len(plant.states) == 1
    if controller.poles is None and first_order:
        poles = poles[:2]
        notes = (*notes, "A first-order plant gives a PID loop of order 2: the dominant pair alone is placed.")
    if len(poles) == 2 and plant.kind not in linear:
        raise SpecError("controller.poles", f"must list 3 poles on a {plant.kind} plant (2 only on a first-order "
                        "transfer_function or state_space plant), got 2")
    return poles, notes, extra


def linear_servo_design(plant: Any, poles: Sequence[complex], zero: float | None = None, *, kind: str,
                        notes: tuple[str, ...] = (), extra: dict | None = None) -> Design:
    """The PID servo of a single-input linear ``plant`` placing ``poles`` and ``zero`` (module docstring).

    Parameters
    ----------
    plant : LinearPlant
        A ``transfer_function`` or ``state_space`` plant with one input, of any order.
    poles : sequence of complex
        Closed-loop poles (1/s), complex ones in conjugate pairs: 2 on a first-order plant, else 3.
    zero : float or None
        The zero of ``y/xD`` the gains place (1/s); ``None``: ``K4 = 0``.
    kind : str
        The design's controller kind.
    notes : tuple of str
        Notes to carry.
    extra : dict or None
        Entries generic layers read by name.

    Raises
    ------
    SpecError
        At ``plant.B`` for more than one input; at ``controller.poles`` for a placement the gains cannot make
        (:func:`place`).
    """
    A, B, C, _ = plant.matrices()
    n = A.shape[0]
    if B.shape[1] != 1:
        raise SpecError("plant.B", f"the PID servo drives a single-input plant; this one has {B.shape[1]} inputs")
    b, pos = B[:, 0], plant.positions[0]
    c = np.eye(n)[pos]
    r = c @ A
    pl = place(A, b, c, r, poles)
    K1, K2, K3 = pl.K1, pl.K2, pl.K3
    K4 = 0.0 if zero is None else -(K3 + K1 * zero) / (K3 * zero)
    u = plant.inputs[0].unit
    y = plant.states[pos].unit
    names = [s.name for s in plant.states]
    rate = " + ".join(f"{v:.4g} {nm}" for v, nm in zip(r, names, strict=True) if v != 0).replace("+ -", "- ") or "0"
    gains = Gains.of([
        Gain("K1", float(K1), f"{u}/({y})", "proportional"),
        Gain("K2", float(K2), f"{u}/({y}/s)", "rate feedback on the output's rate r x = c A x"
             + (" (0: a multiple of y on a first-order plant)" if n == 1 else "")),
        Gain("K3", float(K3), f"{u}/({y}*s)", "integral"),
        Gain("K4", float(K4), "s", "reference feedforward (places the zero)"),
    ])
    z = zero if zero is not None else -float(K3) / float(K1)
    own = plant_zeros(A, b, c)
    notes_out = [*notes, pl.statement]
    if zero is None:
        notes_out.append(f"No zero given: K4 = 0, so y/xD has its zero at -K3/K1 = {z:.6g} 1/s.")
    if own:
        notes_out.append(f"The plant's own zeros {_fmt(own)} 1/s are zeros of y/xD too.")
    solve = ("(K1, K2, K3) solve M K = a_requested - a0 (three coefficients, three gains)" if n == 2 else
             "(K1, K3) solve M K = a_requested - a0 (two coefficients), K2 = 0" if n == 1 else
             "(K1, K2, K3) solve rem(a0 + M K, P) = 0, P(s) = Π(s - p_i) over the 3 requested poles; the other "
             f"{n - 2} poles are the roots of (a0 + M K)/P")
    formulas = (
        "u = -K1 (y - xD) - K2 r x - K3 ∫(y - xD) dt + K3 K4 xD,  r x = c A x = " + rate,
        "det(sI - A_a + b_a k) = det(sI - A_a) + k adj(sI - A_a) b_a,  k = [K1 c + K2 r, K3]: affine in (K1, K2, K3)",
        solve + ";  K4 = -(K3 + K1 z)/(K3 z)",
    )
    d = Design(kind=kind, plant=plant, gains=gains, poles=pl.poles, zeros=(complex(z), *own), reference="step",
               formulas=formulas, notes=tuple(notes_out), extra=dict(extra or {}))
    return with_closed_loop(d, linear_servo_law(d), [0.0, 0.0, 0.0], field="controller.poles")


def linear_servo_law(design: Design, anti_windup: Any = None) -> Law:
    """``u = -K1 (y - xD) - K2 c A x - K3 x_I + K3 K4 xD``, ``x_I' = y - xD`` (the plant's input unit).

    Parameters
    ----------
    design : Design
        Its gains ``K1``..``K4`` and its linear plant (the rate row ``c A`` is read from it).
    anti_windup : AntiWindup or None
        The spec's ``simulation.anti_windup``.
    """
    import casadi as ca

    K1, K2, K3, K4 = (float(design.gains[k]) for k in ("K1", "K2", "K3", "K4"))
    r = ca.DM(np.asarray(design.plant.rate_row(), float))
    return integral_law(
        design.kind, design.plant, [K3], anti_windup,
        lambda y, xc, ref, e: -K1 * e[0] - K2 * ca.dot(r, y) - K3 * xc[0] + K3 * K4 * ref[0],
        {"gains": design.gains.to_json()},
    )
