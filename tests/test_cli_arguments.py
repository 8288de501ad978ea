"""Bad command-line arguments: one line ``designkit: error: <argument>: <reason>``, exit 2, on every subcommand."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from designkit.cli import build_parser, main

ROOT = Path(__file__).resolve().parents[1]
SPEC = str(ROOT / "specs" / "posspeed-link.yaml")


def _refused(capsys, argv: list[str]) -> str:
    with pytest.raises(SystemExit) as exc:
        main(argv)
    captured = capsys.readouterr()
    assert exc.value.code == 2, captured
    assert captured.out == ""
    assert captured.err.count("\n") == 1, captured.err
    assert "usage:" not in captured.err
    return captured.err.rstrip("\n")


@pytest.mark.parametrize(("argv", "prefix"), [
    (["sweep", SPEC, "--samples", "x"], "--samples: must be an integer, got 'x'"),
    (["sweep", SPEC, "--samples", "1.5"], "--samples: must be an integer"),
    (["sweep", SPEC, "--samples", "1e3"], "--samples: must be an integer"),
    (["sweep", SPEC, "--samples"], "--samples: expected one argument"),
    (["sweep", SPEC], "--samples: required"),
    (["sweep"], "spec: required"),
    (["sweep", SPEC, "--samples", "5", "--seed", "s"], "--seed: must be an integer"),
    (["sweep", SPEC, "--samples", "5", "--workers", "two"], "--workers: must be an integer"),
    (["sweep", SPEC, "--samples", "5", "--chunk", "0.5"], "--chunk: must be an integer"),
    (["sweep", SPEC, "--samples", "5", "--bogus", "3"], "--bogus: unrecognized argument"),
    (["sweep", SPEC, "--samples", "5", "--sa", "5"], "--sa: unrecognized argument"),
    (["synth", SPEC, "--jobs", "3"], "--jobs: must be 1 or 2, got '3'"),
    (["synth", SPEC, "--budget", "-1"], "--budget: must be a positive number of seconds"),
    (["synth", SPEC, "--budget", "nan"], "--budget: must be a positive number of seconds"),
    (["synth"], "spec: required"),
    (["verify", SPEC, "--jobs", "x"], "--jobs: must be 1 or 2"),
    (["verify", SPEC, "--budget", "soon"], "--budget: must be a number of seconds"),
    (["verify", SPEC, "--json=yes"], "--json: ignored explicit argument 'yes'"),
    (["simulate"], "spec: required"),
    (["simulate", SPEC, "--csv"], "--csv: expected one argument"),
    (["schema", "--form", "pair"], "--form: invalid choice: 'pair'"),
    (["codegen", SPEC, "--name"], "--name: expected one argument"),
    (["codegen", SPEC, "--out"], "--out: expected one argument"),
    (["model"], "robot: required"),
    (["bogus"], "COMMAND: invalid choice: 'bogus'"),
    ([], "COMMAND: required"),
])
def test_every_bad_argument_is_one_line_naming_it(capsys, argv, prefix):
    err = _refused(capsys, argv)
    assert err.startswith(f"designkit: error: {prefix}"), err


def test_every_subcommand_parser_answers_in_one_line():
    """Each subcommand's own parser has the one-line error (argparse builds them with the top parser's class)."""
    parser = build_parser()
    subs = next(a for a in parser._actions if a.dest == "command").choices
    assert set(subs) == {"synth", "verify", "simulate", "schema", "codegen", "sweep", "model", "tune"}
    for name, sub in subs.items():
        with pytest.raises(SystemExit) as exc:
            sub.parse_args(["--no-such-option"])
        assert exc.value.code == 2, name


def test_the_console_script_exits_2_with_one_line(tmp_path):
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    done = subprocess.run([sys.executable, "-m", "designkit.cli", "sweep", SPEC, "--samples", "ten"],
                          capture_output=True, text=True, env=env, timeout=120, cwd=tmp_path)
    assert done.returncode == 2
    assert done.stdout == ""
    assert done.stderr == "designkit: error: --samples: must be an integer, got 'ten'\n"
    assert not any(tmp_path.iterdir())


def test_help_still_prints_the_usage(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["sweep", "--help"])
    assert exc.value.code == 0
    assert capsys.readouterr().out.startswith("usage: designkit sweep")
