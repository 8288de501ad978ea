"""The unisolvent evaluation set of a chain's regressor, and the exact check of column relations on it.

A constant vector ``r`` is a column relation of the regressor ``W(q, qd, qdd)``
(``tau = W P``) when ``W(x) r = 0`` for *every* state ``x``.  Random samples
cannot prove that; instead we use the structure of the model to pick a finite
set of states on which any function of the regressor's class that vanishes
there vanishes everywhere (a *unisolvent* set).  The class follows from the Lagrangian (see the notes' ``D_ij``,
``D_ijk``, ``D_i``):

* ``W = G(q) + A(q) qdd + B(q)[qd, qd] + Fv(qd) + Fc(sign qd)``: affine in
  ``qdd``, a quadratic form in ``qd``, plus the per-joint viscous and Coulomb
  friction columns of the model.
* Link angular and origin velocities, written in the link's own frame, have
  degree at most 1 in ``cos q_j, sin q_j`` of every revolute joint (and degree
  1 in every prismatic ``q_j``), so the kinetic part is a trigonometric
  polynomial of degree <= 2 in each revolute ``q_j`` (polynomial of degree <= 2
  in a prismatic one) and the gravity part ``G`` has degree <= 1.  The kinetic
  energy does not change when the whole chain moves about (along) joint 1, so
  ``A`` and ``B`` do not depend on ``q_1``.

The evaluation set is therefore (i) ``W(q, 0, 0)`` on the tensor grid of 3
equispaced angles per revolute joint (2 values per prismatic joint), which is
unisolvent for ``G``, and (ii) at ``q_1 = 0`` and the tensor grid of 5
equispaced angles per revolute joint ``2..n`` (3 values per prismatic joint):
``(qd, qdd) = (0, e_k)``, ``(+-e_a, 0)``, ``(2 e_a, 0)``, ``(e_a + e_b, 0)``,
which is unisolvent for the ``qd``/``qdd`` part (``1 + 3n + n(n-1)/2 + n``
coefficients, as many points).  On an equispaced grid the discrete Fourier
transform is exact for these degrees, so by Parseval the 2-norm of the grid
values bounds ``sup_q |W(q) r|``: the null space of the stacked evaluation
matrix ``Y`` *is* the null space of ``W`` as a function, and the residual of a
relation on ``Y`` bounds its residual at every state.

:func:`relation_residuals` evaluates ``W`` on this set (streamed in chunks,
never stored) and returns the relative residuals that
:mod:`designkit.models.base_parameters` reports in its certificate.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterator, Sequence

import casadi
import numpy as np

from designkit.errors import ModelError

__all__ = ["evaluation_states", "regressor_rows", "relation_residuals"]

_CHUNK = 8192  # states per mapped evaluation


def _grid(joints: tuple[str, ...], revolute_points: int, prismatic_points: int) -> np.ndarray:
    axes = []
    for joint in joints:
        if joint == "revolute":
            axes.append(0.3 + 2.0 * np.pi * np.arange(revolute_points) / revolute_points)
        else:
            axes.append(np.linspace(-0.5, 0.5, prismatic_points))
    if not axes:
        return np.zeros((1, 0))
    return np.array(list(itertools.product(*axes)), dtype=float).reshape(-1, len(joints))


def evaluation_states(joints: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The unisolvent evaluation set for a chain's regressor (see the module docstring).

    Parameters
    ----------
    joints : tuple of {"revolute", "prismatic"}
        Joint types, base to tip.

    Returns
    -------
    (numpy.ndarray, numpy.ndarray, numpy.ndarray)
        ``q``, ``qd``, ``qdd``, each ``N x n`` (rad or m, per second, per second squared).
    """
    n = len(joints)
    eye = np.eye(n)
    # Gravity part: degree 1 in every joint, all joints.
    q_gravity = _grid(joints, 3, 2)
    blocks = [(q_gravity, np.zeros_like(q_gravity), np.zeros_like(q_gravity))]
    # Velocity/acceleration part: degree 2, independent of q_1.
    rest = _grid(joints[1:], 5, 3)
    q_kin = np.hstack([np.zeros((rest.shape[0], 1)), rest]) if n else rest
    rates: list[tuple[np.ndarray, np.ndarray]] = []
    for k in range(n):
        rates.append((np.zeros(n), eye[k]))
    for a in range(n):
        rates += [(eye[a], np.zeros(n)), (-eye[a], np.zeros(n)), (2.0 * eye[a], np.zeros(n))]
    for a, b in itertools.combinations(range(n), 2):
        rates.append((eye[a] + eye[b], np.zeros(n)))
    for qd, qdd in rates:
        blocks.append((q_kin, np.tile(qd, (q_kin.shape[0], 1)), np.tile(qdd, (q_kin.shape[0], 1))))
    return tuple(np.vstack([blk[i] for blk in blocks]) for i in range(3))  # type: ignore[return-value]


