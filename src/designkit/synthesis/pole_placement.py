"""Pole placement: Ackermann's formula for a single-input ``(A, B)``, and the gains of a second-order error.

**Ackermann's formula.**  With ``W = [B, AB, ..., A^(n-1) B]`` invertible (controllable,
:mod:`~designkit.synthesis.state_space`), ``e = [0 ... 0 1] W^-1`` and ``P(s) = prod (s - p_j)`` the monic
polynomial of the ``n`` requested poles, ``K = e P(A)`` gives ``det(sI - (A - B K)) = P(s)``.  *Proof*
(Cayley-Hamilton in the controllable canonical basis): ``e A^k B = 0`` for ``k < n - 1`` and ``e A^(n-1) B = 1``, so
``T = [e; e A; ...; e A^(n-1)]`` is invertible and puts ``(A, B)`` in companion form with ``B -> [0 ... 0 1]^T``;
there ``K T^-1`` is the row of differences between ``P``'s and ``A``'s characteristic coefficients, which is what
``e P(A) T^-1`` reads.  The formula handles repeated poles (``scipy.signal.place_poles`` does not for a single
input); the tests pin ``K`` against python-control's ``acker`` and ``place``.

The same row ``e P(A)`` with the ``n - 1`` poles of a sliding motion is a sliding surface ``c`` (``c B = 1``):
:func:`ackermann_row` computes it for any number of poles up to ``n``.

**Several inputs.**  For ``m > 1`` inputs :func:`place` uses the robust method of Kautsky, Nichols and Van Dooren
(``scipy.signal.place_poles``, Tits-Yang variant): among the many ``K`` placing the poles it picks one whose closed-loop
eigenvectors are well conditioned; a pole may be repeated at most ``rank B`` times.

**Second-order error.**  A model-based law that makes each coordinate's error obey ``e'' + K2 e' + K1 e = 0``
places the poles ``p1, p2`` (a real pair or a conjugate pair) with ``K1 = p1 p2`` and ``K2 = -(p1 + p2)``
(:func:`error_gains`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from designkit.synthesis.state_space import controllability_matrix

__all__ = ["ackermann", "ackermann_row", "error_gains", "observer_gain", "place"]


def ackermann_row(A: np.ndarray, B: np.ndarray, poles: Sequence[complex]) -> np.ndarray:
    """``e P(A)``: ``e`` the last row of ``W^-1``, ``P`` the monic polynomial of ``poles`` (module docstring).

    Parameters
    ----------
    A : numpy.ndarray
        ``n x n`` (state units per state unit per second).
    B : numpy.ndarray
        ``n`` or ``n x 1`` (state units per second per input unit); ``(A, B)`` controllable.
    poles : sequence of complex
        At most ``n`` poles (1/s), complex ones in conjugate pairs.

    Returns
    -------
    numpy.ndarray
        The row (length ``n``): with ``n`` poles the state feedback ``K`` (input units per state unit), with
        ``n - 1`` a sliding surface normalised to ``c B = 1``.
    """
    A = np.asarray(A, float)
    n = A.shape[0]
    W = controllability_matrix(A, B)
    e = np.linalg.solve(W.T, np.eye(n)[n - 1])
    P = np.zeros((n, n))
    for k in np.poly(np.asarray(poles, complex)).real:  # Horner: P(A) = (...(A + a1 I) A + a2 I ...) + an I
        P = P @ A + k * np.eye(n)
    return e @ P


def ackermann(A: np.ndarray, B: np.ndarray, poles: Sequence[complex]) -> np.ndarray:
    """``K`` (length ``n``) with ``eig(A - B K) = poles`` (module docstring).

    Parameters
    ----------
    A : numpy.ndarray
        ``n x n`` (state units per state unit per second).
    B : numpy.ndarray
        ``n x 1`` (state units per second per input unit).
    poles : sequence of complex
        ``n`` poles (1/s), complex ones in conjugate pairs.

    Returns
    -------
    numpy.ndarray
        ``K`` (input units per state unit).

    Raises
    ------
    ValueError
        Not ``n`` poles.

    Examples
    --------
    >>> import numpy as np
    >>> A, B = np.array([[0.0, 1.0], [0.0, -2.0]]), np.array([[0.0], [4.0]])
    >>> K = ackermann(A, B, [-3.0, -5.0])
    >>> [round(float(k), 9) for k in K]
    [3.75, 1.5]
    >>> sorted(round(float(p.real), 9) for p in np.linalg.eigvals(A - B @ K[None, :]))
    [-5.0, -3.0]
    """
    n = np.asarray(A).shape[0]
    if len(poles) != n:
        raise ValueError(f"needs {n} poles for {n} states, got {len(poles)}")
    return ackermann_row(A, B, poles)


def error_gains(pairs: Sequence[tuple[complex, complex]]) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """``K1 = p1 p2`` (1/s^2) and ``K2 = -(p1 + p2)`` (1/s) of each pair of error poles (1/s).

    Parameters
    ----------
    pairs : sequence of (complex, complex)
        One pair per coordinate, real or conjugate.

    Returns
    -------
    tuple
        ``(K1, K2)``, each one value per coordinate.

    Examples
    --------
    >>> error_gains([(-10, -10), (-2 + 1j, -2 - 1j)])
    ((100.0, 5.0), (20.0, 4.0))
    """
    K1 = tuple(float((p1 * p2).real) for p1, p2 in pairs)
    K2 = tuple(float((-(p1 + p2)).real) for p1, p2 in pairs)
    return K1, K2


def place(A: np.ndarray, B: np.ndarray, poles: Sequence[complex]) -> np.ndarray:
    """``K`` (``m x n``) with ``eig(A - B K) = poles``: Ackermann's formula for one input, SciPy's robust placement
    (module docstring) for several.

    Parameters
    ----------
    A : numpy.ndarray
        ``n x n`` (state units per state unit per second).
    B : numpy.ndarray
        ``n x m`` (state units per second per input unit); ``(A, B)`` controllable.
    poles : sequence of complex
        ``n`` poles (1/s), complex ones in conjugate pairs.

    Returns
    -------
    numpy.ndarray
        ``K``, ``m x n`` (input units per state unit).

    Raises
    ------
    ValueError
        Not ``n`` poles, or (several inputs) a pole repeated more than ``rank B`` times.

    Examples
    --------
    >>> A = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [-1.0, -2.0, -3.0]])
    >>> B = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    >>> K = place(A, B, [-2.0, -3.0, -4.0])
    >>> sorted(round(float(p.real), 9) for p in np.linalg.eigvals(A - B @ K))
    [-4.0, -3.0, -2.0]
    """
    A, B = np.asarray(A, float), np.asarray(B, float)
    if B.ndim == 1:
        B = B[:, None]
    if B.shape[1] == 1:
        return ackermann(A, B, poles)[None, :]
    n = A.shape[0]
    if len(poles) != n:
        raise ValueError(f"needs {n} poles for {n} states, got {len(poles)}")
    from scipy.signal import place_poles

    return np.asarray(place_poles(A, B, np.asarray(poles, complex), method="YT").gain_matrix, float)


def observer_gain(A: np.ndarray, C: np.ndarray, poles: Sequence[complex]) -> np.ndarray:
    """``L`` (``n x q``) with ``eig(A - L C) = poles``: a Luenberger observer by duality, ``L = place(A^T, C^T)^T``.

    Parameters
    ----------
    A : numpy.ndarray
        ``n x n`` (1/s).
    C : numpy.ndarray
        ``q x n``: the measured outputs; ``(A, C)`` observable.
    poles : sequence of complex
        ``n`` observer poles (1/s), complex ones in conjugate pairs.

    Returns
    -------
    numpy.ndarray
        ``L`` (state units per output unit per second).

    Examples
    --------
    >>> A, C = np.array([[0.0, 1.0], [0.0, -2.0]]), np.array([[1.0, 0.0]])
    >>> L = observer_gain(A, C, [-10.0, -12.0])
    >>> sorted(round(float(p.real), 9) for p in np.linalg.eigvals(A - L @ C))
    [-12.0, -10.0]
    """
    A, C = np.asarray(A, float), np.atleast_2d(np.asarray(C, float))
    return place(A.T, C.T, poles).T
