"""write_report: layout, overwrite, atomicity on failure."""

from __future__ import annotations

import os
import stat

import pytest

import designkit.report.writer as writer
from designkit.report import ReportFiles, build_report_model, write_report


@pytest.fixture(scope="module")
def written(servo_result, tmp_path_factory) -> ReportFiles:
    return write_report(servo_result, tmp_path_factory.mktemp("reports"), studies=False)


def test_report_files_layout(written):
    assert written.html.name == "report.html" and written.pdf.name == "report.pdf"
    assert written.html.parent.name == "report-servo" == written.pdf.parent.name
    assert written.html.read_text(encoding="utf-8").startswith("<!DOCTYPE html>")
    assert written.pdf.read_bytes().startswith(b"%PDF")
    assert sorted(p.name for p in written.html.parent.iterdir()) == ["report.html", "report.pdf"]
    assert stat.S_IMODE(written.html.stat().st_mode) == 0o644


def test_rewriting_replaces_both_files(written, failed_result):
    files = write_report(failed_result, written.html.parent.parent, studies=False)
    assert files == written
    assert "FAILED: Overshoot" in files.html.read_text(encoding="utf-8")
    assert sorted(p.name for p in files.html.parent.iterdir()) == ["report.html", "report.pdf"]


def _snapshot(files: ReportFiles) -> tuple[bytes, bytes]:
    return files.html.read_bytes(), files.pdf.read_bytes()


def test_pdf_failure_leaves_the_old_report_untouched(servo_result, tmp_path, monkeypatch):
    files = write_report(servo_result, tmp_path, studies=False)
    before = _snapshot(files)

    def boom(model):
        raise RuntimeError("typst exploded")

    monkeypatch.setattr(writer, "compile_pdf", boom)
    with pytest.raises(RuntimeError, match="typst exploded"):
        write_report(servo_result, tmp_path, studies=False)
    assert _snapshot(files) == before
    assert sorted(p.name for p in files.html.parent.iterdir()) == ["report.html", "report.pdf"]


def test_failure_while_writing_leaves_the_old_report_and_no_temp_files(servo_result, tmp_path, monkeypatch):
    files = write_report(servo_result, tmp_path, studies=False)
    before = _snapshot(files)
    real_stage = writer._stage
    calls = []

    def stage_then_fail(folder, name, data):
        calls.append(name)
        if name == "report.pdf":
            raise OSError("disk full")
        return real_stage(folder, name, data)

    monkeypatch.setattr(writer, "_stage", stage_then_fail)
    with pytest.raises(OSError, match="disk full"):
        write_report(servo_result, tmp_path, studies=False)
    assert calls == ["report.html", "report.pdf"]
    assert _snapshot(files) == before
    assert sorted(p.name for p in files.html.parent.iterdir()) == ["report.html", "report.pdf"]


def test_partial_write_of_a_staged_file_is_cleaned_up(tmp_path, monkeypatch):
    real_fdopen = os.fdopen

    def fdopen(fd, mode="r", *args, **kwargs):
        fh = real_fdopen(fd, mode, *args, **kwargs)

        class Wrapper:
            def __enter__(self):
                return self

            def __exit__(self, *exc):
                fh.close()
                return False

            def write(self, data):
                fh.write(data[:10])
                raise OSError("no space left")

            def __getattr__(self, name):
                return getattr(fh, name)

        return Wrapper()

    monkeypatch.setattr(writer.os, "fdopen", fdopen)
    with pytest.raises(OSError, match="no space left"):
        writer._stage(tmp_path, "report.pdf", b"x" * 100)
    assert list(tmp_path.iterdir()) == []


def test_model_name_is_the_folder(servo_result, tmp_path):
    files = write_report(servo_result, tmp_path / "new" / "nested", studies=False)
    assert files.html.parent == tmp_path / "new" / "nested" / build_report_model(servo_result, studies=False).name


@pytest.mark.parametrize("name", ["", ".", "..", "a/b", "a\\b"])
def test_unsafe_folder_names_are_refused(tmp_path, name):
    with pytest.raises(ValueError, match="folder name"):
        writer._report_folder(tmp_path, name)
