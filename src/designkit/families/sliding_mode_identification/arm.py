"""The robot form's parameters: the base parameters of a robot plant at its values, and their units.

The arm's dynamics are linear in the model layer's standard parameters ``P`` (:mod:`designkit.models.regressor`),
``u = W(q, qd, qdd) P``, and in the base parameters ``beta = K P`` (:mod:`designkit.models.base_parameters`):
``u = Wb(q, qd, qdd) beta``, ``Wb`` the independent columns of ``W``.  A zoo or DH plant is symbolic in its named
parameters (``m2``, ``d1``, ``g``...); ``W`` depends only on those the kinematics and gravity hold (lengths,
``g``), ``K`` likewise, and ``P`` on the others.  :func:`base_of` evaluates the regressor at the plant's values
and runs the model layer's base-parameter discovery on it; :func:`true_beta` gives ``beta = K P`` for any plant
with the same kinematics (the true plant, after a change of a mass or a friction), and :func:`regressor_symbols`
names the parameters a change of which would change ``Wb`` (refused in ``simulation.plant_change``).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from designkit.models.base_parameters import BaseParameters, base_parameters

__all__ = ["ArmModel", "base_of", "parameter_unit", "regressor_symbols", "true_beta"]

_UNIT_OF = {"m": "kg", "mcx": "kg*m", "mcy": "kg*m", "mcz": "kg*m", "fv": "N*m*s/rad", "fc": "N*m", "Ia": "kg*m^2"}


def parameter_unit(name: str) -> str:
    """The SI unit of a base parameter named after its standard parameter (``Izz1R`` kg*m^2, ``mcx2`` kg*m,
    ``fv1`` N*m*s/rad, ``fc1`` N*m).

    Examples
    --------
    >>> parameter_unit("Izz1R"), parameter_unit("mcx2"), parameter_unit("fc2")
    ('kg*m^2', 'kg*m', 'N*m')
    """
    stem = name.removesuffix("R").rstrip("0123456789")
    return _UNIT_OF.get(stem, "kg*m^2" if stem.startswith("I") else "")


@dataclass(frozen=True, eq=False)
class ArmModel:
    """What :func:`~designkit.models.base_parameters.base_parameters` reads of a robot, at numeric values.

    Parameters
    ----------
    functions : dict
        ``{"regressor": casadi.Function (q, qd, qdd) -> W}`` with the plant's values substituted.
    parameters : numpy.ndarray
        The standard parameters ``P`` at the plant's values.
    parameter_names : tuple of str
        Their names.
    description : ChainDescription
        The chain (its joint types).
    """

    functions: dict[str, Any] = field(repr=False)
    parameters: np.ndarray = field(repr=False)
    parameter_names: tuple[str, ...]
    description: Any = field(repr=False)


def _numeric(plant: Any) -> ArmModel:
    robot = plant.robot
    p = plant.model_parameters()
    reg = robot.functions["regressor"]
    n = robot.n
    q, qd, qdd = (ca.SX.sym(s, n) for s in ("q", "qd", "qdd"))
    args = [q, qd, qdd] + ([ca.DM(np.asarray(p, dtype=float))] if p is not None else [])
    W = reg(*args)
    f = ca.Function("regressor", [q, qd, qdd], [W], ["q", "qd", "qdd"], ["W"])
    values = np.asarray(robot.parameter_values(p), dtype=float).reshape(-1)
    return ArmModel({"regressor": f}, values, tuple(robot.parameter_names), robot.description)


@functools.lru_cache(maxsize=8)
def base_of(plant: Any) -> BaseParameters:
    """The base parameters of the robot plant at its parameter values (cached per plant object)."""
    return base_parameters(_numeric(plant))


def true_beta(base: BaseParameters, plant: Any) -> np.ndarray:
    """``beta = K P`` of ``plant`` (the same kinematics as the plant ``base`` was computed on): SI units."""
    P = np.asarray(plant.robot.parameter_values(plant.model_parameters()), dtype=float).reshape(-1)
    return base.K @ P


def regressor_symbols(plant: Any) -> tuple[str, ...]:
    """The plant's named parameters the regressor ``W(q, qd, qdd)`` depends on (lengths, gravity)."""
    robot = plant.robot
    names = robot.symbol_names
    if not names:
        return ()
    n = robot.n
    q, qd, qdd = (ca.SX.sym(s, n) for s in ("q", "qd", "qdd"))
    p = ca.SX.sym("p", len(names))
    W = robot.functions["regressor"](q, qd, qdd, p)
    return tuple(name for k, name in enumerate(names) if ca.depends_on(W, p[k]))
