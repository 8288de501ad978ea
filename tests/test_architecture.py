"""The shape of the source tree: module size, and the layer contract's configuration (import-linter runs in CI)."""

from __future__ import annotations

import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src" / "designkit"
MAX_LINES = 600


def test_no_module_exceeds_the_size_limit():
    sizes = {str(p.relative_to(SRC)): len(p.read_text().splitlines()) for p in SRC.rglob("*.py")}
    over = {name: n for name, n in sizes.items() if n > MAX_LINES}
    assert not over, f"modules over {MAX_LINES} lines: {over}"


def test_every_package_is_in_the_layer_contract():
    """A new package must be placed in the layers (else import-linter would not check it)."""
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["importlinter"]
    (contract,) = [c for c in config["contracts"] if c["type"] == "layers"]
    named = {name.strip() for layer in contract["layers"] for name in layer.replace(":", "|").split("|")}
    modules = {p.name for p in SRC.iterdir() if p.is_dir() and (p / "__init__.py").exists()}
    modules |= {p.stem for p in SRC.glob("*.py") if p.stem != "__init__"}
    assert modules == named, (sorted(modules - named), sorted(named - modules))
