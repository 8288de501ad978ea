"""Helpers shared by the vsc family's tests."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]
ELASTIC_SPEC = ROOT / "specs" / "vsc-elastic-joint.yaml"
LINK_SPEC = ROOT / "specs" / "vsc-link.yaml"
NARROW_SPEC = ROOT / "specs" / "vsc-elastic-joint-narrow-gains.yaml"
ELASTIC_BOX = {"J2": (0.45, 0.55), "Km": (1.8, 2.2)}
LINK_BOX = {"Km": (1.4, 2.6), "tau": (0.35, 0.65)}


def run_text(text: str):
    """The pipeline's result for spec ``text``."""
    from designkit.pipeline import run
    from designkit.schema.loader import parse_spec

    return run(parse_spec(text))


def check(result, name: str):
    """The check ``name`` of ``result``."""
    return next(c for c in result.checks if c.name == name)
