"""The registry is the single registration point: every table that depends on the kind is derived from it."""

from __future__ import annotations

import ast
import json
from pathlib import Path

import pytest

from designkit.errors import SpecError
from designkit.families import FAMILIES, family
from designkit.schema.loader import _UNION_TAGS, parse_spec
from designkit.schema.spec import Spec
from designkit.synthesis.family import Family
from designkit.verification.suite import GENERIC, CheckRule

SRC = Path(__file__).resolve().parents[2] / "src" / "designkit"


def test_every_module_registers_one_family():
    modules = sorted(p.stem for p in (SRC / "families").glob("*.py") if not p.stem.startswith("_"))
    modules = sorted([*modules, *(p.parent.name for p in (SRC / "families").glob("*/__init__.py"))])
    assert sorted(FAMILIES) == modules  # one module, one kind, named alike
    assert all(isinstance(f, Family) for f in FAMILIES.values())


def test_schema_union_loader_tags_and_checks_are_derived_from_the_registry():
    schema = json.dumps(Spec.model_json_schema())
    for kind, fam in FAMILIES.items():
        assert f'"const": "{kind}"' in schema or f'"enum": ["{kind}"]' in schema, kind
        assert kind in _UNION_TAGS
        assert all(c in GENERIC if isinstance(c, str) else isinstance(c, CheckRule) for c in fam.checks)
        assert fam.display.label and fam.display.law
        assert fam.spec.model_fields["kind"].annotation.__args__ == (kind,)


def test_no_kind_string_outside_its_family_module():
    """A family's kind is written in its own module only (the rest of the code asks the registry)."""
    for path in SRC.rglob("*.py"):
        if "families" in path.relative_to(SRC).parts:
            continue
        tree = ast.parse(path.read_text())
        strings = {n.value for n in ast.walk(tree) if isinstance(n, ast.Constant) and isinstance(n.value, str)}
        assert not strings & set(FAMILIES), (path, strings & set(FAMILIES))


def test_unknown_kind_is_bad_input():
    with pytest.raises(SpecError) as info:
        family("sliding_magic")
    assert info.value.path == "controller.kind"
    with pytest.raises(SpecError) as info:
        parse_spec("name: x\nplant: {kind: link, Km: 1, tau: 1}\ncontroller: {kind: sliding_magic}\n")
    assert info.value.path == "controller.kind"
