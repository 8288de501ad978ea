"""The ``sweep:`` section is read as the rest of the spec is: its numbers by the spec format's YAML reading, its
parameter boxes by ``plant.uncertainty``'s validator (same refusals, with the ``sweep.parameters.<name>`` path)."""

from __future__ import annotations

import pytest

from designkit.cli import main
from designkit.errors import SpecError
from designkit.pipeline import plant
from designkit.schema.loader import parse_spec
from designkit.sweep.section import parse_sweep
from tests.sweep.specs import SIMNOG, link, write


def test_exponent_numbers_are_floats_as_in_the_rest_of_the_spec():
    written = parse_sweep(SIMNOG + "sweep: {parameters: {m2: [2.6e0, 3.5e0]}, payload: {mass: [0, 1e0]}, cut: 2e0, "
                          "distribution: normal}\n")
    plain = parse_sweep(SIMNOG + "sweep: {parameters: {m2: [2.6, 3.5]}, payload: {mass: [0.0, 1.0]}, cut: 2.0, "
                        "distribution: normal}\n")
    assert written.section == plain.section
    assert written.section.parameters["m2"] == [2.6, 3.5]
    assert all(type(v) is float for v in written.section.parameters["m2"])
    assert written.section.cut == 2.0
    # the same text in plant.uncertainty reads the same numbers
    spec = parse_spec(SIMNOG.replace("{m2: [2.0, 4.0]}", "{m2: [2.6e0, 3.5e0]}")).spec
    assert spec.plant.uncertainty.intervals["m2"] == (2.6, 3.5)


def test_an_exponent_number_out_of_range_is_refused_as_a_number():
    from designkit.sweep.chunk import base

    with pytest.raises(SpecError) as exc:
        base(SIMNOG + "sweep: {parameters: {m2: [2, 1e7]}}\n", "<test>")
    with pytest.raises(SpecError) as plain:
        base(SIMNOG + "sweep: {parameters: {m2: [2, 10000000.0]}}\n", "<test>")
    assert exc.value.path == "sweep.parameters.m2"
    assert str(exc.value) == str(plain.value)
    assert str(exc.value).endswith("got [2.0, 10000000.0]")


def test_the_section_is_read_within_the_spec_format_s_limits():
    bomb = "".join(f"a{k}: &a{k} [" + ", ".join([f"*a{k - 1}"] * 10 if k else ["1"] * 10) + "]\n" for k in range(8))
    with pytest.raises(SpecError, match="more than 100,000 nodes"):
        parse_sweep(SIMNOG + "sweep:\n  parameters:\n" + "".join("    " + line + "\n" for line in bomb.splitlines()))


LINK = link()


@pytest.mark.parametrize(("text", "name", "box"), [
    (LINK, "tau", "[-1, 2]"),
    (LINK, "tau", "[0, 2]"),
    (LINK, "Km", "[0, 3]"),
    (LINK, "Km", "[-2, -1]"),
    (LINK, "Km", "[1e-9, 2]"),
    (LINK, "tau", "[1, 2e6]"),
    (SIMNOG, "m2", "[-1, 2]"),
])
def test_a_box_plant_uncertainty_refuses_is_refused_with_the_same_message(tmp_path, capsys, text, name, box):
    # what plant.uncertainty says of the same interval, through the design pipeline's own plant builder
    unc_text = (text.replace("uncertainty: {Km: [0.1, 1.0], tau: [0.5, 4.0]}", f"uncertainty: {{{name}: {box}}}")
                .replace("uncertainty: {m2: [2.0, 4.0]}", f"uncertainty: {{{name}: {box}}}"))
    with pytest.raises(SpecError) as expected:
        plant(parse_spec(unc_text))
    assert expected.value.path == f"plant.uncertainty.{name}"
    spec = write(tmp_path, text + f"sweep: {{parameters: {{{name}: {box}}}}}\n")
    out = tmp_path / "out"
    code = main(["sweep", str(spec), "--samples", "10", "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2
    assert err == f"designkit: error: sweep.parameters.{name}: {expected.value.message}\n"
    assert not out.exists()


def test_a_box_plant_uncertainty_accepts_is_swept(tmp_path):
    """The validator lets through what it should: a positive box beyond plant.uncertainty's, on the boundary of the
    ranges (Km from 1e-6)."""
    sw = parse_sweep(LINK + "sweep: {parameters: {Km: [1e-6, 3], tau: [0.1, 2e0]}}\n")
    from designkit.sweep.chunk import base

    ready = base(sw.text + "sweep: {parameters: {Km: [1.0e-06, 3.0], tau: [0.1, 2.0]}}\n", "<test>")
    assert [(d.name, d.low, d.high, d.path) for d in ready.space.dimensions] == [
        ("Km", 1e-6, 3.0, "sweep.parameters.Km"), ("tau", 0.1, 2.0, "sweep.parameters.tau")]
