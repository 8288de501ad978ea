"""Report section and JSON (placeholder)."""

from typing import Any


def section(result: Any) -> Any:
    return None


def json(result: Any) -> dict:
    return {}
