"""The boundary rules of ``designkit.arguments``: what each kind of argument accepts, converts and refuses."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from designkit import arguments
from designkit.errors import ModelError, OutputError, SpecError


class Named(str):
    pass


def test_text_is_read_as_a_plain_str():
    out = arguments.text(Named("planar2r"), "name")
    assert out == "planar2r" and type(out) is str


@pytest.mark.parametrize(("value", "words"), [
    (b"x", "got bytes"), (None, "got NoneType"), ("a\0b", "NUL character at character 1"),
    ("ok\udcff", "lone surrogate at character 2"), (Path("x"), "got PosixPath"),
])
def test_text_refuses(value, words):
    with pytest.raises(SpecError) as info:
        arguments.text(value, "name")
    assert info.value.path == "name" and words in info.value.message


def test_empty_text_when_it_must_not_be():
    assert arguments.text("", "x") == ""
    with pytest.raises(SpecError, match="must not be empty"):
        arguments.text("  ", "x", empty=False)


def test_paths():
    assert arguments.path("a/b", "p") == Path("a/b")
    assert arguments.path(Path("c"), "p") == Path("c")
    for value, words in ((b"a", "got bytes"), ("", "empty path"), ("a\0", "NUL"), ("\ud800", "surrogate"), (3, "int")):
        with pytest.raises(OutputError) as info:
            arguments.path(value, "out_dir", error=OutputError)
        assert info.value.path == "out_dir" and words in info.value.message


def test_a_pathlike_of_bytes_or_one_that_fails():
    class BytesPath:
        def __fspath__(self):
            return b"x"

    class Broken:
        def __fspath__(self):
            raise RuntimeError("no")

    for value, words in ((BytesPath(), "of bytes"), (Broken(), "__fspath__ failed")):
        with pytest.raises(SpecError, match=words):
            arguments.path(value, "path")


def test_integers():
    assert arguments.integer(np.int32(7), "n", low=1, high=7) == 7
    for value in (1.0, 1.5, True, "2", None, math.nan):
        with pytest.raises(SpecError, match="must be an integer, got"):
            arguments.integer(value, "n")
    for value in (0, 8, 10**400):
        with pytest.raises(SpecError, match="from 1 to 7"):
            arguments.integer(value, "n", low=1, high=7)


def test_numbers():
    assert arguments.number(3, "x") == 3.0 and arguments.number(np.float32(0.5), "x") == 0.5
    assert arguments.number(math.inf, "x", finite=False) == math.inf
    cases = [(math.nan, {}, "finite"), (math.inf, {}, "finite"), (0.0, {"positive": True}, "positive"),
             (-1.0, {"low": 0.0}, "at least 0"), (2.0, {"high": 1.0}, "at most 1"), (True, {}, "real number"),
             (1j, {}, "real number"), ("1", {}, "real number"), (10**400, {}, "floating-point size")]
    for value, options, words in cases:
        with pytest.raises(ModelError) as info:
            arguments.number(value, "Km", error=ModelError, **options)
        assert info.value.path == "Km" and words in info.value.message, (value, info.value.message)


def test_flags_and_choices():
    assert arguments.flag(np.bool_(True), "f") is True and arguments.flag(False, "f") is False
    for value in (1, 0, "yes", None, np.int64(1)):
        with pytest.raises(SpecError, match="True or False"):
            arguments.flag(value, "f")
    assert arguments.choice(Named("process"), "engine", ("dask", "process")) == "process"
    with pytest.raises(SpecError, match="one of 'dask', 'process'"):
        arguments.choice("thread", "engine", ("dask", "process"))


def test_instances():
    assert arguments.instance(None, "plant", int, "an int", optional=True) is None
    assert arguments.instance(3, "plant", int, "an int") == 3
    with pytest.raises(SpecError, match="must be an int, got str"):
        arguments.instance("3", "plant", int, "an int")
