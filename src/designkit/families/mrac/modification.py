"""The ad hoc modifications of the MRAC's gradient rule (``controller.modification``), derived in
docs/families/mrac.md, "Ad hoc modifications".

The plain rule moves the adapted parameters ``alpha = (a1, a2)`` along ``r = Gamma S' Q e`` (``e = ym - x``, ``S``
the model's sensitivities).  A modification changes how ``r`` moves them; nothing else of the loop changes (the
reference and sensitivity models, the PD law, the frozen linearization):

``normalized`` (``rate`` ``nu``, 1/s; default the reference model's natural frequency)
    ``alpha' = r/(1 + phi' phi)`` with ``phi' phi = tr(Gamma S' Q S)/nu``, the normalised gradient rule
    ``gamma/(1 + phi' phi)``.  ``Gamma_j (S' Q S)_jj`` is a rate (1/s) for either parameter, so ``phi' phi`` is
    dimensionless; about the matched trajectory the rule's rate matrix ``k Gamma S' Q S/(1 + phi' phi)`` has its
    eigenvalues below ``k nu`` whatever the reference's amplitude (the plain rule's grow as the amplitude squared).
``dead_zone`` (``width`` ``d``, rad)
    ``alpha' = r max(0, |e1| - d)/max(|e1|, d)``, ``e1 = ym1 - x1``: no adaptation while the position error is
    within ``d``, and outside it the gradient of the error passed through the dead zone ``e1 -> e1 - d sign(e1)``
    (the velocity error scaled alike).  Continuous in ``e1``, so the loop stays an ODE with a Lipschitz right side.
``projection`` (``low``, ``high``: ``[a1, a2]`` each, 1/s^2 and 1/s)
    each parameter moves as ``r_i`` except on the face of the box ``[low, high]`` it would leave: ``alpha_i' = 0``
    where ``alpha_i >= high_i`` and ``r_i > 0`` or ``alpha_i <= low_i`` and ``r_i < 0``.  With a diagonal ``Gamma``
    this is the projection of ``r`` in the metric ``Gamma^-1`` onto the box's tangent cone, so ``V = 1/2 (alpha -
    alpha*)' Gamma^-1 (alpha - alpha*)`` decreases no slower than under the plain rule for any ``alpha*`` in the
    box, and the parameters never leave it (by more than one integration step's move).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Literal

import casadi as ca
from pydantic import field_validator, model_validator

from designkit.spec.fields import Finite, PositiveFinite, Section
from designkit.spec.ranges import Ranged

__all__ = ["KINDS", "Modification", "describe", "modified_rate", "resolved"]


KINDS = {"normalized": ("rate",), "dead_zone": ("width",), "projection": ("low", "high")}
"""Each modification's settings (module docstring)."""


def _pair(v: list[float] | None) -> list[float] | None:
    if v is None:
        return v
    if len(v) != 2:
        raise ValueError(f"must list 2 values [a1, a2] (1/s², 1/s), got {len(v)}")
    for k, x in enumerate(v):
        if not 1e-12 <= x <= 1e12:
            raise ValueError(f"[{k}]: must be between 1e-12 and 1e12 (positive coefficients), got {x:g}")
    return [float(x) for x in v]


