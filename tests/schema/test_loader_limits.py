"""Bounded work and strict types at load time: size, node and depth limits, JSON-only YAML, booleans
are not numbers, numbers within the float range, quoted values cut short."""

from __future__ import annotations

import time
import tracemalloc
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import pytest
from pydantic import ValidationError

import designkit.pipeline  # noqa: F401 - imported up front: the CLI's lazy imports are not what is measured
import designkit.report  # noqa: F401
from designkit.cli import main
from designkit.errors import QUOTE_LIMIT, SpecError, short_repr
from designkit.schema import loader
from designkit.schema.loader import parse_spec
from designkit.schema.spec import Spec
from tests.cli_input import assert_bad_input
from tests.problems import POSSPEED_YAML

TIME_BOUND = 1.0
"""CPU seconds within which a hostile input must be refused.  CPU time of this process, not wall time: the
bound is on the work done, which another process loading the machine does not change (a bomb that expanded would cost
far more than a second either way)."""

MEMORY_BOUND = 200e6
"""Bytes of Python allocations (tracemalloc peak) a hostile input may cost."""

BACKENDS = ["libyaml", "python"] if loader.yaml.__with_libyaml__ else ["python"]


@pytest.fixture(params=BACKENDS)
def backend(request, monkeypatch) -> str:
    """Run the test on libyaml's parser (the default when PyYAML has it) and on the pure-Python one."""
    if request.param == "python":
        monkeypatch.setattr(loader, "_BoundedLoader", loader._PyLoader)
    return request.param


@dataclass
class Cost:
    seconds: float = 0.0
    peak_bytes: int = 0


@contextmanager
def measured() -> Iterator[Cost]:
    """CPU time (``time.process_time``) and tracemalloc peak of the block."""
    cost = Cost()
    tracemalloc.start()
    start = time.process_time()
    try:
        yield cost
    finally:
        cost.seconds = time.process_time() - start
        cost.peak_bytes = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()


def spec_with(replace: str, by: str) -> str:
    text = POSSPEED_YAML.replace(replace, by)
    assert text != POSSPEED_YAML
    return text


def anchor_bomb(levels: int = 9, fan: int = 9) -> str:
    """An anchor bomb inside ``controller.poles``: each anchor a list of ``fan`` aliases of the previous."""
    items = ["&a0 [" + ",".join(["-1"] * fan) + "]"]
    items += [f"&a{i} [" + ",".join([f"*a{i - 1}"] * fan) + "]" for i in range(1, levels)]
    return spec_with("[-4, -5, -20]", "[" + ",".join(items) + "]")


def refused(text: str) -> tuple[SpecError, Cost]:
    with measured() as cost, pytest.raises(SpecError) as info:
        parse_spec(text)
    return info.value, cost


# ------------------------------------------------------------------------------------ resources


def test_anchor_bomb_is_refused_within_the_bounds(backend):
    text = anchor_bomb()
    assert len(text) - len(POSSPEED_YAML) < 400  # 9 levels of 9 aliases: 9**9 = 387 million poles expanded
    err, cost = refused(text)
    assert err.path.startswith("controller.poles")
    assert f"{loader.MAX_NODES:,} nodes" in err.message
    assert cost.seconds < TIME_BOUND, cost
    assert cost.peak_bytes < MEMORY_BOUND, cost


def test_anchor_bomb_one_level_deeper_costs_no_more(backend):
    err, cost = refused(anchor_bomb(levels=10))
    assert "nodes" in err.message
    assert cost.seconds < TIME_BOUND and cost.peak_bytes < MEMORY_BOUND, cost


def test_anchor_bomb_through_the_cli(tmp_path, capsys):
    with measured() as cost:
        assert_bad_input(tmp_path, capsys, anchor_bomb(), "controller.poles")
    assert cost.seconds < TIME_BOUND and cost.peak_bytes < MEMORY_BOUND, cost


@pytest.mark.parametrize(("opening", "closing"), [("[", "]"), ("{a: ", "}")], ids=["lists", "mappings"])
def test_3000_levels_of_nesting_are_refused_without_recursion_error(backend, opening, closing):
    err, cost = refused(spec_with("[-4, -5, -20]", opening * 3000 + "-1" + closing * 3000))
    assert err.path.startswith("controller.poles")
    assert f"deeper than {loader.MAX_DEPTH} levels" in err.message
    assert cost.seconds < TIME_BOUND and cost.peak_bytes < MEMORY_BOUND, cost


