"""The Python API's exception family: every user mistake is a DesignkitError, and the
CLI answers every DesignkitError with exit 2 and one line, anything else with exit 3."""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

import numpy as np
import pytest

import designkit as dk
from designkit import errors
from designkit.cli import main
from tests.problems import POSSPEED_GAINS, POSSPEED_YAML


@pytest.fixture(scope="module")
def loaded() -> dk.LoadedSpec:
    return dk.parse_spec(POSSPEED_YAML)


@pytest.fixture(scope="module")
def result(loaded) -> dk.PipelineResult:
    return dk.run(loaded, simulate=False)


def test_one_family_with_its_attributes():
    for cls in (dk.SpecError, dk.ModelError, dk.OutputError):
        assert issubclass(cls, dk.DesignkitError)
    spec_error = dk.SpecError("plant.Km", "must be positive")
    assert (spec_error.path, spec_error.message, str(spec_error)) == ("plant.Km", "must be positive",
                                                                        "plant.Km: must be positive")
    model_error = dk.ModelError("links[1].mass", "must be positive")
    assert (model_error.field, model_error.path, model_error.message) == ("links[1].mass", "links[1].mass",
                                                                          "must be positive")
    assert dk.ModelError("no such robot").path == ""
    output_error = dk.OutputError("out_dir", "x is a file")
    assert isinstance(output_error, OSError) and str(output_error) == "out_dir: x is a file"
    for name in ("DesignkitError", "SpecError", "ModelError", "OutputError"):
        assert name in errors.__doc__ and name in dk.__all__


@pytest.mark.parametrize("path", [None, 123, 1.5, b"specs/posspeed-link.yaml", ["specs/posspeed-link.yaml"]])
def test_load_spec_refuses_what_is_not_a_path(path):
    with pytest.raises(dk.SpecError) as info:
        dk.load_spec(path)
    assert info.value.path == "path"
    assert f"got {type(path).__name__}" in info.value.message
    assert "\n" not in str(info.value)


def test_load_spec_takes_str_and_pathlike(tmp_path):
    spec = tmp_path / "spec.yaml"
    spec.write_text(POSSPEED_YAML)
    assert dk.load_spec(str(spec)).spec == dk.load_spec(spec).spec


@pytest.mark.parametrize(("path", "words"), [("missing.yaml", "not found"), (".", "cannot read")])
def test_load_spec_of_a_missing_or_unreadable_file(tmp_path, path, words):
    with pytest.raises(dk.SpecError, match=words):
        dk.load_spec(tmp_path / path)


def test_load_spec_of_a_file_that_is_not_utf8(tmp_path):
    spec = tmp_path / "spec.yaml"
    spec.write_bytes(POSSPEED_YAML.encode() + b"# \xff\xfe\n")
    with pytest.raises(dk.SpecError, match="not UTF-8"):
        dk.load_spec(spec)


@pytest.mark.parametrize("text", [None, 123, ["name: x"], {"name": "x"}])
def test_parse_spec_refuses_what_is_not_text(text):
    with pytest.raises(dk.SpecError) as info:
        dk.parse_spec(text)
    assert info.value.path == "text"
    assert f"got {type(text).__name__}" in info.value.message


def test_parse_spec_decodes_utf8_bytes():
    from_bytes = dk.parse_spec(POSSPEED_YAML.encode())
    from_text = dk.parse_spec(POSSPEED_YAML)
    assert from_bytes.spec == from_text.spec and from_bytes.sha256 == from_text.sha256
    with pytest.raises(dk.SpecError, match="not UTF-8"):
        dk.parse_spec(b"name: \xff")


def test_run_accepts_a_spec_and_gives_the_same_gains(loaded, result):
    from_spec = dk.run(loaded.spec, simulate=False)
    assert dict(from_spec.design.gains) == pytest.approx(POSSPEED_GAINS)
    assert dict(from_spec.design.gains) == dict(result.design.gains)
    assert [c.status for c in from_spec.checks] == [c.status for c in result.checks]
    canonical = json.dumps(loaded.spec.model_dump(mode="json"), sort_keys=True, separators=(",", ":"))
    assert from_spec.loaded.text == canonical
    assert from_spec.loaded.sha256 == hashlib.sha256(canonical.encode()).hexdigest()
    assert from_spec.loaded.path == "<Spec>"
    assert dk.parse_spec(from_spec.loaded.text).spec == loaded.spec  # the canonical JSON is a valid spec


