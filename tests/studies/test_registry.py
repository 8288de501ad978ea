"""Studies are discovered: adding one is adding a module, no generic file changes."""

from __future__ import annotations

import ast
import sys
from pathlib import Path

import designkit.studies as studies
from designkit.studies.core.study import Study

SRC = Path(studies.__file__).resolve().parents[1]

EXTRA = '''
from designkit.studies.core.study import Study, StudyResult

STUDY = Study(name="planted", title="A planted study", order=99, applies=lambda result, family: True,
              run=lambda ctx: StudyResult("planted", "A planted study"))
'''


def test_a_study_module_dropped_in_the_package_is_discovered(tmp_path, monkeypatch):
    (tmp_path / "planted.py").write_text(EXTRA)
    monkeypatch.setattr(studies, "__path__", [*studies.__path__, str(tmp_path)])
    monkeypatch.syspath_prepend(str(tmp_path))
    try:
        found = studies._discover()
    finally:
        sys.modules.pop("designkit.studies.planted", None)
    assert "planted" in found and isinstance(found["planted"], Study)
    assert list(found)[-1] == "planted"  # report order: by ``order``
    assert {"arm", "gains", "boundary", "lab1"} <= set(found)


def test_no_module_outside_the_studies_names_a_study():
    """The report, the pipeline and the CLI lay out and carry what the registry returns; none names a study."""
    names = set(studies.STUDIES)
    offenders = []
    for path in SRC.rglob("*.py"):
        rel = path.relative_to(SRC).as_posix()
        if rel.startswith("studies/"):
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("designkit.studies."):
                module = node.module.split(".")[2]
                if module in names:
                    offenders.append(f"{rel} imports designkit.studies.{module}")
    assert not offenders, offenders


def test_a_study_is_found_by_name_without_importing_the_others():
    import subprocess

    code = ("import sys\nfrom designkit.studies import STUDIES\nassert 'lab2' in STUDIES and len(STUDIES) >= 6\n"
            "STUDIES['gains']\n"
            "print(sorted({m.split('.')[2] for m in sys.modules if m.startswith('designkit.studies.')}))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         env={"PYTHONPATH": str(SRC.parent), "PATH": "/usr/bin:/bin"}).stdout
    assert out.strip() == "['core', 'gains']"
