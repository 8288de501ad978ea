"""A spec section chosen by its ``kind`` among the registered families', validated by that family's model alone.

The spec's ``controller`` (and each entry of a comparison's ``controllers``) is one of the families' sections.
A discriminated union of every family's model would import every family to validate any spec; :class:`ByKind`
validates the same way -- the same errors at the same key paths, an unknown or missing ``kind`` reported as
pydantic reports a discriminated union's (``union_tag_invalid``, ``union_tag_not_found``) -- while importing only
the family the section names (:data:`designkit.families.FAMILIES` looks a family up by its kind).  The union of
every member, for the JSON Schema and the ranges table, is :meth:`ByKind.union`.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import cache
from typing import Annotated, Any, Union

from pydantic import BaseModel, Field
from pydantic_core import PydanticKnownError, core_schema

from designkit.families import FAMILIES

__all__ = ["ByKind"]


class ByKind:
    """Pydantic metadata (``Annotated[Section, ByKind(model_of)]``): a mapping validated by the model of its kind.

    Parameters
    ----------
    model_of : callable
        ``kind -> model class``: the section model of a registered kind (imports that family only).
    """

    def __init__(self, model_of: Callable[[str], type[BaseModel]]) -> None:
        self.model_of = cache(model_of)

    def union(self) -> Any:
        """The discriminated union of every registered kind's model (imports every family)."""
        return Annotated[Union[tuple(self.model_of(k) for k in FAMILIES)], Field(discriminator="kind")]  # noqa: UP007

    def validate(self, value: Any) -> BaseModel:
        """``value`` (a mapping, or a section model) validated by the model its ``kind`` names."""
        if isinstance(value, BaseModel):
            kind = getattr(value, "kind", None)
            if isinstance(kind, str) and kind in FAMILIES and isinstance(value, self.model_of(kind)):
                return value
            value = value.model_dump()
        if not isinstance(value, dict):
            raise PydanticKnownError("model_attributes_type")
        if "kind" not in value:
            raise PydanticKnownError("union_tag_not_found", {"discriminator": "'kind'"})
        kind = value["kind"]
        if not isinstance(kind, str) or kind not in FAMILIES:
            expected = ", ".join(repr(k) for k in FAMILIES)
            raise PydanticKnownError("union_tag_invalid", {"discriminator": "'kind'", "tag": str(kind),
                                                           "expected_tags": expected})
        return self.model_of(kind).model_validate(value)

    def __get_pydantic_core_schema__(self, source: Any, handler: Any) -> core_schema.CoreSchema:
        return core_schema.no_info_plain_validator_function(self.validate)