def _evaluate(mapped: casadi.Function, pattern: casadi.Sparsity, q: np.ndarray, qd: np.ndarray,
              qdd: np.ndarray) -> np.ndarray:
    """Dense ``W`` at ``N`` states, shape ``(N, n, p)``, through a zero-copy ``FunctionBuffer``.

    ``mapped`` is the regressor mapped over ``N`` states and ``pattern`` the sparsity of one ``W``.
    """
    count = q.shape[0]
    buffer, run = mapped.buffer()
    inputs = [np.ascontiguousarray(x.T).ravel(order="F") for x in (q, qd, qdd)]
    for index, array in enumerate(inputs):
        buffer.set_arg(index, memoryview(array))
    nonzeros = np.zeros(mapped.nnz_out(0))
    buffer.set_res(0, memoryview(nonzeros))
    run()
    if buffer.ret() != 0:
        raise ModelError(f"evaluation of {mapped.name()!r} failed (return code {buffer.ret()})")
    flat = np.array(pattern.row()) + pattern.size1() * np.array(pattern.get_col())  # column-major index
    dense = np.zeros((count, pattern.size2() * pattern.size1()))
    dense[:, flat] = nonzeros.reshape(count, -1)
    return dense.reshape(count, pattern.size2(), pattern.size1()).transpose(0, 2, 1)



def regressor_rows(reg: casadi.Function, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> Iterator[np.ndarray]:
    """Rows of ``W`` at the states ``(q, qd, qdd)`` (each ``N x n``), chunk by chunk.

    Each chunk is evaluated with ``reg`` mapped over up to ``_CHUNK`` states and yielded
    as an array of shape ``(chunk * n, p)``: all rows of ``W`` at one state, then the next.
    """
    p = reg.size2_out(0)
    pattern = reg.sparsity_out(0)
    maps: dict[int, casadi.Function] = {}
    for start in range(0, q.shape[0], _CHUNK):
        stop = min(start + _CHUNK, q.shape[0])
        if stop - start not in maps:
            maps[stop - start] = reg.map(stop - start)
        yield _evaluate(maps[stop - start], pattern, q[start:stop], qd[start:stop], qdd[start:stop]).reshape(-1, p)


def relation_residuals(
    reg: casadi.Function,
    states: tuple[np.ndarray, ...],
    *,
    kept: Sequence[int],
    dependent: Sequence[int],
    relation: np.ndarray,
    zero: np.ndarray,
) -> tuple[float, float]:
    """Relative residuals of column relations and of zero columns on the unisolvent set.

    Parameters
    ----------
    reg : casadi.Function
        The regressor, ``q, qd, qdd -> W`` (``n x p``).
    states : (numpy.ndarray, numpy.ndarray, numpy.ndarray)
        ``q, qd, qdd`` from :func:`evaluation_states`.
    kept : sequence of int
        Independent columns, ascending.
    dependent : sequence of int
        Columns claimed to be combinations of the kept ones.
    relation : numpy.ndarray
        ``(len(kept), p)``; column ``j`` holds the coefficients of dependent column ``j``.
    zero : numpy.ndarray
        Boolean mask of the columns claimed to vanish identically.

    Returns
    -------
    (float, float)
        The largest ``||Y_j - Y_kept c_j|| / ||Y_j||`` over dependent ``j`` (0 when there is
        none), and the largest norm of a zero column relative to the largest column.
    """
    p = reg.size2_out(0)
    column_sq = np.zeros(p)
    residual_sq = np.zeros(len(dependent))
    coefficients = relation[:, dependent]
    for Y in regressor_rows(reg, *states):
        column_sq += np.einsum("ij,ij->j", Y, Y)
        if dependent:
            R = Y[:, dependent] - Y[:, kept] @ coefficients
            residual_sq += np.einsum("ij,ij->j", R, R)
    norms = np.sqrt(column_sq)
    largest = max(norms.max(initial=0.0), 1e-300)
    relation_level = np.sqrt(residual_sq) / np.maximum(norms[dependent], 1e-300) if dependent else [0.0]
    return float(np.max(relation_level)), float(norms[zero].max(initial=0.0) / largest)