@pytest.mark.parametrize("argument", [None, 42, "specs/posspeed-link.yaml", Path("specs/posspeed-link.yaml"),
                                      {"name": "x"}])
def test_run_refuses_anything_else(argument):
    with pytest.raises(dk.DesignkitError) as info:
        dk.run(argument)
    assert isinstance(info.value, dk.SpecError) and info.value.path == "loaded"
    assert f"got {type(argument).__name__}" in info.value.message


def test_write_report_to_an_existing_file_is_refused_and_nothing_overwritten(result, tmp_path):
    blocker = tmp_path / "report-here"
    blocker.write_text("precious")
    for out in (blocker, blocker / "below"):
        with pytest.raises(dk.OutputError) as info:
            dk.write_report(result, out, studies=False)
        assert info.value.path == "out_dir"
        assert "is an existing file" in info.value.message and str(blocker) in info.value.message
    assert blocker.read_text() == "precious"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report-here"]


def test_write_report_where_the_report_folder_is_a_file(result, tmp_path):
    (tmp_path / result.loaded.spec.name).write_text("precious")
    with pytest.raises(dk.OutputError, match="is an existing file"):
        dk.write_report(result, tmp_path, studies=False)
    assert (tmp_path / result.loaded.spec.name).read_text() == "precious"


@pytest.mark.skipif(os.geteuid() == 0, reason="root may write anywhere")
def test_write_report_into_a_read_only_folder(result, tmp_path):
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    try:
        with pytest.raises(dk.OutputError, match="no permission"):
            dk.write_report(result, locked / "reports", studies=False)
    finally:
        locked.chmod(0o700)
    assert list(locked.iterdir()) == []


@pytest.mark.parametrize("argument", [None, 1, "result"])
def test_write_report_refuses_what_is_not_a_result(tmp_path, argument):
    with pytest.raises(dk.SpecError) as info:
        dk.write_report(argument, tmp_path, studies=False)
    assert info.value.path == "result"
    assert list(tmp_path.iterdir()) == []


def test_write_report_refuses_an_out_dir_that_is_not_a_path(result):
    with pytest.raises(dk.OutputError, match="got NoneType"):
        dk.write_report(result, None, studies=False)


# ------------------------------------------------------------------------------------ the CLI's mapping


def _spec(tmp_path: Path) -> Path:
    spec = tmp_path / "spec.yaml"
    spec.write_text(POSSPEED_YAML)
    return spec


