"""Edge inputs carried to a verdict through the CLI, shared by the tests of every family.

Every run here holds NumPy's ``RuntimeWarning`` as an error (an overflow, an invalid value or a division by zero
that reaches the user is a bug), and asserts what no input may produce: a traceback or an internal error.
"""

from __future__ import annotations

import warnings
from pathlib import Path

from designkit.cli import main


def run_cli(tmp_path: Path, capsys, text: str, *, synth: bool = False) -> tuple[int, str, str]:
    """``designkit verify`` (or ``synth --out``) on the spec ``text``: ``(exit code, stdout, stderr)``.

    No ``RuntimeWarning`` is allowed (each is raised as an error, so it would end as an internal error), and
    stderr names no traceback, no internal error and no warning."""
    spec = tmp_path / "spec.yaml"
    spec.write_text(text)
    args = ["synth", str(spec), "--out", str(tmp_path / "out")] if synth else ["verify", str(spec)]
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        code = main(args)
    captured = capsys.readouterr()
    for word in ("Traceback", "internal error", "RuntimeWarning"):
        assert word not in captured.err, captured.err
    return code, captured.out, captured.err


def failed_line(out: str, check: str) -> str:
    """The ``FAIL <check>: <reason>`` line of the verdict in ``out`` (AssertionError when there is none)."""
    lines = [ln.strip() for ln in out.splitlines() if ln.strip().startswith(f"FAIL {check}:")]
    assert lines, f"no FAIL line for {check} in:\n{out}"
    return lines[0]


def assert_fails(tmp_path: Path, capsys, text: str, check: str, reason: str, *, synth: bool = False) -> str:
    """The spec ``text`` ends as exit 1 with ``check`` failed, its reason containing ``reason``; the output."""
    code, out, err = run_cli(tmp_path, capsys, text, synth=synth)
    assert code == 1, (out, err)
    assert reason in failed_line(out, check), out
    assert "NOT VERIFIED: " in out
    return out
