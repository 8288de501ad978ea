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


def test_every_kind_string_is_written_in_one_module_of_its_family():
    """A family's kind is written once, in one module of its own (the rest of the code asks the registry or
    imports the family's ``KIND``)."""
    where: dict[str, list[Path]] = {kind: [] for kind in FAMILIES}
    for path in SRC.rglob("*.py"):
        tree = ast.parse(path.read_text())
        strings = {n.value for n in ast.walk(tree) if isinstance(n, ast.Constant) and isinstance(n.value, str)}
        for kind in strings & set(FAMILIES):
            where[kind].append(path.relative_to(SRC))
    for kind, paths in where.items():
        assert len(paths) == 1, (kind, paths)
        assert paths[0].parts[0] == "families" and paths[0].with_suffix("").parts[1] == kind, (kind, paths)


def test_unknown_kind_is_bad_input():
    with pytest.raises(SpecError) as info:
        family("sliding_magic")
    assert info.value.path == "controller.kind"
    with pytest.raises(SpecError) as info:
        parse_spec("name: x\nplant: {kind: link, Km: 1, tau: 1}\ncontroller: {kind: sliding_magic}\n")
    assert info.value.path == "controller.kind"


def test_a_familys_own_checks_figures_and_sections_reach_the_pipeline_and_the_report_through_the_registry():
    """What a family brings from its own package is found by the shared code through FAMILIES and the check
    registry: its rules run (check_rules), its figures and sections are laid out (the report's builders), so
    adding such a family edits no generic module."""
    from designkit.families import check_rules
    from designkit.verification.suite import CheckRule, generic

    for kind, fam in FAMILIES.items():
        own = [c for c in fam.checks if isinstance(c, CheckRule)]
        resolved = check_rules(kind)
        assert all(rule in resolved for rule in own), kind
        assert not any(rule.name in generic() for rule in own), kind  # its own names, not a generic one's
    text = (SRC.parents[1] / "specs" / "sliding-mode-link.yaml").read_text()
    loaded = parse_spec(text)
    from designkit.pipeline import run
    from designkit.report.figures import design_figures
    from designkit.report.model import build_report_model

    result = run(loaded)
    fam = family(loaded.spec.controller.kind)
    own_figures = {f.filename for f in (draw(result) for draw in fam.figures) if f is not None}
    assert own_figures and own_figures <= {f.filename for f in design_figures(result)}
    own_rules = [r for r in fam.checks if isinstance(r, CheckRule)]
    assert all(any(r.owns(c.name) for c in result.checks) for r in own_rules)
    model = build_report_model(result, studies=False)
    assert [s.anchor for s in model.sections] == [s.anchor for s in (make(result) for make in fam.sections) if s]