def test_synth_out_an_existing_file_is_exit_2_naming_out(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("precious")
    code = main(["synth", str(_spec(tmp_path)), "--out", str(blocker)])
    captured = capsys.readouterr()
    assert code == 2
    assert captured.err.startswith("designkit: error: --out: cannot write the report: ")
    assert "is an existing file" in captured.err and captured.err.count("\n") == 1
    assert blocker.read_text() == "precious"


@pytest.mark.parametrize(
    "error",
    [dk.ModelError("plant.dh[1].mass", "must be positive"), dk.SpecError("plant.Km", "bad\nsecond line"),
     dk.OutputError("--out", "cannot"), dk.DesignkitError("a bare one")],
    ids=["model", "multiline", "output", "base"],
)
def test_every_designkit_error_is_exit_2_on_one_line(tmp_path, capsys, monkeypatch, error):
    import designkit.pipeline

    def fail(*args, **kwargs):
        raise error

    monkeypatch.setattr(designkit.pipeline, "run", fail)
    code = main(["verify", str(_spec(tmp_path))])
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith("designkit: error: ") and err.count("\n") == 1 and "Traceback" not in err
    assert str(error).split("\n")[0] in err


def test_anything_else_stays_an_internal_error(tmp_path, capsys, monkeypatch):
    import designkit.pipeline

    def fail(*args, **kwargs):
        raise KeyError("a bug")

    monkeypatch.setattr(designkit.pipeline, "run", fail)
    code = main(["verify", str(_spec(tmp_path))])
    err = capsys.readouterr().err
    assert code == 3
    assert err.startswith("designkit: internal error: KeyError")


def test_simulate_csv_into_a_folder_is_exit_2_naming_csv(tmp_path, capsys):
    code = main(["simulate", str(_spec(tmp_path)), "--csv", str(tmp_path)])
    captured = capsys.readouterr()
    assert code == 2
    assert captured.err.startswith("designkit: error: --csv: cannot write ") and captured.err.count("\n") == 1


def test_a_per_input_requirement_of_the_wrong_length_names_its_key(tmp_path, capsys):
    # a case from the fuzzer: too many torque limits for a one-input link, refused before the time-domain check
    from tests.cli_input import assert_bad_input

    text = ("name: lengths\nplant: {kind: link, Km: 2.0, tau: 0.5}\n"
            "controller: {kind: pid_servo, poles: [-4, -5, -20], zero: -3}\n"
            "requirements: {max_control: [1, 2, 3]}\n")
    assert_bad_input(tmp_path, capsys, text, "requirements.max_control: needs one value per input (1), got 3")


# ----------------------------------------------------------------------------- API misuse from the fuzzed corpus


LINK_SPEC = "name: a\nplant: {kind: link, Km: 2.0, tau: 0.5}\ncontroller: {kind: pid_servo, poles: [-4, -5, -20]}\n"


@pytest.mark.parametrize("call, path", [
    (lambda spec, design: dk.synthesize(None), "spec"),
    (lambda spec, design: dk.synthesize("specs/posspeed-link.yaml"), "spec"),
    (lambda spec, design: dk.simulate(None, design), "spec"),
    (lambda spec, design: dk.simulate(spec, None), "design"),
    (lambda spec, design: dk.build(1, 2), "spec"),
    (lambda spec, design: dk.build(spec, "design"), "design"),
])
def test_the_wrong_object_is_named(call, path):
    loaded = dk.parse_spec(LINK_SPEC)
    with pytest.raises(dk.SpecError) as err:
        call(loaded.spec, dk.synthesize(loaded.spec))
    assert err.value.path == path and "\n" not in str(err.value)


def test_a_loaded_spec_is_taken_for_its_spec():
    loaded = dk.parse_spec(LINK_SPEC)
    assert dk.synthesize(loaded).gains["K1"] == dk.synthesize(loaded.spec).gains["K1"]


def test_unknown_names_are_designkit_errors_and_key_errors():
    design = dk.synthesize(dk.parse_spec(LINK_SPEC).spec)
    arm = dk.robot("planar2r")
    for lookup, path in ((lambda: design.gains["K9"], "gains['K9']"), (lambda: arm.functions["nope"],
                                                                        "functions['nope']")):
        with pytest.raises(dk.NameNotFoundError) as err:
            lookup()
        assert isinstance(err.value, KeyError) and isinstance(err.value, dk.DesignkitError)
        assert err.value.path == path and str(err.value).startswith(path)
    assert dict(design.gains).keys() == {"K1", "K2", "K3", "K4"}  # the mapping protocol still works


@pytest.mark.parametrize("q, words", [
    (["a", "b"], "got text"),
    (np.array([None, 1.0], dtype=object), "other objects"),
    (np.array([1j, 0.0]), "complex"),
    ([True, False], "booleans"),
])
def test_model_calls_refuse_what_is_not_real_numbers(q, words):
    with pytest.raises(dk.ModelError) as err:
        dk.robot("planar2r").inverse_dynamics(q, [0.0, 0.0], [0.0, 0.0])
    assert err.value.path == "q" and words in err.value.message


def test_model_calls_take_numbers_in_any_container():
    arm = dk.robot("planar2r")
    ref = arm.inverse_dynamics([0.1, 0.2], [0.0, 0.0], [0.0, 0.0])
    assert np.array_equal(arm.inverse_dynamics(np.array([0.1, 0.2], dtype=object), [0, 0], (0, 0)), ref)


@pytest.mark.parametrize("overrides, path", [({"m2": float("nan")}, "m2"), ({"d1": -1.0}, "d1"),
                                             ({"m1": -0.5}, "m1"), ({"g": float("inf")}, "g")])
def test_zoo_overrides_follow_the_plant_rule(overrides, path):
    with pytest.raises(dk.ModelError) as err:
        dk.robot("planar2r", **overrides)
    assert err.value.path == path
    with pytest.raises(dk.ModelError):  # the same values the plant's with_params refuses
        dk.zoo_plant("planar2r").with_params(**overrides)


def test_urdf_paths_and_numbers_off_the_chain(tmp_path):
    with pytest.raises(dk.ModelError) as err:
        dk.robot_from_urdf(None)
    assert err.value.path == "path"
    from importlib.resources import files

    text = (files("designkit.models.robots") / "planar2r.urdf").read_text().replace(
        '<link name="base_link"/>', '<link name="base_link"><inertial><mass value="nan"/><inertia ixx="0" ixy="0" '
        'ixz="0" iyy="0" iyz="0" izz="0"/></inertial></link>')
    bad = tmp_path / "nan-base.urdf"
    bad.write_text(text)
    with pytest.raises(dk.ModelError, match="base_link"):
        dk.robot_from_urdf(bad)


# ------------------------------------------------------------------- every public function, every parameter


class _Text(str):
    """A str subclass whose own methods fail: the API reads its plain value or refuses it, never calls them."""

    def encode(self, *args, **kwargs):
        raise RuntimeError("a str subclass's encode was called")

    def __fspath__(self):
        raise RuntimeError("a str subclass's __fspath__ was called")


MISSING = "missing-file.yaml"
_NAN, _INF = float("nan"), float("inf")
_COMMON = {"None": None, "bytes": b"x", "list": [1], "nul": "a\0b", "surrogate": "\ud800", "str-sub": _Text("2")}
WRONG: dict[str, dict[str, object]] = {
    "count": {**_COMMON, "str": "2", "float": 1.5, "bool": True, "negative": -5, "zero": 0, "nan": _NAN, "inf": _INF,
              "huge": 10**400},
    "seed": {**_COMMON, "str": "2", "float": 1.5, "bool": True, "negative": -5, "nan": _NAN, "huge": 10**400},
    "positive": {**_COMMON, "str": "2", "bool": True, "negative": -5.0, "zero": 0, "nan": _NAN, "inf": _INF,
                 "huge": 10**400, "complex": 1j},
    "tolerance": {**_COMMON, "str": "2", "bool": True, "negative": -5.0, "nan": _NAN, "inf": _INF, "huge": 10**400},
    "flag": {"None": None, "str": "yes", "int": 1, "float": 0.0, "nan": _NAN, "str-sub": _Text("True"), "list": []},
    "name": {"None": None, "int": 1, "float": 1.5, "bool": True, "bytes": b"x", "nul": "a\0b", "surrogate": "\ud800",
             "empty": "", "path": Path("x"), "list": ["x"]},
    "yaml": {"None": None, "int": 1, "float": 1.5, "bool": True, "nul": "name: a\0b", "surrogate": "name: \ud800",
             "path": Path("x"), "list": ["x"]},
    "file": {"None": None, "int": 1, "bool": True, "bytes": b"x", "nul": "a\0b.yaml", "surrogate": "\ud800.yaml",
             "empty": "", "list": ["x"], "missing": Path(MISSING), "folder": Path(".")},
    "folder": {"None": None, "int": 1, "bool": True, "bytes": b"x", "nul": "a\0b", "surrogate": "\ud800",
               "empty": "", "list": ["x"], "file": Path("a-file")},
    "object": {"None": None, "str": "x", "int": 1, "str-sub": _Text("x"), "bytes": b"x", "missing": Path(MISSING),
               "folder": Path("."), "dict": {"name": "x"}},
}
"""Wrong values by kind of parameter; ``missing``, ``folder`` and ``file`` are relative to the test's folder."""


@pytest.fixture(scope="module")
def env(tmp_path_factory):
    import casadi as ca

    folder = tmp_path_factory.mktemp("env")
    spec_file = folder / "spec.yaml"
    spec_file.write_text(POSSPEED_YAML)
    loaded = dk.parse_spec(POSSPEED_YAML)
    design = dk.synthesize(loaded.spec)
    q = ca.SX.sym("q", 2)
    sweepable = dk.parse_spec(POSSPEED_YAML.replace("tau: 0.5}", "tau: 0.5, uncertainty: {Km: [1.8, 2.2]}}")
                              + "requirements: {overshoot: 20}\nsimulation: {duration: 1.0}\n")
    tunable = folder / "tunable.yaml"
    tunable.write_text(POSSPEED_YAML + "requirements: {overshoot: 20}\nsimulation: {duration: 1.0}\n")
    return {"loaded": loaded, "sweepable": sweepable, "spec_file": spec_file, "tunable": tunable, "spec": loaded.spec,
            "design": design,
            "simulator": dk.build(loaded.spec, design), "result": dk.run(loaded, simulate=False),
            "arm": dk.robot("planar2r"), "chain": dk.robot("planar2r").description,
            "f": ca.Function("f", [q], [ca.cos(q[0]) + q[1] ** 2], ["q"], ["y"]),
            "urdf": Path(dk.__file__).parent / "models" / "robots" / "planar2r.urdf"}


def _codegen(loaded, out_dir, name=None):
    """:func:`designkit.pipeline.codegen` (``designkit codegen``), imported when called."""
    from designkit.pipeline import codegen

    return codegen(loaded, out_dir, name=name)


def _learn(result, feedforward):
    return feedforward


# function, its valid call (keyword arguments from env, out = a folder below the test's folder), its parameters
CALLS = {
    "load_spec": ("load_spec", lambda e, out: {"path": e["spec_file"]},
                  {"path": "file"}),
    "parse_spec": ("parse_spec", lambda e, out: {"text": POSSPEED_YAML, "path": "<string>"},
                   {"text": "yaml", "path": "name"}),
    "synthesize": ("synthesize", lambda e, out: {"spec": e["spec"], "plant": None, "base_dir": None},
                   {"spec": "object", "plant": "object", "base_dir": "folder"}),
    "run": ("run", lambda e, out: {"loaded": e["loaded"], "simulate": False, "budget": 60.0},
            {"loaded": "object", "simulate": "flag", "budget": "positive"}),
    "simulate": ("simulate", lambda e, out: {"spec": e["spec"], "design": e["design"], "plant": None},
                 {"spec": "object", "design": "object", "plant": "object"}),
    "build": ("build", lambda e, out: {"spec": e["spec"], "design": e["design"], "plant": None, "law": None,
                                       "expected_runs": 1, "reference": None},
              {"spec": "object", "design": "object", "plant": "object", "law": "object", "expected_runs": "count",
               "reference": "object"}),
    "run_trials": ("run_trials", lambda e, out: {"simulator": e["simulator"], "trials": 1, "learn": _learn,
                                                 "feedforward": None},
                   {"simulator": "object", "trials": "count", "learn": "object", "feedforward": "object"}),
    "family": ("family", lambda e, out: {"kind": "pid_servo"}, {"kind": "name"}),
    "zoo_plant": ("zoo_plant", lambda e, out: {"name": "planar2r", "overrides": None, "friction": True,
                                               "motor_inertia": False, "consistent_inertia": None},
                  {"name": "name", "overrides": "object", "friction": "flag", "motor_inertia": "flag",
                   "consistent_inertia": "name"}),
    "chain_plant": ("chain_plant", lambda e, out: {"description": e["chain"], "friction": True, "motor_inertia": False,
                                                   "source": "", "consistent_inertia": None},
                    {"description": "object", "friction": "flag", "motor_inertia": "flag", "source": "name",
                     "consistent_inertia": "name"}),
    "write_report": ("write_report", lambda e, out: {"result": e["result"], "out_dir": out, "processes": 1,
                                                     "studies": False},
                     {"result": "object", "out_dir": "folder", "processes": "count", "studies": "flag"}),
    "sweep": ("sweep", lambda e, out: {"spec": e["sweepable"], "samples": 2, "seed": 0, "client": None,
                                       "scheduler": None, "workers": None, "out": out, "chunk": None,
                                       "engine": "process", "progress": False, "falsification": False, "report": False},
              {"spec": "object", "samples": "count", "seed": "seed", "client": "object", "scheduler": "name",
               "workers": "count", "out": "folder", "chunk": "count", "engine": "name", "progress": "flag",
               "falsification": "flag", "report": "flag"}),
    "tune": ("tune", lambda e, out: {"spec": e["tunable"], "out": out, "budget": 0.5, "seed": 0, "write": True},
             {"spec": "file", "out": "folder", "budget": "positive", "seed": "seed", "write": "flag"}),
    "codegen": (_codegen, lambda e, out: {"loaded": e["loaded"], "out_dir": out, "name": None},
                {"loaded": "object", "out_dir": "folder", "name": "name"}),
    "robot_from_dh": ("robot_from_dh", lambda e, out: {"description": e["chain"], "friction": False,
                                                       "motor_inertia": False},
                      {"description": "object", "friction": "flag", "motor_inertia": "flag"}),
    "enclose": ("enclose", lambda e, out: {"function": e["f"], "box": {"q": ([0, 0], [1, 1])}, "output": 0,
                                           "index": None, "rel_tol": 1e-3, "abs_tol": 0.0, "max_boxes": 100,
                                           "strict": True, "thresholds": (None, None)},
                {"function": "object", "box": "object", "output": "object", "index": "object", "rel_tol": "positive",
                 "abs_tol": "tolerance", "max_boxes": "count", "strict": "flag", "thresholds": "object"}),
    "model_bound": ("model_bound", lambda e, out: {"robot": e["arm"], "quantity": "mass_matrix", "index": (0, 0),
                                                   "q": ([0, -1], [0, 1]), "rel_tol": 1e-2, "abs_tol": 0.0,
                                                   "max_boxes": 1000, "strict": True},
                    {"robot": "object", "quantity": "name", "index": "object", "q": "object", "rel_tol": "positive",
                     "abs_tol": "tolerance", "max_boxes": "count", "strict": "flag"}),
    "robot": ("robot", lambda e, out: {"name": "planar2r"}, {"name": "name"}),
    "robot_from_urdf": ("robot_from_urdf", lambda e, out: {"path": e["urdf"], "base_link": None, "tip_link": None,
                                                           "gravity": (0.0, 0.0, -9.81), "friction": False},
                        {"path": "file", "base_link": "name", "tip_link": "name", "gravity": "object",
                         "friction": "flag"}),
}
"""Every public function of ``designkit`` (and ``designkit.pipeline.codegen``) with a call that works and the kind
of each parameter."""

ALLOWED: dict[tuple[str, str], set[str]] = {
    **{(f, p): {"None"} for f, p in [
        ("synthesize", "plant"), ("simulate", "plant"), ("build", "plant"), ("build", "law"), ("build", "reference"),
        ("run_trials", "feedforward"), ("run", "budget"), ("zoo_plant", "overrides"),
        ("zoo_plant", "consistent_inertia"), ("chain_plant", "consistent_inertia"),
        ("sweep", "client"), ("sweep", "scheduler"), ("sweep", "workers"),
        ("sweep", "out"), ("sweep", "chunk"), ("tune", "out"), ("codegen", "name"), ("robot_from_dh", "description"),
        ("enclose", "index"), ("model_bound", "max_boxes"), ("robot_from_urdf", "base_link"),
        ("robot_from_urdf", "tip_link")]},
    ("synthesize", "base_dir"): {"None", "file"}, ("codegen", "loaded"): {"str", "str-sub"},
    ("chain_plant", "source"): {"empty"}, ("parse_spec", "path"): {"empty"},
    ("model_bound", "index"): {"None", "int"}, ("model_bound", "q"): {"int"},
}
"""Values of a parameter's kind that the parameter takes (``None`` where it means "the default")."""

ALIASES = {("robot", "name"): "robot", ("zoo_plant", "name"): "robot", ("zoo_plant", "overrides"): "parameters"}
"""Parameters whose errors carry the spec's name of the field (``plant.robot``, ``plant.parameters``)."""

CASES = [(function, parameter, label) for function, (_, _, kinds) in CALLS.items() for parameter, kind in kinds.items()
         for label in WRONG[kind] if label not in ALLOWED.get((function, parameter), set())]


def test_the_campaign_covers_every_exported_function():
    import inspect

    exported = {name for name in dk.__all__ if name != "__version__" and inspect.isfunction(getattr(dk, name))}
    assert exported | {"sweep", "codegen"} == set(CALLS)
    for function, (target, _, kinds) in CALLS.items():
        fn = getattr(dk, target) if isinstance(target, str) else target
        named = {p.name for p in inspect.signature(fn).parameters.values() if p.kind is not p.VAR_KEYWORD}
        if function != "sweep":  # dk.sweep forwards to designkit.sweep.api.sweep
            assert set(kinds) <= named, (function, set(kinds) - named)


def _call(which, env, _out, **changes):
    target, valid, _ = CALLS[which]
    fn = getattr(dk, target) if isinstance(target, str) else target
    return fn(**{**valid(env, _out), **changes})


@pytest.mark.parametrize(("function", "parameter", "label"), CASES, ids=["-".join(c) for c in CASES])
def test_every_wrong_argument_is_refused_naming_it(env, tmp_path, monkeypatch, function, parameter, label):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "a-file").write_text("in the way")
    before = sorted(p.name for p in tmp_path.rglob("*"))
    value = WRONG[CALLS[function][2][parameter]][label]
    with pytest.raises(dk.DesignkitError) as info:
        _call(function, env, tmp_path / "out", **{parameter: value})
    named = ALIASES.get((function, parameter), parameter)
    assert parameter in str(info.value) or named in str(info.value) or (
        label in ("missing", "folder") and (MISSING in str(info.value) or label == "folder")), str(info.value)
    assert "\n" not in str(info.value)
    assert sorted(p.name for p in tmp_path.rglob("*")) == before


