"""``designkit codegen`` refuses what ``designkit verify`` refuses, with the same line, exit 2, nothing written."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from designkit.cli import main

ROOT = Path(__file__).resolve().parents[1]


def _variant(tmp_path: Path, spec: str, changes: dict[str, object]) -> Path:
    doc = yaml.safe_load((ROOT / "specs" / f"{spec}.yaml").read_text())
    for key, value in changes.items():
        *parents, last = key.split(".")
        node = doc
        for part in parents:
            node = node.setdefault(part, {})
        node[last] = value
    path = tmp_path / "spec.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return path


@pytest.mark.parametrize(("spec", "changes", "flags", "key"), [
    ("posspeed-link", {"simulation.dt": 1000}, [], "simulation.dt"),
    ("posspeed-link", {"simulation.dt": 0.003, "simulation.sampling_period": 0.01}, [], "simulation.dt"),
    ("sliding-mode-link", {"controller.boundary_layer": 1e-12}, [], "controller.boundary_layer"),
    ("pid-sm-link", {"controller.epsilon": 1e-12}, [], "controller.epsilon"),
    ("posspeed-link", {}, ["--budget", "0.01"], "budget"),
    ("posspeed-link", {"requirements.max_control": [1.0, 2.0]}, [], "requirements.max_control"),
])
def test_codegen_refuses_what_verify_refuses(tmp_path, capsys, spec, changes, flags, key):
    path = _variant(tmp_path, spec, changes)
    assert main(["verify", str(path), "--jobs", "1", *flags]) == 2
    verify_err = capsys.readouterr().err
    out = tmp_path / "code"
    assert main(["codegen", str(path), "--out", str(out), *flags]) == 2
    captured = capsys.readouterr()
    assert captured.err == verify_err
    assert captured.err.startswith(f"designkit: error: {key}:") and captured.err.count("\n") == 1, captured.err
    assert captured.out == ""
    assert not out.exists()


def test_a_spec_verify_accepts_is_written(tmp_path, capsys):
    path = _variant(tmp_path, "posspeed-link", {"simulation.dt": 0.002})
    out = tmp_path / "code"
    assert main(["codegen", str(path), "--out", str(out)]) == 0
    assert sorted(p.suffix for p in (out / "posspeed-link").iterdir()) == [".c", ".h"]
