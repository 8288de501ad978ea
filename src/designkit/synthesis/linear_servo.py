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

**Solvability.**  Three requested poles fix three coefficients: the placement is exact when ``n + 1 = 3`` (a plant
of order 2) and ``M`` is invertible.  A first-order plant gives a loop of order 2 and one of order 3 or more a loop
of order ``n + 1 > 3`` whose coefficients three gains do not set in general; such plants are refused at
``controller.poles`` with the reason, as is an ``M`` singular to ``1e-10`` (Hadamard's ratio: the plant's zero
cancels what the gains would move).

**Zero.**  ``y/xD = N(s) ((K1 + K3 K4) s + K3) / a_K(s)`` with ``N(s)`` the plant's numerator: the requested zero
``z`` gives ``K4 = -(K3 + K1 z)/(K3 z)`` as on the link (:mod:`designkit.synthesis.pid`); the plant's own zeros are
zeros of the loop too.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from designkit.errors import SpecError
from designkit.synthesis.closed_loop import with_closed_loop
from designkit.synthesis.design import Design, Gain, Gains
from designkit.synthesis.law import Law, integral_law

__all__ = ["characteristic_map", "linear_servo_design", "linear_servo_law", "plant_zeros"]

SINGULAR_TOL = 1e-10
"""Hadamard ratio of the gain map ``M`` below which the placement is refused (a gain would be unbounded)."""


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


def linear_servo_design(plant: Any, poles: Sequence[complex], zero: float | None = None, *, kind: str,
                        notes: tuple[str, ...] = (), extra: dict | None = None) -> Design:
    """The PID servo of a single-input linear ``plant`` of order 2 placing ``poles`` and ``zero`` (module docstring).

    Parameters
    ----------
    plant : LinearPlant
        A ``transfer_function`` or ``state_space`` plant with one input.
    poles : sequence of 3 complex
        Closed-loop poles (1/s), complex ones in conjugate pairs.
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
        At ``controller.poles``: a plant not of order 2, or a placement the three gains cannot make.
    """
    A, B, C, _ = plant.matrices()
    n = A.shape[0]
    if B.shape[1] != 1:
        raise SpecError("plant.B", f"the PID servo drives a single-input plant; this one has {B.shape[1]} inputs")
    if n != 2:
        why = ("the loop has order 2 and two coefficients, not three poles" if n == 1 else
               f"the loop has order {n + 1}: its {n + 1} characteristic coefficients are not set by three gains in "
               "general")
        raise SpecError("controller.poles", f"a PID places three closed-loop poles on a plant of order 2 only; this "
                        f"plant has order {n}, so {why} (a state feedback places one pole per state)")
    b, pos = B[:, 0], plant.positions[0]
    c = np.eye(n)[pos]
    r = c @ A
    a0, M = characteristic_map(A, b, c, r)
    ratio = _hadamard(M)
    if ratio < SINGULAR_TOL:
        raise SpecError("controller.poles", f"the three gains cannot move the loop's three coefficients independently "
                        f"on this plant (gain map singular, Hadamard ratio {ratio:.3g}): a plant zero cancels one of "
                        "them")
    target = np.real(np.poly(np.asarray(poles, complex)))[1:]
    K1, K2, K3 = np.linalg.solve(M, target - a0)
    if K3 == 0:
        raise SpecError("controller.poles", "places a pole at 0 (K3 = 0): the integral would not act")
    K4 = 0.0 if zero is None else -(K3 + K1 * zero) / (K3 * zero)
    u = plant.inputs[0].unit
    y = plant.states[pos].unit
    names = [s.name for s in plant.states]
    rate = " + ".join(f"{v:.4g} {nm}" for v, nm in zip(r, names, strict=True) if v != 0).replace("+ -", "- ") or "0"
    gains = Gains.of([
        Gain("K1", float(K1), f"{u}/({y})", "proportional"),
        Gain("K2", float(K2), f"{u}/({y}/s)", "rate feedback on the output's rate r x = c A x"),
        Gain("K3", float(K3), f"{u}/({y}*s)", "integral"),
        Gain("K4", float(K4), "s", "reference feedforward (places the zero)"),
    ])
    z = zero if zero is not None else -float(K3) / float(K1)
    own = plant_zeros(A, b, c)
    notes_out = list(notes)
    if zero is None:
        notes_out.append(f"No zero given: K4 = 0, so y/xD has its zero at -K3/K1 = {z:.6g} 1/s.")
    if own:
        notes_out.append("The plant's own zeros " + ", ".join(f"{complex(q).real:.4g}" if abs(complex(q).imag) < 1e-12
                                                              else f"{complex(q):.4g}" for q in own)
                         + " 1/s are zeros of y/xD too.")
    formulas = (
        "u = -K1 (y - xD) - K2 r x - K3 ∫(y - xD) dt + K3 K4 xD,  r x = c A x = " + rate,
        "det(sI - A_a + b_a k) = det(sI - A_a) + k adj(sI - A_a) b_a,  k = [K1 c + K2 r, K3]: affine in (K1, K2, K3)",
        "(K1, K2, K3) solve M K = a_requested - a0 (three coefficients, three gains);  K4 = -(K3 + K1 z)/(K3 z)",
    )
    d = Design(kind=kind, plant=plant, gains=gains, poles=tuple(complex(p) for p in poles),
               zeros=(complex(z), *own), reference="step", formulas=formulas, notes=tuple(notes_out),
               extra=dict(extra or {}))
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