@pytest.mark.parametrize("function", sorted(set(CALLS) - {"sweep", "write_report", "codegen", "run_trials"}))
def test_the_valid_calls_of_the_campaign_work(env, tmp_path, function):
    # the baseline every wrong call departs from: it runs and returns its object, so a refusal above is the
    # changed argument's
    assert _call(function, env, tmp_path / "out") is not None


def test_a_str_subclass_is_read_as_its_text(env):
    assert dk.parse_spec(_Text(POSSPEED_YAML)).spec == dk.parse_spec(POSSPEED_YAML).spec
    assert dk.load_spec(_Text(str(env["spec_file"]))).spec == env["loaded"].spec
    assert dk.robot(_Text("planar2r")).n == 2


def test_a_sweep_with_a_client_that_is_not_one_writes_nothing(env, tmp_path):
    with pytest.raises(dk.SpecError) as info:
        dk.sweep(env["sweepable"], 2, client="x", out=tmp_path / "sweep")
    assert info.value.path == "client"
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(("call", "path"), [
    (lambda e: dk.build(e["spec"], e["design"], expected_runs=-5), "expected_runs"),
    (lambda e: dk.sweep(e["sweepable"], 2, chunk=1.5, engine="process"), "--chunk"),
    (lambda e: dk.write_report(e["result"], "unused", processes="2"), "processes"),
    (lambda e: dk.run_trials(e["simulator"], 0, _learn), "trials"),
])
def test_numbers_out_of_their_range_are_refused_not_coerced(env, call, path):
    with pytest.raises(dk.SpecError) as info:
        call(env)
    assert info.value.path == path
