"""The registry of a package's modules: names from the listing, a module imported when its name is looked up."""

from __future__ import annotations

import sys
from dataclasses import dataclass

import pytest

from designkit.discovery import Registry


@dataclass(frozen=True)
class Entry:
    name: str


def _package(tmp_path, monkeypatch, modules: dict[str, str]) -> str:
    """A package ``planted_registry`` under ``tmp_path`` with ``modules`` (name -> source); its name."""
    root = tmp_path / "planted_registry"
    root.mkdir()
    (root / "__init__.py").write_text("")
    for name, source in modules.items():
        if name.endswith("/"):
            (root / name).mkdir()
            (root / name / "__init__.py").write_text(source)
        else:
            (root / f"{name}.py").write_text(source)
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setitem(sys.modules, "test_discovery_entry", sys.modules[__name__])
    for key in [k for k in sys.modules if k.startswith("planted_registry")]:
        monkeypatch.delitem(sys.modules, key)
    return "planted_registry"


DECLARE = "from test_discovery_entry import Entry\nENTRY = Entry({name!r})\n"


def test_names_come_from_the_listing_and_only_the_looked_up_module_is_imported(tmp_path, monkeypatch):
    pkg = _package(tmp_path, monkeypatch, {
        "alpha": DECLARE.format(name="alpha"),
        "beta/": DECLARE.format(name="beta"),
        "gamma": "raise RuntimeError('imported')\n",  # importing it would fail: it must not be imported
        "_private": "raise RuntimeError('imported')\n",
        "core": "raise RuntimeError('imported')\n",
    })
    reg = Registry(pkg, "ENTRY", Entry, skip=("core",))
    assert list(reg) == ["alpha", "beta", "gamma"] and len(reg) == 3
    assert "gamma" in reg and "core" not in reg and "_private" not in reg and 3 not in reg
    assert not [m for m in sys.modules if m.startswith(f"{pkg}.")]
    assert reg["beta"] == Entry("beta")
    assert reg.get("alpha") == Entry("alpha")
    assert reg.loaded() == ("alpha", "beta")
    assert sorted(m for m in sys.modules if m.startswith(f"{pkg}.")) == [f"{pkg}.alpha", f"{pkg}.beta"]
    assert reg.get("delta") is None
    with pytest.raises(KeyError):
        reg["core"]
    with pytest.raises(RuntimeError, match="imported"):
        reg["gamma"]


def test_a_module_must_declare_its_value_under_its_own_name(tmp_path, monkeypatch):
    pkg = _package(tmp_path, monkeypatch, {"alpha": DECLARE.format(name="other"), "beta": "ENTRY = 3\n",
                                           "gamma": "X = 1\n"})
    reg = Registry(pkg, "ENTRY", Entry)
    with pytest.raises(TypeError, match="declares name 'other'"):
        reg["alpha"]
    with pytest.raises(TypeError, match="defines no ENTRY"):
        reg["beta"]
    with pytest.raises(TypeError, match="defines no ENTRY"):
        reg["gamma"]


def test_values_import_every_module(tmp_path, monkeypatch):
    pkg = _package(tmp_path, monkeypatch, {n: DECLARE.format(name=n) for n in ("b", "a", "c")})
    reg = Registry(pkg, "ENTRY", Entry)
    assert [e.name for e in reg.values()] == ["a", "b", "c"]
    assert reg.loaded() == ("a", "b", "c")