def test_deep_block_nesting_is_refused(backend):
    err, cost = refused(POSSPEED_YAML + "extra:\n" + "- " * 3000 + "1\n")
    assert err.path.startswith("extra") and "deeper than" in err.message
    assert cost.seconds < TIME_BOUND, cost


def test_deep_nesting_through_the_cli(tmp_path, capsys):
    with measured() as cost:
        # controller.poles[0]... (the composer) or controller.poles (the scanner, where a libyaml that scans
        # ahead -- PyYAML 6.0.4's wheels -- hands the text to the pure-Python one)
        assert_bad_input(tmp_path, capsys, spec_with("[-4, -5, -20]", "[" * 3000 + "1" + "]" * 3000),
                         "controller.poles")
    assert cost.seconds < TIME_BOUND and cost.peak_bytes < MEMORY_BOUND, cost


def test_nesting_within_the_limit_is_left_to_the_schema(backend):
    err, _ = refused(spec_with("[-4, -5, -20]", "[" * 50 + "-1" + "]" * 50))
    assert err.path == "controller.poles[0]"
    assert "complex string" in err.message  # the schema's answer, not the loader's


def test_aliases_nesting_past_the_limit_are_refused(backend):
    chain = ["&n0 [1]"] + [f"&n{i} [[[[*n{i - 1}]]]]" for i in range(1, 20)]  # 4 levels per alias
    err, _ = refused(spec_with("[-4, -5, -20]", "[" + ", ".join(chain) + "]"))
    assert "deeper than" in err.message


def test_node_limit_counts_plain_nodes_too(backend, monkeypatch):
    monkeypatch.setattr(loader, "MAX_NODES", 1000)  # the mechanism, on a small document
    err, _ = refused(spec_with("[-4, -5, -20]", "[" + "0, " * 1000 + "]"))
    assert err.path.startswith("controller.poles[")
    assert "more than 1,000 nodes" in err.message


def test_recursive_alias_is_refused(backend):
    err, _ = refused(spec_with("[-4, -5, -20]", "&r [-4, *r]"))
    assert err.path == "controller.poles[1]" and "recursive" in err.message


