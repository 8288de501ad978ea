"""The package's explicit re-exports resolve to the checks themselves, and importing it stays light."""

from __future__ import annotations

import doctest
import importlib
import subprocess
import sys

import pytest

import designkit.verification as verification

HEAVY = ("cvxpy", "casadi", "scipy", "control", "matplotlib")


@pytest.mark.parametrize("name", verification.__all__)
def test_reexport_is_the_defining_modules_object(name):
    module = importlib.import_module(verification._EXPORTS[name])
    assert getattr(verification, name) is getattr(module, name)


def test_unknown_name_raises_attribute_error():
    with pytest.raises(AttributeError, match="no_such_check"):
        _ = verification.no_such_check


def test_docstring_examples():
    assert doctest.testmod(verification).failed == 0


@pytest.mark.parametrize("module", ["designkit.verification", "designkit.verification.check"])
def test_import_does_not_load_heavy_dependencies(module):
    code = f"import sys, {module}; print(','.join(m for m in {HEAVY!r} if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert out == ""
