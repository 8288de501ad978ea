"""A plant's linear model at rest, symbolic in its parameters, and the controllability of ``(A, B)``.

**Linear model.**  ``x' = A(p) x + B(p) u + D(p) d`` is the plant's ODE linearised at the rest state ``x = 0``,
``u = 0``, ``d = 0`` by CasADi, kept symbolic in the plant parameters ``p`` (:func:`linear_model`), so that a
family can evaluate it at the nominal parameters, at a vertex of an uncertainty box, or keep its entries as CasADi
expressions over the box (the bounds of a variable-structure controller's gains).

**Controllability.**  A single-input ``(A, B)`` is controllable when its controllability matrix
``W = [B, AB, ..., A^(n-1) B]`` is invertible.  Numerically that is judged by Hadamard's ratio
``|det W| / prod ||W_k||`` (:func:`controllability_ratio`): 1 for orthogonal columns, 0 for dependent ones, and
invariant to the scaling of each column, so the states' units do not enter.  Below :data:`CONTROLLABILITY_TOL`
no state feedback or sliding surface built on ``W^-1`` can be trusted; :func:`check_controllable` refuses such a
plant with a message naming the spec key that made it so.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import casadi as ca
import numpy as np

from designkit.errors import SpecError

__all__ = ["CONTROLLABILITY_TOL", "COUPLING", "LinearModel", "check_controllable", "controllability_matrix",
           "controllability_ratio", "linear_model"]

CONTROLLABILITY_TOL = 1e-10
"""``(A, B)`` is treated as uncontrollable when ``|det W| / prod ||W_k||`` (Hadamard's ratio of the controllability
matrix, 1 for orthogonal columns) is below this: a gain or surface would rest on a numerically singular ``W``."""

COUPLING = ("KR", "J2", "R2")
"""Elastic-joint parameters of the coupling ``k2 = KR R2^2/J2`` through which the motor reaches the link."""


@dataclass(frozen=True, eq=False)
class LinearModel:
    """``x' = A(p) x + B(p) u + D(p) d`` at rest, symbolic in the plant parameters.

    Attributes
    ----------
    names : tuple of str
        Parameter names, in the plant's order.
    p : casadi.SX
        Their symbols.
    A, B, D : casadi.SX
        ``n x n``, ``n x 1`` and ``n x n_d`` in ``p`` (units of the plant's states per state, input, disturbance).
    nominal : numpy.ndarray
        The plant's parameter values.
    """

    names: tuple[str, ...]
    p: ca.SX
    A: ca.SX
    B: ca.SX
    D: ca.SX
    nominal: np.ndarray

    @functools.cached_property
    def _numeric(self) -> ca.Function:
        return ca.Function("abd", [self.p], [self.A, self.B, self.D])

    def at(self, values: dict[str, float] | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(A, B, D)`` as arrays at the nominal parameters with ``values`` replaced."""
        pv = self.nominal.copy()
        for k, v in (values or {}).items():
            pv[self.names.index(k)] = float(v)
        return tuple(np.array(m, dtype=float) for m in self._numeric(pv))  # type: ignore[return-value]


def linear_model(plant: object) -> LinearModel:
    """The plant's ODE linearised at rest (``x = 0``, ``u = 0``, ``d = 0``), symbolic in its parameters.

    Parameters
    ----------
    plant : Plant
        Any plant with ``ode()`` ``(x, u, d, p) -> xdot``, ``parameters`` and ``parameter_vector``.

    Returns
    -------
    LinearModel
        ``A``, ``B``, ``D`` as CasADi expressions in the parameter symbols, and the nominal values.
    """
    f = plant.ode()  # type: ignore[attr-defined]
    n, nd = f.size1_in(0), f.size1_in(2)
    x, u, d = ca.SX.sym("x", n), ca.SX.sym("u", f.size1_in(1)), ca.SX.sym("d", nd)
    names = tuple(par.name for par in plant.parameters)  # type: ignore[attr-defined]
    p = ca.SX.sym("p", len(names))
    xdot = f(x, u, d, p)
    at_rest = {"x": ca.DM.zeros(n), "u": ca.DM.zeros(u.numel()), "d": ca.DM.zeros(nd)}
    mats = []
    for var in (x, u, d):
        jac = ca.jacobian(xdot, var)
        mats.append(ca.substitute([jac], [x, u, d], [at_rest["x"], at_rest["u"], at_rest["d"]])[0])
    return LinearModel(names, p, *mats, np.asarray(plant.parameter_vector, dtype=float))  # type: ignore[attr-defined]


def controllability_matrix(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """``W = [B, AB, ..., A^(n-1) B]`` (``n x n m``; ``n x n`` for a single input).

    Parameters
    ----------
    A : numpy.ndarray
        ``n x n`` (state units per state unit per second).
    B : numpy.ndarray
        ``n`` or ``n x 1`` (state units per second per input unit).

    Returns
    -------
    numpy.ndarray
        ``n x n``; column ``k`` in state units per second^(k+1) per input unit.
    """
    n = A.shape[0]
    B = np.asarray(B, float).reshape(n, -1)
    blocks = [B]
    for _ in range(n - 1):
        blocks.append(A @ blocks[-1])
    return np.hstack(blocks)


def controllability_ratio(A: np.ndarray, B: np.ndarray) -> float:
    """Hadamard's ratio ``|det W| / prod ||W_k||`` of :func:`controllability_matrix`, in ``[0, 1]``
    (dimensionless; 0: uncontrollable); with several inputs (``W`` wider than tall) the ratio of the ``n``-th to
    the first singular value of ``W`` with unit columns, also 0 exactly when ``rank W < n``."""
    W = controllability_matrix(A, B)
    norms = np.linalg.norm(W, axis=0)
    if W.shape[1] > W.shape[0]:  # several inputs: the n-th singular value of the column-scaled W over the first
        kept = norms > 0
        if not np.any(kept):
            return 0.0
        sv = np.linalg.svd(W[:, kept] / norms[kept], compute_uv=False)
        return float(sv[W.shape[0] - 1] / sv[0]) if sv.size >= W.shape[0] else 0.0
    if np.any(norms == 0):
        return 0.0
    return float(abs(np.linalg.det(W / norms)))


def check_controllable(spec: object, model: LinearModel, box: dict[str, tuple[float, float]],
                       consequence: str = "no state feedback places the poles") -> None:
    """Refuse a plant (nominal, or a vertex of the box) whose ``(A, B)`` is not controllable.

    Parameters
    ----------
    spec : Spec
        The spec (its ``plant`` section names the parameter to blame).
    model : LinearModel
        The plant's linear model.
    box : dict
        Parameter name -> ``(low, high)`` in the parameter's SI unit; every bound is checked.
    consequence : str
        What an uncontrollable plant means for the controller, ending the message.

    Raises
    ------
    SpecError
        At ``plant.<name>``: on the elastic joint, the coupling parameter given (``KR``, else ``J2`` or ``R2``)
        that makes the motor unable to move the link; at ``plant.uncertainty.<name>`` for a vertex.
    """
    A, B, _ = model.at()
    ratio = controllability_ratio(A, B)
    if ratio < CONTROLLABILITY_TOL:
        plant = spec.plant  # type: ignore[attr-defined]
        if plant.kind == "transfer_function":
            raise SpecError("plant.num", f"shares a root with plant.den (a pole-zero cancellation): the realisation "
                            f"is not controllable (Hadamard ratio {ratio:.3g}): {consequence}")
        if plant.kind == "state_space":
            raise SpecError("plant.B", f"(A, B) is not controllable (Hadamard ratio {ratio:.3g}): {consequence}")
        if plant.kind != "elastic_joint":
            raise SpecError("plant", f"the plant is not controllable (Hadamard ratio {ratio:.3g})")
        given = [k for k in COUPLING if getattr(plant, k, None) is not None] or ["KR"]
        raise SpecError(f"plant.{given[0]}", f"makes the plant uncontrollable: the motor reaches the link only "
                        f"through the coupling k2 = KR R2²/J2 = {-A[3, 2]:.3g} 1/s², and the controllability "
                        f"matrix [B, AB, A²B, A³B] is singular to {ratio:.3g} (Hadamard ratio, below "
                        f"{CONTROLLABILITY_TOL:g}): {consequence}")
    for name, (lo, hi) in box.items():
        for v in (lo, hi):
            Ab, Bb, _ = model.at({name: v})
            if controllability_ratio(Ab, Bb) < CONTROLLABILITY_TOL:
                raise SpecError(f"plant.uncertainty.{name}", f"{name} = {v:g} makes the plant uncontrollable")