class Modification(Section):
    """``controller.modification`` (module docstring): ``kind`` and that kind's settings only.

    ``normalized``: ``rate`` (1/s, 1e-6 to 1e6; default the reference model's natural frequency), the adaptation
    rate above which the rule is normalised.  ``dead_zone``: ``width`` (rad, above 0, at most 1e3, required), no
    adaptation while ``|ym1 - x1| <= width``.  ``projection``: ``low`` and ``high`` (``[a1, a2]`` each, 1/s^2 and
    1/s, 1e-12 to 1e12, ``low < high``, required), the box the adapted parameters are kept in.
    """

    kind: Literal["normalized", "dead_zone", "projection"]
    rate: Ranged(1e-6, 1e6, "1/s", base=PositiveFinite) | None = None
    width: Ranged(0, 1e3, "rad", low_open=True, base=Finite) | None = None
    low: list[Finite] | None = None
    high: list[Finite] | None = None

    @field_validator("low", "high")
    @classmethod
    def _two(cls, v: list[float] | None) -> list[float] | None:
        return _pair(v)

    @model_validator(mode="after")
    def _settings_of_kind(self) -> Modification:
        own = KINDS[self.kind]
        for name in ("rate", "width", "low", "high"):
            if name not in own and getattr(self, name) is not None:
                raise ValueError(f"{name}: not a setting of the {self.kind} modification (its settings: "
                                 f"{', '.join(own)})")
        for name in own:
            if name != "rate" and getattr(self, name) is None:
                raise ValueError(f"{name}: required by the {self.kind} modification")
        if self.kind == "projection":
            for k, (lo, hi) in enumerate(zip(self.low, self.high, strict=True)):
                if lo >= hi:
                    raise ValueError(f"high[{k}]: must be above low[{k}] = {lo:g}, got {hi:g}")
        return self


def resolved(spec: Any, natural_frequency: float) -> dict[str, Any] | None:
    """The modification of a ``controller`` section as the design stores it (``MracData.modification``), its
    default filled in (``rate``: ``natural_frequency``, rad/s, of the reference model); None without one."""
    m = spec.modification
    if m is None:
        return None
    if m.kind == "normalized":
        return {"kind": "normalized", "rate": float(m.rate) if m.rate is not None else float(natural_frequency)}
    if m.kind == "dead_zone":
        return {"kind": "dead_zone", "width": float(m.width)}
    return {"kind": "projection", "low": [float(v) for v in m.low], "high": [float(v) for v in m.high]}


def modified_rate(modification: Mapping[str, Any] | None, r: ca.SX, alpha: ca.SX, e: ca.SX, S: ca.SX,
                  gamma: ca.DM, Q: ca.DM) -> ca.SX:
    """``alpha'`` from the plain rule's ``r = Gamma S' Q e`` under ``modification`` (module docstring).

    Parameters
    ----------
    modification : mapping or None
        :func:`resolved`'s value.
    r, alpha, e : SX
        The plain rule's rate (2), the adapted parameters (2), the error ``(ym1 - x1, ym2 - x2)`` (rad, rad/s).
    S : SX
        The sensitivities ``dym/da`` (2 x 2).
    gamma, Q : DM
        ``Gamma`` (2 x 2, diagonal) and the weighting.
    """
    if modification is None:
        return r
    kind = modification["kind"]
    if kind == "normalized":
        phi2 = ca.trace(gamma @ S.T @ Q @ S) / float(modification["rate"])
        return r / (1.0 + phi2)
    if kind == "dead_zone":
        d = float(modification["width"])
        return r * ca.fmax(ca.fabs(e[0]) - d, 0.0) / ca.fmax(ca.fabs(e[0]), d)
    low, high = modification["low"], modification["high"]
    out = []
    for i in range(2):
        blocked = ca.logic_or(ca.logic_and(alpha[i] >= high[i], r[i] > 0), ca.logic_and(alpha[i] <= low[i], r[i] < 0))
        out.append(ca.if_else(blocked, 0.0, r[i]))
    return ca.vertcat(*out)


def describe(modification: Mapping[str, Any] | None) -> str:
    """The modification in words with its setting (``""`` for the plain rule)."""
    if modification is None:
        return ""
    if modification["kind"] == "normalized":
        return (f"normalised gradient rule α' = Γ Sᵀ Q e / (1 + φᵀφ), φᵀφ = tr(Γ Sᵀ Q S)/ν, "
                f"ν = {modification['rate']:.4g} 1/s")
    if modification["kind"] == "dead_zone":
        return f"dead zone: no adaptation while |ym − x1| ≤ {modification['width']:.4g} rad"
    lo, hi = modification["low"], modification["high"]
    return (f"projection of α on the box {lo[0]:.4g} ≤ α1 ≤ {hi[0]:.4g} 1/s², {lo[1]:.4g} ≤ α2 ≤ {hi[1]:.4g} 1/s")
