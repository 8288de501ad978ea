"""The contract of bad input through ``designkit synth``, shared by the tests of every family."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from designkit.cli import main


def assert_bad_input(tmp_path: Path, capsys, text: str, message: str, extra: Sequence[str] = ()) -> None:
    """``designkit synth`` on ``text`` (with the options ``extra``) exits 2 with one line on stderr containing
    ``message`` (the key path and the problem), no traceback, nothing on stdout and nothing written."""
    spec = tmp_path / "spec.yaml"
    spec.write_text(text)
    out = tmp_path / "out"
    code = main(["synth", str(spec), "--out", str(out), *extra])
    captured = capsys.readouterr()
    assert code == 2, captured
    assert message in captured.err
    assert captured.err.startswith("designkit: error: ")
    assert captured.err.count("\n") == 1 and "Traceback" not in captured.err
    assert captured.out == ""
    assert not out.exists() or not any(out.rglob("*"))