def test_oversized_file_is_refused_before_it_is_read(tmp_path, capsys):
    big = POSSPEED_YAML + ("# padding " + "x" * 90 + "\n") * (2 * 2**20 // 100)
    assert len(big) > 2 * 2**20
    spec = tmp_path / "spec.yaml"
    spec.write_text(big)
    with measured() as cost:
        code = main(["verify", str(spec)])
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith("designkit: error: spec file ") and err.count("\n") == 1
    assert "2.0 MiB" in err and "limit of 1 MiB (1,048,576 bytes)" in err
    assert cost.seconds < TIME_BOUND, cost
    assert cost.peak_bytes < 2 * 2**20, cost  # never read in full


def test_oversized_stream_is_refused_after_one_mebibyte():
    """A file whose size is not known up front (a pipe, a device) is read no further than the limit."""
    err = None
    with measured() as cost:
        try:
            loader.load_spec("/dev/zero")
        except SpecError as exc:
            err = exc
    assert err is not None and "more than 1 MiB" in err.message
    assert cost.seconds < TIME_BOUND and cost.peak_bytes < 4 * 2**20, cost


def test_oversized_text_is_refused():
    err, cost = refused(POSSPEED_YAML + "#" * (2 * 2**20))
    assert "limit of 1 MiB" in err.message
    assert cost.seconds < TIME_BOUND, cost
    with pytest.raises(SpecError, match="limit of 1 MiB"):
        parse_spec(POSSPEED_YAML.encode() + b"#" * (2 * 2**20))


# ------------------------------------------------------------------------------------ strict types


@pytest.mark.parametrize(
    ("replace", "by", "message"),
    [
        ("Km: 2.0", "Km: true", "plant.Km: must be a number, not a boolean"),
        ("tau: 0.5", "tau: yes", "plant.tau: must be a number, not a boolean"),
        ("tau: 0.5", "tau: off", "plant.tau: must be a number, not a boolean"),
        ("-20]", "true]", "controller.poles[2]: must be a number or a complex string like '-2+3j', not a boolean"),
        ("zero: -3", "zero: no", "controller.zero: must be a number, not a boolean"),
        ("tau: 0.5}", "tau: 0.5, uncertainty: {Km: [1.5, 2.5], grid: true}}", "plant.uncertainty.grid: must be a "
         "number, not a boolean"),
        ("Km: 2.0", "Km: 2.0, Km: 3.0", "plant.Km: duplicate key (first given on line 2)"),
        ("name: posspeed-link\n", "name: posspeed-link\nname: other\n", "name: duplicate key (first given on line 1)"),
        ("name: posspeed-link\n", "name: posspeed-link\ncontroller: {}\n", "controller: duplicate key"),
        ("Km: 2.0", "Km: !!binary aGVsbG8=", "plant.Km: YAML tag !!binary is not allowed"),
        ("Km: 2.0", "Km: !!set {a, b}", "plant.Km: YAML tag !!set is not allowed"),
        ("Km: 2.0", "Km: !!timestamp 2001-12-14", "plant.Km: YAML tag !!timestamp is not allowed"),
        ("Km: 2.0", "Km: !!python/object/apply:os.system [echo]", "plant.Km: YAML tag !!python/object/apply:os.system"
         " is not allowed"),
        ("Km: 2.0", "Km: !!omap [{a: 1}]", "plant.Km: YAML tag !!omap is not allowed"),
        ("Km: 2.0", "Km: !local 2.0", "plant.Km: YAML tag !local is not allowed"),
        ("Km: 2.0", "Km: !!str [2.0]", "plant.Km: YAML tag !!str cannot be put on a list"),
        ("Km: 2.0", "Km: " + "1" * 400, "plant.Km: must be within the floating-point range (|x| <= 1.798e+308), got "
         "an integer of 400 digits"),
        ("Km: 2.0", "Km: " + "1" * 5000, "plant.Km: must be within the floating-point range (|x| <= 1.798e+308), got "
         "an integer of 5000 digits"),  # past Python's 4300-digit conversion limit
        ("-20]", "-" + "1" * 400 + "]", "controller.poles[2]: must be within the floating-point range"),
        ("Km: 2.0", "Km: 1e400", "plant.Km: must be within the floating-point range (|x| <= 1.798e+308), got "
         "'1e400'"),
        ("zero: -3", "zero: -1.0e+400", "controller.zero: must be within the floating-point range"),
        ("Km: 2.0", "Km: 2.0, ? [1]: 2", "plant: a mapping key must be a string or a number"),
        ("Km: 2.0", 'Km: !!int ""', "plant.Km: not an integer: ''"),
        ("Km: 2.0", "Km: !!float abc", "plant.Km: not a number: 'abc'"),
        # text is not a number, however it came to be text (only JSON's types are read)
        ("Km: 2.0", "Km: !!str 3", "plant.Km: must be a number, got the string '3'"),
        ("Km: 2.0", "Km: '2.0'", "plant.Km: must be a number, got the string '2.0'"),
    ],
)
def test_wrong_yaml_types_are_exit_2_with_the_key_path(tmp_path, capsys, replace, by, message):
    assert_bad_input(tmp_path, capsys, spec_with(replace, by), message)


@pytest.mark.parametrize(
    ("replace", "by", "field", "value"),
    [
        ("Km: 2.0", "Km: !!float 3", "Km", 3.0),
        ("Km: 2.0", "Km: 2e-3", "Km", 0.002),  # a float, as in JSON (YAML 1.1 would read a string)
        ("Km: 2.0", "Km: 2.5E+2", "Km", 250.0),
    ],
)
def test_json_numbers_and_harmless_tags_are_accepted(replace, by, field, value):
    assert getattr(parse_spec(spec_with(replace, by)).spec.plant, field) == value


def test_an_unquoted_date_is_a_string():
    assert parse_spec(spec_with("name: posspeed-link", "name: 2001-12-14")).spec.name == "2001-12-14"


def test_anchors_aliases_and_merge_keys_within_the_limits_are_read():
    text = spec_with("{kind: link, Km: 2.0, tau: 0.5}",
                     "{kind: link, Km: &k 2.0, tau: 0.5, uncertainty: {Km: [1.5, *k]}}")
    assert parse_spec(text).spec.plant.uncertainty.intervals["Km"] == (1.5, 2.0)
    merged = spec_with("{kind: pid_servo, poles: [-4, -5, -20], zero: -3}",
                       "{<<: {kind: pid_servo, zero: -4, poles: [-1, -2, -3]}, poles: [-4, -5, -20], zero: -3}")
    assert parse_spec(merged).spec == parse_spec(POSSPEED_YAML).spec  # explicit keys win over merged ones


@pytest.mark.parametrize(
    ("data", "path"),
    [
        ({"plant": {"kind": "link", "Km": True, "tau": 0.5}}, ("plant", "link")),
        ({"plant": {"kind": "link", "Km": 10**400, "tau": 0.5}}, ("plant", "link")),
        ({"plant": {"kind": "link", "Km": 2.0, "tau": 0.5}, "simulation": {"step": [1.0, 10**400]}},
         ("simulation",)),
        ({"plant": {"kind": "link", "Km": 2.0, "tau": 0.5}, "simulation": {"step": True}}, ("simulation",)),
    ],
)
def test_python_values_get_the_same_rules(data, path):
    """Validating Python data (not YAML) refuses booleans and huge integers too, with no OverflowError."""
    data = {"name": "x", "controller": {"kind": "pid_servo", "poles": [-4, -5, -20]}, **data}
    with pytest.raises(ValidationError) as info:
        Spec.model_validate(data)
    assert tuple(info.value.errors()[0]["loc"])[: len(path)] == path


def test_a_huge_integer_pole_from_python_is_a_validation_error():
    data = {"name": "x", "plant": {"kind": "link", "Km": 2.0, "tau": 0.5},
            "controller": {"kind": "pid_servo", "poles": [-4, -5, -(10**400)]}}
    with pytest.raises(ValidationError, match="floating-point range"):
        Spec.model_validate(data)


# ------------------------------------------------------------------------------------ quoted values


LONG = "x" * 20_000


@pytest.mark.parametrize(
    ("replace", "by", "path"),
    [
        ("Km: 2.0", f"Km: {LONG}", "plant.Km"),
        ("kind: link", f"kind: {LONG}", "plant.kind"),
        ("zero: -3", f"zero: '{LONG}'", "controller.zero"),
        ("-20]", f"'{LONG}']", "controller.poles[2]"),
        ("Km: 2.0", f"Km: 2.0, ? {LONG} : 1", "plant.xxxx"),  # explicit keys: no 1024-character limit
        ("Km: 2.0", f"Km: 2.0, ? {LONG} : 1, ? {LONG} : 2", "plant.xxxx"),
        ("Km: 2.0", f"Km: {'1' * 10_000}", "plant.Km"),
    ],
    ids=["number", "tag", "quoted", "pole", "key", "duplicate-key", "digits"],
)
def test_long_user_values_are_cut_in_messages(tmp_path, capsys, replace, by, path):
    assert_bad_input(tmp_path, capsys, spec_with(replace, by), path)
    spec_line = (tmp_path / "spec.yaml").read_text()
    err, _ = refused(spec_line)
    assert "x" * (QUOTE_LIMIT + 1) not in str(err) and "1" * (QUOTE_LIMIT + 1) not in str(err)
    assert len(str(err)) < 2 * QUOTE_LIMIT + loader.MAX_MESSAGE


def test_control_characters_in_keys_stay_on_one_line(tmp_path, capsys):
    assert_bad_input(tmp_path, capsys, spec_with("Km: 2.0", 'Km: 2.0, "a\\nb\\rc": 1'), "plant.a\\nb\\rc: unknown key")


def test_short_repr_never_builds_the_full_repr():
    class Huge:
        def __repr__(self) -> str:  # pragma: no cover - must not be called on containers' items past the limit
            raise AssertionError("repr built")

    assert short_repr([0] * 10**6 + [Huge()]).endswith("...]")
    assert short_repr("y" * 10**6) == "'" + "y" * (QUOTE_LIMIT - 2) + "…"
    assert short_repr(10**5000) == "an integer of 5001 digits"
    assert len(short_repr({"a": [[[[1]]]] * 100})) <= QUOTE_LIMIT


def test_every_example_spec_still_loads(backend):
    specs = sorted((Path(__file__).resolve().parents[2] / "specs").glob("*.yaml"))
    assert specs
    for path in specs:
        assert parse_spec(path.read_text()).spec.name == path.stem
