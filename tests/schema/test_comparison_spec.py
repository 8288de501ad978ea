"""Comparison specs (``controllers:``): the form, the key paths of bad input, the JSON Schema."""

from __future__ import annotations

import json

import jsonschema
import pytest

from designkit.cli import main
from designkit.errors import SpecError
from designkit.schema.comparison import ComparisonSpec, json_schema
from designkit.schema.loader import parse_spec
from designkit.schema.spec import Spec

HEAD = ("name: cmp\nplant: {kind: link, Km: 2.0, tau: 0.5}\n"
        "simulation: {duration: 8, trajectory: {kind: square, amplitude: 0.5, period: 4}}\n")
MRAC = "{kind: mrac, poles: [-4, -5], gamma: 10000, Q: [1, 0.1]"
STR = "{kind: self_tuning, sampling_period: 0.01, estimator: speed, forgetting: 0.99, poles: [-4, -5]"


def _error(text: str) -> SpecError:
    with pytest.raises(SpecError) as info:
        parse_spec(HEAD + text)
    return info.value


def test_a_comparison_is_read_with_labels_and_members():
    loaded = parse_spec(HEAD + f"controllers: [{MRAC}}}, {STR}, label: str}}]\n")
    assert isinstance(loaded.spec, ComparisonSpec) and loaded.is_comparison
    assert loaded.spec.labels == ("mrac", "str")
    members = loaded.members()
    assert [label for label, _ in members] == ["mrac", "str"]
    alone = parse_spec(HEAD.replace("name: cmp", "name: mrac") + f"controller: {MRAC}}}\n").spec
    assert members[0][1].spec == alone  # the member is the single-controller spec, label dropped
    assert members[0][1].path == loaded.path


@pytest.mark.parametrize(("text", "path", "words"), [
    ("controllers: []\n", "controllers", "at least 2"),
    (f"controllers: [{MRAC}}}]\n", "controllers", "at least 2"),
    ("controllers: [" + ", ".join([f"{MRAC}, label: c{k}}}" for k in range(7)]) + "]\n", "controllers", "at most 6"),
    (f"controller: {MRAC}}}\ncontrollers: [{MRAC}}}, {STR}}}]\n", "controllers", "not both"),
    (f"controllers: [{MRAC}}}, {MRAC.replace('10000', '-1')}, label: b}}]\n", "controllers[1].gamma", ""),
    (f"controllers: [{MRAC}}}, {STR}, zzz: 1}}]\n", "controllers[1].zzz", "unknown key"),
    (f"controllers: [{MRAC}}}, {{kind: nope}}]\n", "controllers[1].kind", "does not match"),
    (f"controllers: [{MRAC}}}, {MRAC}}}]\n", "controllers[1].label", "distinct label"),
    (f"controllers: [{MRAC}}}, {STR}, label: 'a b'}}]\n", "controllers[1].label", ""),
    ("controllers: {a: 1}\n", "controllers", ""),
])
def test_bad_comparisons_name_their_key_path(text, path, words):
    err = _error(text)
    assert err.path == path, str(err)
    assert words in err.message


def test_a_family_rule_inside_an_entry_names_the_entry():
    # the decentralized PID is designed for a robot, not a link: the family's rule, with the entry's path
    err = _error(f"controllers: [{MRAC}}}, {{kind: decentralized_pid, poles: [-4, -5, -20], zero: -3}}]\n")
    assert err.path.startswith("controllers[1]"), str(err)


def test_single_specs_are_unchanged():
    loaded = parse_spec(HEAD + f"controller: {MRAC}}}\n")
    assert isinstance(loaded.spec, Spec) and not loaded.is_comparison
    with pytest.raises(SpecError, match="not a comparison"):
        loaded.members()
    with pytest.raises(SpecError) as info:
        parse_spec(HEAD)
    assert info.value.path == "controller"


def test_json_schema_forms(capsys):
    data = parse_spec(HEAD + f"controllers: [{MRAC}}}, {STR}, label: str}}]\n").spec.model_dump(mode="json")
    jsonschema.validate(data, json_schema("comparison"))
    jsonschema.validate(data, json_schema("any"))
    single = parse_spec(HEAD + f"controller: {MRAC}}}\n").spec.model_dump(mode="json")
    jsonschema.validate(single, json_schema("any"))
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate(data, json_schema("single"))
    assert main(["schema", "--form", "comparison"]) == 0
    schema = json.loads(capsys.readouterr().out)
    assert {"plant", "controllers"} <= set(schema["required"])
    assert "label" in json.dumps(schema)
