"""The on-disk cache of compiled report templates: same output, files keyed by content, never fatal."""

from __future__ import annotations

import os

import pytest

from designkit.report import html, pdf
from designkit.report.templates_cache import bytecode_cache


@pytest.fixture
def fresh_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("DESIGNKIT_CACHE_DIR", str(tmp_path))
    bytecode_cache.cache_clear()
    yield tmp_path / "templates"
    bytecode_cache.cache_clear()


def test_cached_templates_render_the_same_reports(fresh_cache, servo_model):
    first_html, first_typ = html.render_html(servo_model), pdf.render_typst(servo_model)
    files = sorted(p.name for p in fresh_cache.iterdir())
    assert len(files) == 2 and all(name.endswith(".cache") for name in files)  # one per template
    bytecode_cache.cache_clear()  # a new process: loads the compiled code from disk
    assert html.render_html(servo_model) == first_html
    assert pdf.render_typst(servo_model) == first_typ
    assert sorted(p.name for p in fresh_cache.iterdir()) == files


def test_a_corrupt_cache_file_is_recompiled(fresh_cache, servo_model):
    expected = html.render_html(servo_model)
    for p in fresh_cache.iterdir():
        p.write_bytes(b"not a jinja cache")
    bytecode_cache.cache_clear()
    assert html.render_html(servo_model) == expected


@pytest.mark.skipif(os.geteuid() == 0, reason="root can write a read-only folder")
def test_an_unwritable_cache_folder_is_not_used(tmp_path, monkeypatch, servo_model):
    tmp_path.chmod(0o500)
    monkeypatch.setenv("DESIGNKIT_CACHE_DIR", str(tmp_path / "sub"))
    bytecode_cache.cache_clear()
    try:
        assert bytecode_cache() is None
        assert "<html" in html.render_html(servo_model)
    finally:
        tmp_path.chmod(0o700)
        bytecode_cache.cache_clear()


def test_a_cache_path_that_is_a_file_is_not_used(tmp_path, monkeypatch, servo_model):
    (tmp_path / "templates").write_text("a file where the folder should be")
    monkeypatch.setenv("DESIGNKIT_CACHE_DIR", str(tmp_path))
    bytecode_cache.cache_clear()
    try:
        assert bytecode_cache() is None
        assert "<html" in html.render_html(servo_model)
    finally:
        bytecode_cache.cache_clear()
