"""Which families accept which plant kinds: the JSON Schema says it, the README's table is in step with it, and the
loader behaves as both say (a listed pair is read, an unlisted one refused at ``controller.kind``)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from designkit.errors import SpecError
from designkit.schema.comparison import json_schema
from designkit.schema.loader import parse_spec

README = Path(__file__).resolve().parents[2] / "README.md"


def _readme_table() -> dict[str, list[str]]:
    text = README.read_text()
    block = text[text.index("| plant kind | families |"):].split("\n\n", 1)[0]
    rows = {}
    for line in block.splitlines()[2:]:
        kind, families = (cell.strip() for cell in line.strip("|").split("|"))
        rows[kind.strip("`")] = re.findall(r"`([a-z_]+)`", families)
    return rows


@pytest.mark.parametrize("form", ["single", "comparison", "any"])
def test_every_form_of_the_schema_lists_the_plant_kinds(form):
    schema = json_schema(form)
    by_plant = schema["x-families-by-plant-kind"]
    assert "vsc" in by_plant["transfer_function"] and "pid_tracking" in by_plant["state_space"]
    vsc = schema["$defs"]["VscSpecEntry" if form == "comparison" else "VscSpec"]
    assert "transfer_function" in vsc["x-plant-kinds"] and "Plant kinds:" in vsc["description"]


def test_the_readme_table_is_the_schemas():
    assert _readme_table() == json_schema("single")["x-families-by-plant-kind"]


PLANTS = {
    "transfer_function": "{kind: transfer_function, num: [1], den: [1, 1, 0]}",
    "elastic_joint": "{kind: elastic_joint}",
}


@pytest.mark.parametrize(("plant", "controller"), [
    ("transfer_function", "{kind: vsc, sliding_poles: [-5], relay_amplitude: 1.0}"),
    ("transfer_function", "{kind: pid_tracking, poles: [-5, -6, -7]}"),
    ("elastic_joint", "{kind: pid_tracking, poles: [-5, -6, -7]}"),
])
def test_the_loader_agrees(plant, controller):
    listed = json_schema("single")["x-families-by-plant-kind"][plant]
    kind = re.search(r"kind: (\w+)", controller).group(1)
    reference = ("trajectory: {kind: quintic, amplitude: 1.0, duration: 0.5}" if kind == "pid_tracking"
                 else "step: 1.0")
    text = f"name: x\nplant: {PLANTS[plant]}\ncontroller: {controller}\nsimulation: {{duration: 1.0, {reference}}}\n"
    if kind in listed:
        assert parse_spec(text).spec.controller.kind == kind
    else:
        with pytest.raises(SpecError) as info:
            parse_spec(text)
        assert info.value.path == "controller.kind"
