"""Certificates: the solver's answer in a form NumPy can re-check on its own.

A certificate is data (matrices, multipliers, a point) plus a statement it proves, e.g.
"``x'Px`` decreases along ``x' = A x``" or "``c + a . theta > 0`` on this parameter box".  The
optimisation solver only *proposes* the data.  Whether the statement holds is decided by
:meth:`Certificate.recheck`, which recomputes eigenvalues, residuals and bounds with NumPy from
the data alone and returns a :class:`Recheck`: ``ok``, a signed ``margin`` (non-negative iff
``ok``), one line of explanation and the numbers it computed.

Every certificate serialises to plain JSON with :meth:`Certificate.to_dict` and is rebuilt with
:func:`load`, so a stored certificate can be re-checked later without the solver.  The concrete
kinds live in :mod:`designkit.verification.lmi` (``"lyapunov"``, ``"kyp"``) and
:mod:`designkit.verification.lp` (``"lp_lower_bound"``, ``"feasible_point"``, ``"farkas"``).

JSON has no complex numbers, NaN or infinity: :func:`to_json` writes a complex number as
``[re, im]`` and a non-finite float as ``None``; :func:`array_from_json` reads ``None`` back as NaN.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from importlib import import_module
from typing import Any, Protocol, runtime_checkable

import numpy as np

_KINDS: dict[str, str] = {
    "lyapunov": "designkit.verification.lmi:LyapunovCertificate",
    "kyp": "designkit.verification.lmi:KypCertificate",
    "lp_lower_bound": "designkit.verification.lp_certificates:LowerBoundCertificate",
    "feasible_point": "designkit.verification.lp_certificates:FeasiblePointCertificate",
    "farkas": "designkit.verification.lp_certificates:FarkasCertificate",
}


def to_json(value: Any) -> Any:
    """A JSON-serialisable copy of ``value`` (strict JSON: no NaN, no infinity).

    NumPy arrays become nested lists, NumPy scalars Python numbers, complex numbers ``[re, im]``,
    non-finite floats ``None``; mappings and sequences are converted recursively.

    Examples
    --------
    >>> to_json({"a": np.array([1.0, np.inf]), "z": 1 + 2j})
    {'a': [1.0, None], 'z': [1.0, 2.0]}
    """
    if isinstance(value, Mapping):
        return {str(k): to_json(v) for k, v in value.items()}
    if isinstance(value, np.ndarray):
        return [to_json(v) for v in value.tolist()] if value.ndim else to_json(value.item())
    if isinstance(value, (list, tuple)):
        return [to_json(v) for v in value]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (complex, np.complexfloating)):
        return [to_json(complex(value).real), to_json(complex(value).imag)]
    if isinstance(value, (float, np.floating)):
        x = float(value)
        return x if math.isfinite(x) else None
    return value


def array_from_json(value: Any) -> np.ndarray:
    """Float array from :func:`to_json` output (``None`` becomes NaN)."""

    def conv(v: Any) -> Any:
        if isinstance(v, list):
            return [conv(u) for u in v]
        return np.nan if v is None else float(v)

    return np.array(conv(value), dtype=float)


@dataclass(frozen=True)
class Recheck:
    """Verdict of a certificate's NumPy re-check.

    Parameters
    ----------
    ok : bool
        The statement of the certificate holds (with its margin and tolerances).
    margin : float
        Signed slack of the tightest condition, non-negative iff ``ok`` (unit of the certificate:
        dimensionless for LMIs, the condition's unit for LP bounds).  NaN or ``-inf`` when the
        data cannot be evaluated (non-finite entries).
    detail : str
        One line: what was checked and, when not ok, which condition failed.
    values : Mapping
        The numbers the re-check computed (eigenvalues, residuals, bounds), already JSON-ready.
    """

    ok: bool
    margin: float
    detail: str = ""
    values: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        ok, margin = bool(self.ok), float(self.margin)
        if ok != bool(margin >= 0):  # NaN >= 0 is False: a NaN margin is never ok
            raise ValueError(f"inconsistent re-check: ok={ok} with margin={margin}")
        object.__setattr__(self, "ok", ok)
        object.__setattr__(self, "margin", margin)
        object.__setattr__(self, "values", to_json(dict(self.values)))

    def to_dict(self) -> dict[str, Any]:
        """JSON-serialisable form."""
        return {"ok": self.ok, "margin": to_json(self.margin), "detail": self.detail, "values": dict(self.values)}


@runtime_checkable
class Certificate(Protocol):
    """What every certificate provides.

    Attributes
    ----------
    kind : str
        Registered name (see :func:`load`), also stored under ``"kind"`` in :meth:`to_dict`.
    """

    kind: str

    def recheck(self) -> Recheck:
        """Decide the certificate's statement from its data with NumPy only (no solver)."""

    def to_dict(self) -> dict[str, Any]:
        """The data needed to re-check, JSON-serialisable, with ``"kind"``."""


def load(data: Mapping[str, Any]) -> Certificate:
    """Rebuild a certificate from :meth:`Certificate.to_dict` output (e.g. after ``json.loads``).

    Raises
    ------
    ValueError
        When ``data["kind"]`` is not a registered kind.
    """
    kind = data.get("kind")
    target = _KINDS.get(str(kind))
    if target is None:
        raise ValueError(f"unknown certificate kind {kind!r}; known: {sorted(_KINDS)}")
    module, name = target.split(":")
    return getattr(import_module(module), name).from_dict(data)
