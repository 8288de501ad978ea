"""A run imports the family it designs with and no other: the registry looks a family up by its kind.

Each case runs the command line in a fresh interpreter (``designkit.cli.main``, so that the process ends through the
interpreter's normal exit) and reads ``sys.modules`` when the command has returned: every imported module under
``designkit.families`` is the registry itself or a module of the spec's family.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[2]
SPECS = ROOT / "specs"

_PROBE = r"""
import json, sys
from designkit.cli import main
codes = [main(argv) for argv in json.loads(sys.argv[1])]
print(json.dumps({"codes": codes, "modules": sorted(m for m in sys.modules if m.startswith("designkit."))}))
"""


def _modules_after(*commands: list[str]) -> tuple[list[int], list[str]]:
    """Exit codes of ``commands`` run one after the other in one fresh interpreter, and the designkit modules it
    imported."""
    src = str(ROOT / "src")
    env_path = [src, *(p for p in sys.path if p)]
    proc = subprocess.run([sys.executable, "-c", _PROBE, json.dumps(commands)], capture_output=True, text=True,
                          check=True, env={"PYTHONPATH": ":".join(env_path), "PATH": "/usr/bin:/bin",
                                           "HOME": str(Path.home()), "MPLBACKEND": "Agg"}, timeout=600)
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    return out["codes"], out["modules"]


def _families(modules: list[str]) -> set[str]:
    """The family modules among ``modules`` (the registry ``designkit.families`` left out)."""
    return {m for m in modules if m.startswith("designkit.families.")}


def _kind(spec: Path) -> str:
    return yaml.safe_load(spec.read_text())["controller"]["kind"]


def test_a_one_link_verify_and_synth_import_only_the_pid_servo(tmp_path):
    spec = SPECS / "posspeed-link.yaml"
    codes, modules = _modules_after(["verify", str(spec), "--jobs", "1"],
                                    ["synth", str(spec), "--out", str(tmp_path), "--no-studies", "--jobs", "1"])
    assert codes == [0, 0]
    assert (tmp_path / "posspeed-link" / "report.pdf").is_file()
    assert _families(modules) == {"designkit.families.pid_servo"}  # a one-module family: exactly that module
    assert "designkit.families" in modules


@pytest.mark.parametrize("name", ["mrac-link.yaml", "sliding-mode-link.yaml"])
def test_a_family_package_is_the_only_family_imported(name):
    spec = SPECS / name
    kind = _kind(spec)
    codes, modules = _modules_after(["verify", str(spec), "--jobs", "1"])
    assert codes[0] in (0, 1)
    families = _families(modules)
    assert f"designkit.families.{kind}" in families
    assert {m.split(".")[2] for m in families} == {kind}, sorted(families)


def test_the_schema_command_imports_every_family():
    codes, modules = _modules_after(["schema"])
    assert codes == [0]
    listed = sorted(p.stem if p.is_file() else p.name for p in (ROOT / "src" / "designkit" / "families").iterdir()
                    if not p.name.startswith("_") and (p.suffix == ".py" or (p / "__init__.py").is_file()))
    assert {m.split(".")[2] for m in _families(modules)} == set(listed)
