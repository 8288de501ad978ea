"""Helpers shared by the sliding-mode family's tests."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]
LINK_SPEC = ROOT / "specs" / "sliding-mode-link.yaml"
WEAK_SPEC = ROOT / "specs" / "sliding-mode-weak-switching.yaml"
BOX = {"Km": (1.4, 2.6), "tau": (0.35, 0.65)}
"""The example's box: the POSSPEED link within 30 % of Km = 2, tau = 0.5."""


def spec_text(path: Path = LINK_SPEC, drop: tuple[str, ...] = (), **controller: object) -> str:
    """The spec at ``path`` with ``controller`` keys added (YAML values as written) and lines starting with any
    of ``drop`` removed."""
    lines = [ln for ln in path.read_text().splitlines(keepends=True) if not ln.strip().startswith(drop or ("\0",))]
    text = "".join(lines)
    extra = "".join(f"  {k}: {v}\n" for k, v in controller.items())
    return text.replace("  margin: 0.2\n", "  margin: 0.2\n" + extra)


def run_text(text: str):
    """The pipeline's result for spec ``text``."""
    from designkit.pipeline import run
    from designkit.schema.loader import parse_spec

    return run(parse_spec(text))


def check(result, name: str):
    """The check ``name`` of ``result``."""
    return next(c for c in result.checks if c.name == name)
