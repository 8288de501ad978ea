"""The model a model-based controller believes: the true plant, or the nominal robot changed as the spec says.

A spec's ``plant`` is the **true** plant the simulation runs; ``controller.model`` (optional) is
what the controller knows of it.  Without it the controller knows the true plant exactly; with it,
the model is the plant's nominal robot (its payload removed) with the written parameter values, an
assumed payload and friction switched as written (:class:`~designkit.spec.controllers.ControllerModel`).
"""

from __future__ import annotations

from typing import Any

from designkit.errors import ModelError, SpecError

__all__ = ["controller_model"]


def controller_model(plant: Any, section: Any, path: str = "controller.model") -> Any:
    """The controller's model of ``plant`` (see the module docstring).

    Raises
    ------
    SpecError
        A parameter the plant does not have (``controller.model.parameters.<name>``), a refused value, or a
        payload on a link the robot does not have (``controller.model.payload.link``).
    """
    if section is None:
        return plant
    base = plant.without_payload() if hasattr(plant, "without_payload") else plant
    try:
        model = base.with_params(**section.parameters)
    except ModelError as exc:
        raise SpecError(f"{path}.parameters.{exc.field}", exc.message) from None
    try:
        if section.payload is not None:
            if not hasattr(model, "with_payload"):
                raise ModelError("payload", f"a {model.kind} plant carries no payload")
            model = model.with_payload(section.payload.mass, section.payload.link)
        if section.friction is not None:
            if not hasattr(model, "with_options"):
                raise ModelError("friction", f"a {model.kind} plant has no friction option")
            model = model.with_options(friction=section.friction)
    except ModelError as exc:
        raise SpecError(f"{path}.{exc.field}", exc.message) from None
    return model
