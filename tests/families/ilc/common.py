"""Specs shared by the learning family's tests."""

from __future__ import annotations

from pathlib import Path

SPECS = Path(__file__).resolve().parents[3] / "specs"
EXAMPLE = SPECS / "ilc-simnog.yaml"
DIVERGING = SPECS / "ilc-simnog-diverging.yaml"


def arm_spec(controller: str = "{kind: ilc, poles: [-10, -10]}", *, duration: float = 0.5, dt: float = 0.001,
             extra: str = "", plant: str = "{kind: robot, robot: planar2r}", requirements: str = "",
             trajectory: str = "{kind: quintic, amplitude: [1.0, -0.5], duration: 0.4}",
             numerics: str = "{compile: never}") -> str:
    """A short two-link spec (interpreted step: no compilation in the tests)."""
    return (f"name: ilc-test\nplant: {plant}\ncontroller: {controller}\n{requirements}"
            f"numerics: {numerics}\n"
            f"simulation: {{duration: {duration}, dt: {dt}, trajectory: {trajectory}{extra}}}\n")
