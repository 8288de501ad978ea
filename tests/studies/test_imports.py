"""The studies reach the families only through the registry and what a ``Family`` declares: no module under
``src/designkit/studies/`` imports a family's module (``designkit.families.<x>``), at module level or inside a
function, nor names one for a dynamic import."""

from __future__ import annotations

import ast
from pathlib import Path

import designkit.studies as studies
from designkit.families import FAMILIES

STUDIES_DIR = Path(studies.__file__).resolve().parent


def _offences(path: Path) -> list[str]:
    out = []
    for node in ast.walk(ast.parse(path.read_text())):  # every node: imports inside functions included
        if isinstance(node, ast.Import):
            out += [a.name for a in node.names if a.name.startswith("designkit.families.")]
        elif isinstance(node, ast.ImportFrom) and node.module:
            if node.module.startswith("designkit.families."):
                out.append(node.module)
            elif node.module == "designkit.families":  # the registry: its functions, never a family module
                out += [f"designkit.families.{a.name}" for a in node.names if a.name in FAMILIES or
                        (STUDIES_DIR.parent / "families" / a.name).exists() or
                        (STUDIES_DIR.parent / "families" / f"{a.name}.py").exists()]
        elif isinstance(node, ast.Constant) and isinstance(node.value, str) and \
                node.value.startswith("designkit.families."):
            out.append(node.value)
    return out


def test_no_study_module_imports_a_family_module():
    found = {str(p.relative_to(STUDIES_DIR)): _offences(p) for p in sorted(STUDIES_DIR.rglob("*.py"))}
    assert len(found) > 10  # the scan sees the studies
    assert {k: v for k, v in found.items() if v} == {}


def test_the_scan_catches_an_import_inside_a_function(tmp_path):
    planted = tmp_path / "planted.py"
    planted.write_text("def f():\n    from designkit.families.vsc.surface import reduced_poles\n"
                       "    return reduced_poles\n"
                       "def g():\n    import designkit.families.mrac.laws\n"
                       "from designkit.families import family, mrac\n")
    assert sorted(_offences(planted)) == ["designkit.families.mrac", "designkit.families.mrac.laws",
                                          "designkit.families.vsc.surface"]
