"""Physical consistency of a chain's inertial parameters, and the nearest consistent inertia.

A link's mass ``m`` and inertia tensor ``I_c`` about its centre of mass come from a mass distribution
only if ``m >= 0`` and ``I_c = tr(S) E - S`` for the distribution's second-moment matrix
``S = int (x - c)(x - c)' dm``, which is positive semi-definite.  In the principal axes of ``I_c``
(moments ``l1, l2, l3``) that is ``S = diag(d)`` with ``d_i = (l_j + l_k - l_i)/2 >= 0``: the
moments are non-negative and satisfy the **triangle inequalities** ``l_i <= l_j + l_k``
(equivalently, the pseudo-inertia matrix ``[[S, m c], [m c', m]]`` is positive semi-definite;
P. M. Wensing, S. Kim and J.-J. E. Slotine, "Linear matrix inequalities for physically consistent
inertial parameter identification", IEEE RA-L 3(1), 2018).  A body with no mass has no inertia.

Literature parameters are kept as published; :func:`check_inertia` states every violation (link,
which condition, by how much), and :func:`nearest_consistent` offers, as an explicit option, a
consistent inertia in the same principal axes, by one of two projections of the principal moments:

* ``"raise"`` (the default): the smallest moment is raised until the triangle inequality holds
  (``l_min' = l_max - l_mid``; a negative moment is first raised to zero).  Every published moment
  stays a lower bound and the total change is the least possible among changes that only raise
  moments; the added inertia is about one axis, so ``M(q)`` changes only where the link turns about
  it.  On the PUMA 560 that is nothing for link 1 (it only ever turns about the axis that carries
  its 0.35 kg*m^2) and a rank-one term for link 3.
* ``"nearest"``: the Euclidean projection onto the consistent cone, ``l' = A d*`` with
  ``d* = argmin_{d >= 0} ||A d - l||`` (non-negative least squares, SciPy's ``nnls``),
  ``A = [[0, 1, 1], [1, 0, 1], [1, 1, 0]]`` the map from second moments to moments; it also lowers
  the largest moment (by 0.117 kg*m^2 on the PUMA's link 1, and ``M_11`` with it).

A massless link with an inertia (a rotor's inertia lumped into the joint) is stated as such.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from designkit.models.description import ChainDescription

__all__ = ["Consistency", "InertiaChange", "InertiaViolation", "check_inertia", "nearest_consistent"]

ROUNDING = 1e-12
"""Violations smaller than this share of the link's largest moment (or mass) are rounding, not violations."""

_A = np.array([[0.0, 1.0, 1.0], [1.0, 0.0, 1.0], [1.0, 1.0, 0.0]])


def _tensor(inertia: Any) -> np.ndarray | None:
    """The inertia tensor, or None when an entry is symbolic."""
    from designkit.models.chain import numeric_value

    values = [numeric_value(v) for v in inertia]
    if any(v is None for v in values):
        return None
    ixx, iyy, izz, ixy, ixz, iyz = values
    return np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])


@dataclass(frozen=True)
class InertiaViolation:
    """One physical-consistency condition a link breaks.

    Parameters
    ----------
    link : int
        1-based link number.
    name : str
        The joint's name.
    condition : str
        In words.
    amount : float
        By how much it is broken (kg*m^2, or kg for the mass).
    """

    link: int
    name: str
    condition: str
    amount: float

    def sentence(self) -> str:
        """One plain sentence."""
        unit = "kg" if self.condition.startswith("mass") else "kg·m²"
        return f"link {self.link} ({self.name}): {self.condition}, broken by {self.amount:.3g} {unit}"


@dataclass(frozen=True)
class Consistency:
    """The violations of a chain's inertial parameters (empty: consistent).

    Parameters
    ----------
    robot : str
    violations : tuple of InertiaViolation
    notes : tuple of str
        Facts that are not violations (a massless link carrying a rotor's inertia).
    """

    robot: str
    violations: tuple[InertiaViolation, ...]
    notes: tuple[str, ...] = ()

    @property
    def consistent(self) -> bool:
        """No link breaks a condition."""
        return not self.violations

    def sentences(self) -> list[str]:
        """What a report or the model summary says, one plain sentence each."""
        if self.consistent:
            out = [f"The inertial parameters of {self.robot} are physically consistent (every link's mass is "
                   "non-negative and its principal moments satisfy the triangle inequalities)."]
        else:
            out = [f"The inertial parameters of {self.robot} are not physically consistent, as published: "
                   + "; ".join(v.sentence() for v in self.violations) + ". Drake and MuJoCo may refuse or silently "
                   "alter such a link; a consistent inertia is available as an explicit option (dk.robot(name, "
                   "consistent_inertia='raise'), or consistent_inertia: raise in a spec's robot plant)."]
        return out + list(self.notes)


