"""The shape of the source tree: module size, the layer contract's configuration (import-linter runs in CI), and
which modules may import a family."""

from __future__ import annotations

import ast
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


FAMILIES_DIR = SRC / "families"


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(SRC.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imported(path: Path) -> list[tuple[int, str]]:
    """``(line, module)`` of every import of ``path``: statements anywhere (inside functions too), relative ones
    resolved, ``from designkit.families import name`` counted as ``designkit.families.name``, and the lines of its
    doctests (``>>>``) that import."""
    tree = ast.parse(path.read_text())
    package = _module_name(path).split(".")
    if path.name != "__init__.py":
        package = package[:-1]
    found: list[tuple[int, str]] = []

    def collect(node: ast.AST, line: int | None = None) -> None:
        for n in ast.walk(node):
            where = line if line is not None else getattr(n, "lineno", 0)
            if isinstance(n, ast.Import):
                found.extend((where, a.name) for a in n.names)
            elif isinstance(n, ast.ImportFrom):
                base = package[:len(package) - n.level + 1] if n.level else []
                module = ".".join([*base, *([n.module] if n.module else [])])
                if module == "designkit.families":  # the registry's names, or family modules by name
                    found.extend((where, f"{module}.{a.name}") for a in n.names)
                else:
                    found.append((where, module))

    collect(tree)
    for n in ast.walk(tree):
        if isinstance(n, ast.Constant) and isinstance(n.value, str) and ">>>" in n.value:
            for k, text in enumerate(n.value.splitlines()):
                code = text.strip().removeprefix(">>>").strip() if text.strip().startswith(">>>") else ""
                if "import" in code:
                    try:
                        collect(ast.parse(code), n.lineno + k)
                    except SyntaxError:
                        continue
    return found


def _family_of(module: str) -> str | None:
    """The family package or module ``module`` belongs to (``designkit.families.<name>...``), or None (the registry
    ``designkit.families`` and the names it exports are no family's)."""
    parts = module.split(".")
    if parts[:2] != ["designkit", "families"] or len(parts) < 3:
        return None
    name = parts[2]
    return name if (FAMILIES_DIR / name).is_dir() or (FAMILIES_DIR / f"{name}.py").is_file() else None


def test_no_family_imports_another_and_only_the_families_import_a_family():
    """(a) A family's modules import no other family (what two families share lives below them: ``synthesis``,
    ``spec``); (b) outside ``designkit/families/`` a family module is never imported, only the registry
    ``designkit.families`` -- in code, inside functions, and in doctests."""
    offenders = []
    for path in sorted(SRC.rglob("*.py")):
        rel = path.relative_to(SRC).as_posix()
        own = _family_of(_module_name(path))
        for line, module in _imported(path):
            target = _family_of(module)
            if target is None or target == own:
                continue
            offenders.append(f"{rel}:{line} imports {module}")
    assert not offenders, "family modules imported across families or from outside them:\n" + "\n".join(
        dict.fromkeys(offenders))
