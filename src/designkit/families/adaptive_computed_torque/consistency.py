"""Starting estimates no physical arm has: warned, never refused (a user may start the adaptation anywhere).

The estimate vector ``P^`` is the arm's true regressor vector with the adapted entries at ``controller.initial``.
Per link touched by an adapted parameter, with ``m``, ``h = (mcx, mcy, mcz)`` and ``I_O`` (the inertia tensor
about the link's frame origin) read from ``P^``, a mass distribution exists only if (Wensing, Kim and Slotine,
IEEE RA-L 3(1), 2018; :mod:`designkit.models.physical` for the tensor about the centre of mass)

* ``m >= 0``;
* ``I_O`` is positive semidefinite (its moments non-negative);
* its principal moments satisfy the triangle inequalities ``l_i <= l_j + l_k``, i.e.
  ``S_O = tr(I_O)/2 E - I_O`` (the second moments ``int x x' dm``) is positive semidefinite;
* the pseudo-inertia matrix ``J = [[S_O, h], [h', m]]`` is positive semidefinite (which the three above imply only
  without a first moment).

And per joint: rotor inertia ``Ia``, viscous ``fv`` and Coulomb ``fc`` friction non-negative.  A condition is
warned when the estimate breaks it and the true arm does not (an arm inconsistent as published is the generic
inertia warning's business), with the adapted parameters of that link named.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from designkit.families.adaptive_computed_torque.laws import parameter_units, true_parameters
from designkit.families.adaptive_computed_torque.words import unit_text

__all__ = ["TOLERANCE", "start_warnings", "violations"]

TOLERANCE = 1e-9
"""A condition holds when its smallest eigenvalue (or value) is above ``-TOLERANCE`` times the link's scale."""

_JOINT = {"Ia": "rotor inertia", "fv": "viscous friction", "fc": "Coulomb friction"}


def _link(values: dict[str, float], i: int) -> tuple[float, np.ndarray, np.ndarray] | None:
    keys = [f"{k}{i}" for k in ("m", "mcx", "mcy", "mcz", "Ixx", "Ixy", "Ixz", "Iyy", "Iyz", "Izz")]
    if not all(k in values for k in keys):
        return None
    m, hx, hy, hz, ixx, ixy, ixz, iyy, iyz, izz = (values[k] for k in keys)
    inertia = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    return m, np.array([hx, hy, hz]), inertia


def _conditions(m: float, h: np.ndarray, inertia: np.ndarray) -> dict[str, float]:
    """Each condition's value (>= 0 when it holds): mass, the least moment, the least second moment (triangle),
    the least eigenvalue of the pseudo-inertia matrix."""
    S = 0.5 * np.trace(inertia) * np.eye(3) - inertia
    J = np.block([[S, h[:, None]], [h[None, :], np.array([[m]])]])
    return {"mass": float(m), "psd": float(np.linalg.eigvalsh(inertia)[0]),
            "triangle": float(np.linalg.eigvalsh(S)[0]), "pseudo": float(np.linalg.eigvalsh(J)[0])}


def violations(names: Sequence[str], true: Sequence[float], estimate: Sequence[float]) -> list[tuple[str, str]]:
    """``(parameters named, sentence)`` for each condition the estimate breaks and the true vector keeps (module
    docstring); ``names`` the regressor's parameter names, ``true`` and ``estimate`` vectors in that layout."""
    t = dict(zip(names, (float(x) for x in true), strict=True))
    e = dict(zip(names, (float(x) for x in estimate), strict=True))
    changed = [x for x in names if t[x] != e[x]]
    out: list[tuple[str, str]] = []
    links = sorted({_split(x)[1] for x in changed if _split(x)[0] not in _JOINT})
    for i in links:
        got_t, got_e = _link(t, i), _link(e, i)
        if got_t is None or got_e is None:
            continue
        mine = [x for x in changed if _split(x)[0] not in _JOINT and _split(x)[1] == i]
        start = ", ".join(f"{x} = {e[x]:.6g} {unit_text(_unit(x))}" for x in mine)
        scale = max(1.0, float(np.max(np.abs(got_t[2]))), abs(got_t[0]))
        ct, ce = _conditions(*got_t), _conditions(*got_e)
        broken = {k: v for k, v in ce.items() if v < -TOLERANCE * scale and ct[k] >= -TOLERANCE * scale}
        if not broken:
            continue
        words = []
        if "mass" in broken:
            words.append(f"a negative mass ({broken['mass']:.4g} kg)")
        if "psd" in broken:
            words.append(f"an inertia tensor about the frame origin that is not positive semidefinite (least "
                         f"eigenvalue {broken['psd']:.4g} kg·m²: a negative moment of inertia)")
        if "triangle" in broken:
            words.append(f"principal moments that break the triangle inequality l_i ≤ l_j + l_k (by "
                         f"{-2 * broken['triangle']:.4g} kg·m²)")
        if not words and "pseudo" in broken:
            words.append(f"mass, first moment and inertia of no body (pseudo-inertia matrix not positive "
                         f"semidefinite, least eigenvalue {broken['pseudo']:.4g})")
        if words:
            out.append((", ".join(mine), f"the starting estimate {start} gives link {i} " + " and ".join(words)))
    for x in changed:
        stem = x.rstrip("0123456789")
        if stem in _JOINT and e[x] < 0 <= t[x]:
            out.append((x, f"the starting estimate {x} = {e[x]:.6g} {unit_text(_unit(x))} is a negative "
                           f"{_JOINT[stem]} of joint {x[len(stem):]}"))
    return out


def _unit(name: str) -> str:
    return parameter_units([name])[0]


def _split(name: str) -> tuple[str, int]:
    """``"Izz12"`` -> ``("Izz", 12)``."""
    stem = name.rstrip("0123456789")
    return stem, int(name[len(stem):]) if name[len(stem):] else 0


def start_warnings(plant: Any, adapted: Sequence[str], initial: Sequence[float]) -> tuple[str, ...]:
    """The warnings (one sentence each) on the starting estimates ``initial`` of ``adapted`` on the arm ``plant``."""
    names = list(plant.robot.parameter_names)
    true = true_parameters(plant)
    est = true.copy()
    for x, v in zip(adapted, initial, strict=True):
        est[names.index(x)] = float(v)
    return tuple("Physically impossible starting estimate (controller.initial: " + who + "): " + sentence
                 + "; the adaptation may start there, but no arm has these parameters."
                 for who, sentence in violations(names, true, est))
