"""Spec format (pydantic models) and YAML loading."""

from designkit.spec.loader import LoadedSpec, load_spec, parse_spec
from designkit.spec.schema import Spec

__all__ = ["LoadedSpec", "Spec", "load_spec", "parse_spec"]
