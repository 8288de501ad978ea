"""The decentralized PID's design data (:attr:`~designkit.synthesis.design.Design.data`)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Literal

from designkit.models.link import LinkParameters
from designkit.synthesis.design import FamilyData

__all__ = ["DecentralizedPidData"]


@dataclass(frozen=True)
class DecentralizedPidData(FamilyData):
    """Where the joint loops were designed and what the law adds, read by the law, the workspace check and the
    diagnoses.

    Attributes
    ----------
    configuration : tuple of float
        ``q*``, the configuration the simplified links are computed at (rad or m per joint).
    links : tuple of LinkParameters
        Each joint's simplified link at ``q*`` (:func:`designkit.models.link.simplified_link`): ``Km = 1/f_i``
        ((rad/s)/(N*m) or (m/s)/N), ``tau = D_ii(q*)/f_i`` (s), ``inertia = D_ii(q*)`` (kg*m^2 or kg) and
        ``damping = f_i`` (N*m*s/rad or N*s/m); the plants of ``design.loops``.
    gravity_feedforward : {"measured", "desired", "none"}
        The gravity feed-forward of the law: ``g^(q)``, ``g^(qD)`` or none.
    workspace : Mapping or None
        The box the ``workspace`` check certifies (:func:`designkit.spec.workspace.workspace_box`): ``low`` and
        ``high`` (rad or m per joint), ``samples``, ``tolerance`` (relative) and ``source``; None without
        ``controller.workspace``.
    """

    configuration: tuple[float, ...]
    links: tuple[LinkParameters, ...]
    gravity_feedforward: Literal["measured", "desired", "none"]
    workspace: Mapping[str, Any] | None
