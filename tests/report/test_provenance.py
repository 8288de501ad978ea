"""Provenance: designkit version, git commit and dirty flag, Python, OS, command line; stable mode."""

from __future__ import annotations

import shutil
import subprocess

import pytest

from designkit.report import provenance as prov


def test_rows_name_version_python_os_and_command_line(monkeypatch):
    monkeypatch.delenv(prov.STABLE_ENV, raising=False)
    rows = dict(prov.provenance_rows(["/usr/local/bin/designkit", "synth", "specs/a b.yaml"]))
    assert rows["designkit"] == prov.designkit_version()
    assert rows["Python"].split()[-1].count(".") == 2
    assert rows["operating system"]
    assert rows["command line"] == "designkit synth 'specs/a b.yaml'"  # shell-quoted, program by its name only


def test_stable_mode_leaves_out_what_changes_with_every_commit(monkeypatch):
    monkeypatch.setenv(prov.STABLE_ENV, "stable")
    rows = dict(prov.provenance_rows(["designkit", "synth", "x.yaml"]))
    assert "git commit" not in rows and "uncommitted changes" not in rows
    assert "x.yaml" not in rows["command line"]
    assert rows == dict(prov.provenance_rows(["other", "args"]))  # same report whatever the invocation


def test_git_state_of_a_checkout(tmp_path):
    if shutil.which("git") is None:
        pytest.skip("git is not installed")
    pkg = tmp_path / "repo" / "pkg"
    pkg.mkdir(parents=True)
    (pkg / "__init__.py").write_text("x = 1\n")

    def git(*args):
        subprocess.run(["git", *args], cwd=tmp_path / "repo", check=True, capture_output=True)

    git("init", "-q")
    git("add", ".")
    git("-c", "user.name=t", "-c", "user.email=t@t", "commit", "-q", "-m", "c")
    prov.git_state.cache_clear()
    commit, dirty = prov.git_state(str(pkg))
    assert len(commit) == 40 and dirty is False
    (tmp_path / "repo" / "elsewhere.txt").write_text("regenerated report\n")
    git("add", "elsewhere.txt")
    prov.git_state.cache_clear()
    assert prov.git_state(str(pkg))[1] is False  # changes outside the package do not count
    (pkg / "__init__.py").write_text("x = 2\n")
    prov.git_state.cache_clear()
    assert prov.git_state(str(pkg)) == (commit, True)
    prov.git_state.cache_clear()


def test_no_git_or_no_checkout_is_no_error(tmp_path, monkeypatch):
    prov.git_state.cache_clear()
    assert prov.git_state(str(tmp_path)) is None  # not a checkout
    monkeypatch.setenv("PATH", str(tmp_path))  # no git at all
    prov.git_state.cache_clear()
    assert prov.git_state(str(tmp_path)) is None
    rows = dict(prov.provenance_rows(["designkit"], stable=False))
    assert "git commit" not in rows
    prov.git_state.cache_clear()


def test_report_shows_provenance_and_is_reproducible(servo_result, monkeypatch):
    from designkit.report.html import render_html
    from designkit.report.model import build_report_model

    monkeypatch.delenv(prov.STABLE_ENV, raising=False)
    # same inputs, same process: same bytes
    first = render_html(build_report_model(servo_result, studies=False))
    assert render_html(build_report_model(servo_result, studies=False)) == first
    for name, value in prov.provenance_rows():
        assert f"<th>{name}</th><td class=\"mono hash\">{value}</td>".replace("'", "&#39;") in first
