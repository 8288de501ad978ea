"""Inertial parameters of a link, linear in the dynamics.

Each link contributes ``[m, m*cx, m*cy, m*cz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz]``: mass (kg),
first moment ``m c`` (kg*m) and inertia tensor (kg*m^2) about its *DH-frame origin*,
in the link frame.  The recursive Newton--Euler of :mod:`designkit.models.newton_euler`
is linear in these, so they are the standard parameters of the regressor
(:mod:`designkit.models.regressor`).
"""

from __future__ import annotations

from typing import Any

from designkit.models.description import ChainDescription, LinkDescription
from designkit.models.exact_arithmetic import add, mul, scalar, sub

__all__ = ["INERTIAL_NAMES", "inertial_parameters", "link_inertial_parameters"]

INERTIAL_NAMES: tuple[str, ...] = ("m", "mcx", "mcy", "mcz", "Ixx", "Ixy", "Ixz", "Iyy", "Iyz", "Izz")
"""Names of the 10 inertial parameters of one link (about its DH-frame origin, link frame)."""


def link_inertial_parameters(link: LinkDescription) -> tuple[Any, ...]:
    """The 10 inertial parameters of a link about its DH-frame origin.

    Parallel-axis theorem: ``I_o = I_c + m (|c|^2 E - c c')``, where ``I_c`` is the
    inertia tensor about the centre of mass ``c`` (tensor entries, so the
    off-diagonal ``Ixy`` is ``-sum m x y``).

    Parameters
    ----------
    link : LinkDescription
        Mass (kg), centre of mass (m) and inertia about it (kg*m^2), link frame.

    Returns
    -------
    tuple
        ``(m, m cx, m cy, m cz, Ixx, Ixy, Ixz, Iyy, Iyz, Izz)`` (kg, kg*m, kg*m^2).
    """
    m = scalar(link.mass)
    cx, cy, cz = (scalar(c) for c in link.com)
    ixx, iyy, izz, ixy, ixz, iyz = (scalar(v) for v in link.inertia)
    return (
        m,
        mul(m, cx),
        mul(m, cy),
        mul(m, cz),
        add(ixx, mul(m, add(mul(cy, cy), mul(cz, cz)))),
        sub(ixy, mul(m, mul(cx, cy))),
        sub(ixz, mul(m, mul(cx, cz))),
        add(iyy, mul(m, add(mul(cx, cx), mul(cz, cz)))),
        sub(iyz, mul(m, mul(cy, cz))),
        add(izz, mul(m, add(mul(cx, cx), mul(cy, cy)))),
    )


def inertial_parameters(description: ChainDescription) -> list[Any]:
    """Concatenated inertial parameters of every link (length ``10 n``), see :func:`link_inertial_parameters`."""
    return [p for link in description.links for p in link_inertial_parameters(link)]