def check_inertia(description: ChainDescription) -> Consistency:
    """The physical-consistency conditions (module docstring) of every link of a chain.

    A symbolic mass is not judged; a link with a symbolic inertia entry is skipped (and noted).

    Examples
    --------
    >>> from designkit.models.robots.puma560 import description
    >>> [v.link for v in check_inertia(description()).violations]
    [1, 3]
    """
    from designkit.models.chain import numeric_value

    violations: list[InertiaViolation] = []
    notes: list[str] = []
    for k, link in enumerate(description.links, start=1):
        name = link.name or f"joint{k}"
        m = numeric_value(link.mass)
        if m is not None and m < 0:
            violations.append(InertiaViolation(k, name, "mass must be non-negative", -m))
        tensor = _tensor(link.inertia)
        if tensor is None:
            notes.append(f"Link {k} ({name}): its inertia is symbolic, checked when given values.")
            continue
        moments = np.linalg.eigvalsh(tensor)
        scale = max(float(np.max(np.abs(moments))), 0.0)
        if scale == 0.0:
            continue
        if moments[0] < -ROUNDING * scale:
            violations.append(InertiaViolation(k, name, "inertia tensor must be positive semi-definite",
                                               float(-moments[0])))
        gaps = [moments[j] + moments[(j + 1) % 3] - moments[(j + 2) % 3] for j in range(3)]
        worst = int(np.argmin(gaps))
        if gaps[worst] < -ROUNDING * scale:
            i = (worst + 2) % 3
            others = sorted(((worst) % 3, (worst + 1) % 3))
            violations.append(InertiaViolation(
                k, name, f"principal moments must satisfy the triangle inequality ({moments[others[0]]:.4g} + "
                f"{moments[others[1]]:.4g} >= {moments[i]:.4g} kg·m²)", float(-gaps[worst])))
        if m == 0.0:
            notes.append(f"Link {k} ({name}) has no mass but an inertia of up to {scale:.3g} kg·m²: a rotor's inertia "
                         "lumped into the joint, not a body.")
    return Consistency(description.name, tuple(violations), tuple(notes))


@dataclass(frozen=True)
class InertiaChange:
    """What :func:`nearest_consistent` changed in one link.

    Parameters
    ----------
    link : int
        1-based.
    before, after : tuple of float
        Principal moments (kg*m^2), in the same principal axes.
    """

    link: int
    before: tuple[float, float, float]
    after: tuple[float, float, float]

    def sentence(self) -> str:
        """One plain sentence."""
        b = ", ".join(f"{v:.4g}" for v in self.before)
        a = ", ".join(f"{v:.4g}" for v in self.after)
        return f"link {self.link}: principal moments ({b}) kg·m² replaced by ({a}) kg·m² in the same axes"


def _raise(moments: np.ndarray) -> np.ndarray:
    out = np.maximum(moments, 0.0)
    order = np.argsort(out)
    low, mid, high = order
    if out[low] + out[mid] < out[high]:
        out[low] = out[high] - out[mid]
    return out


def nearest_consistent(description: ChainDescription, method: str = "raise"
                       ) -> tuple[ChainDescription, tuple[InertiaChange, ...]]:
    """The chain with each inconsistent link's principal moments projected (module docstring).

    Parameters
    ----------
    description : ChainDescription
        Numeric.
    method : {"raise", "nearest"}
        The projection.

    Masses, centres of mass and principal axes are kept; links already consistent are unchanged.

    Examples
    --------
    >>> from designkit.models.robots.puma560 import description
    >>> fixed, changes = nearest_consistent(description())
    >>> check_inertia(fixed).consistent, [c.link for c in changes]
    (True, [1, 3])
    """
    from scipy.optimize import nnls

    from designkit.errors import ModelError

    if method not in ("raise", "nearest"):
        raise ModelError("method", f"must be 'raise' or 'nearest', got {method!r}")
    bad = {v.link for v in check_inertia(description).violations if not v.condition.startswith("mass")}
    links = list(description.links)
    changes: list[InertiaChange] = []
    for k in sorted(bad):
        link = links[k - 1]
        moments, axes = np.linalg.eigh(_tensor(link.inertia))  # bad links have a numeric tensor
        new = _raise(moments) if method == "raise" else _A @ nnls(_A, moments)[0]
        tensor = axes @ np.diag(new) @ axes.T
        tensor = 0.5 * (tensor + tensor.T)
        clean = np.where(np.abs(tensor) < 1e-15 * max(1.0, float(np.abs(tensor).max())), 0.0, tensor)
        inertia = (clean[0, 0], clean[1, 1], clean[2, 2], clean[0, 1], clean[0, 2], clean[1, 2])
        links[k - 1] = replace(link, inertia=tuple(float(v) for v in inertia))
        changes.append(InertiaChange(k, tuple(float(v) for v in moments), tuple(float(v) for v in new)))
    source = description.source + f"; principal moments made physically consistent ({method}, designkit)"
    return replace(description, links=tuple(links), source=source), tuple(changes)
