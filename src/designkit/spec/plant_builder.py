"""Build the :class:`~designkit.models.plant.Plant` a spec's ``plant`` section describes.

One function per plant kind, in a table keyed by ``kind`` (:data:`BUILDERS`).  Model-layer
errors (:class:`~designkit.errors.ModelError`, which name a model field) are re-raised as
:class:`~designkit.errors.SpecError` with the full key path (``plant.parameters.m7``,
``plant.dh[1].mass``, ``plant.uncertainty.Km``), so a user always learns which line to fix.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from designkit.errors import ModelError, SpecError
from designkit.models.plant import PlantBase
from designkit.spec.plants import (
    ElasticJointPlantSpec,
    LinkPlantSpec,
    RobotPlantSpec,
    StateSpacePlantSpec,
    TransferFunctionPlantSpec,
)

__all__ = ["BUILDERS", "check_uncertainty", "plant_from_spec"]


def _link(section: LinkPlantSpec, base_dir: Path | None) -> PlantBase:
    from designkit.models.link import LinkPlant

    return LinkPlant(Km=section.Km, tau=section.tau)


def _elastic(section: ElasticJointPlantSpec, base_dir: Path | None) -> PlantBase:
    from designkit.models.elastic import ElasticJointPlant
    from designkit.models.robots.elastic_link import elastic_link

    return ElasticJointPlant(elastic_link(**section.given()))


def _robot(section: RobotPlantSpec, base_dir: Path | None) -> PlantBase:
    plant = _robot_model(section, base_dir)
    if section.payload is not None:
        plant = plant.with_payload(section.payload.mass, section.payload.link)
    limits = section.limits
    for name in ("velocity", "acceleration", "torque"):
        value = getattr(limits, name, None) if limits is not None else None
        if isinstance(value, list) and len(value) != plant.n_joints:
            raise ModelError(f"limits.{name}", f"needs one value per joint ({plant.n_joints}), got {len(value)}")
    return plant


def _robot_model(section: RobotPlantSpec, base_dir: Path | None) -> PlantBase:
    from designkit.models.robot_plant import chain_plant, zoo_plant

    options = {"friction": section.friction, "motor_inertia": section.motor_inertia,
               "consistent_inertia": section.consistent_inertia}
    if section.robot is not None:
        return zoo_plant(section.robot, overrides=section.parameters, **options)
    if section.dh is not None:
        from designkit.models.description import ChainDescription, LinkDescription

        links = tuple(LinkDescription(**row.model_dump()) for row in section.dh)
        description = ChainDescription(name="dh", links=links, convention=section.convention,
                                       gravity=tuple(section.gravity))
        try:
            return chain_plant(description, source=f"DH table of {len(links)} joints", **options)
        except ModelError as exc:  # the description's links[i] are the spec's dh[i]
            raise ModelError(exc.field.replace("links[", "dh[", 1) or "dh", exc.message) from None
    from designkit.models.urdf import description_from_urdf

    path = Path(section.urdf)
    if not path.is_absolute() and base_dir is not None:
        path = base_dir / path
    try:
        found = path.is_file()
    except OSError as exc:  # a name too long for the file system, and the like
        raise ModelError("urdf", f"cannot be read: {exc.strerror or exc}") from None
    if not found:
        raise ModelError("urdf", f"file not found: {path}")
    try:
        description = description_from_urdf(path, base_link=section.base_link, tip_link=section.tip_link,
                                            gravity=tuple(section.gravity))
        return chain_plant(description, source=f"URDF {path.name}", **options)
    except ModelError as exc:  # whatever the URDF's fault, the line to fix is plant.urdf
        raise ModelError("urdf", str(exc)) from None


def _transfer_function(section: TransferFunctionPlantSpec, base_dir: Path | None) -> PlantBase:
    from designkit.models.linear_plant import transfer_function_plant

    return transfer_function_plant(section.num, section.den, section.parameters, units=section.units,
                                   input=section.input, output=section.output, dt=section.dt)


def _state_space(section: StateSpacePlantSpec, base_dir: Path | None) -> PlantBase:
    from designkit.models.linear_plant import state_space_plant

    return state_space_plant(section.A, section.B, section.C, section.D, section.parameters, states=section.states,
                             inputs=section.inputs, outputs=section.outputs, units=section.units, dt=section.dt)


BUILDERS: dict[str, Callable[[Any, Path | None], PlantBase]] = {
    "link": _link,
    "robot": _robot,
    "elastic_joint": _elastic,
    "transfer_function": _transfer_function,
    "state_space": _state_space,
}
"""Plant kind -> builder ``(section, base_dir) -> Plant``."""


def check_uncertainty(plant: PlantBase, uncertainty: Any, path: str = "plant.uncertainty") -> None:
    """Every interval of ``uncertainty`` names a parameter of ``plant`` and has valid bounds."""
    for name, (lo, hi) in uncertainty.intervals.items():
        try:
            plant.with_params(**{name: lo})
            plant.with_params(**{name: hi})
        except ModelError as exc:
            raise SpecError(f"{path}.{name}", exc.message) from None


def plant_from_spec(section: Any, base_dir: str | Path | None = None) -> PlantBase:
    """The nominal plant of a spec's ``plant`` section.

    Parameters
    ----------
    section : LinkPlantSpec, RobotPlantSpec or ElasticJointPlantSpec
        The validated section.
    base_dir : path-like, optional
        Folder of the spec file; a relative ``urdf`` path is resolved against it.

    Raises
    ------
    SpecError
        With the key path under ``plant`` (unknown robot or parameter, URDF not found or not a
        serial chain, a parameter or uncertainty bound out of range).
    """
    base = Path(base_dir) if base_dir is not None else None
    try:
        plant = BUILDERS[section.kind](section, base)
    except ModelError as exc:
        raise SpecError(f"plant.{exc.field}" if exc.field else "plant", exc.message) from None
    if section.uncertainty is not None:
        check_uncertainty(plant, section.uncertainty)
    return plant
