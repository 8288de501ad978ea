"""C code of the designed controller (``designkit codegen``), compiled and checked against the Python law.

The independent route is the system C compiler: the generated ``.c`` is built into a shared
library and every exported function is called through ``casadi.external`` (which runs the
compiled C, not the Python expression graph), and the C example of ``docs/codegen.md`` is built
into a program that reads samples on stdin.  Both are compared with the law's CasADi Functions
(the model terms with the robot model's own functions at the nominal parameters) on random states.
"""

from __future__ import annotations

import dataclasses
import hashlib
import re
import subprocess
from pathlib import Path

import casadi as ca
import numpy as np
import pytest
import yaml

from designkit.cli import main
from designkit.errors import SpecError
from designkit.families import FAMILIES, family
from designkit.models.codegen import find_compiler
from designkit.pipeline import codegen
from designkit.pipeline import design as design_of
from designkit.schema.loader import load_spec, parse_spec
from designkit.synthesis.codegen import (
    LAW_ROLES,
    MODEL_TERMS,
    LawCode,
    c_identifier,
    generate_law_code,
    law_source,
)
from tests.marks import slow_cases
from tests.tolerances import TOL

ROOT = Path(__file__).resolve().parents[2]
SPECS = sorted((ROOT / "specs").glob("*.yaml"))
DOC = ROOT / "docs" / "codegen.md"
N_SAMPLES = 50
SERVO = ROOT / "specs" / "posspeed-link.yaml"
SIMNOG = ROOT / "specs" / "simnog-decentralized-pid.yaml"


def _kind(path: Path) -> str | None:
    data = yaml.safe_load(path.read_text())
    return (data.get("controller") or {}).get("kind") if isinstance(data, dict) else None


def _plant_of(path: Path) -> tuple[str, str]:
    data = yaml.safe_load(path.read_text())
    plant = data.get("plant") or {}
    return str(plant.get("kind")), str(plant.get("robot", ""))


def _plant_text(path: Path) -> str:
    """The ``plant`` section of a spec as YAML text."""
    return yaml.safe_dump(yaml.safe_load(path.read_text()).get("plant", {}))


def _specs_of(kind: str) -> list[Path]:
    """The example specs of ``kind``, one per plant (the link, the elastic joint, each robot): the law's C is the
    same code path for every spec of one plant, and designing some (the PUMA 560's proven hierarchy) costs tens of
    seconds."""
    specs = [p for p in SPECS if _kind(p) == kind and "dt:" not in _plant_text(p)]  # a discrete plant: no law
    if not specs:
        pytest.skip(f"no example spec in specs/ has controller.kind: {kind}")
    one = {_plant_of(p): p for p in reversed(specs)}  # the first spec of each plant
    return sorted(one.values(), key=lambda p: (_plant_of(p)[1] == "puma560", _plant_of(p)[0] != "link", p.name))


SPREAD_UNDER_XDIST = True
"""The module fixture is the compiler's name (cheap): the tests stay spread over the workers (tests/conftest.py)."""


@pytest.fixture(scope="module")
def cc() -> str:
    compiler = find_compiler()
    if compiler is None:
        pytest.skip("no C compiler (cc, gcc or clang) on PATH: the generated C cannot be compiled")
    return compiler


def _build(cc: str, sources: list[Path], output: Path, *, shared: bool, include: Path | None = None) -> Path:
    flags = ["-O2", "-fPIC", "-shared"] if shared else ["-std=c99", "-O2"]
    inc = ["-I", str(include)] if include is not None else []
    proc = subprocess.run([cc, *flags, *inc, *map(str, sources), "-o", str(output), "-lm"],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    return output


def _law(loaded):
    dsn = design_of(loaded)
    return dsn, family(dsn.kind).law(dsn, loaded.spec.simulation.anti_windup)


def _sample(name: str, size: int, rng: np.random.Generator) -> np.ndarray:
    if name == "gate":
        return rng.integers(0, 2, size).astype(float)
    scale = {"y": 2.0, "xc": 1.0, "m": 1.0, "r": 2.0, "q": np.pi, "qd": 3.0}.get(name, 1.0)
    return rng.uniform(-scale, scale, size)


def _reference(role: str, dsn, law):
    """The Python route of ``role``: the law's own Function, or the robot model's at the nominal parameters."""
    if role in LAW_ROLES:
        return lambda *args: getattr(law, role).call([ca.DM(a) for a in args])
    if role in MODEL_TERMS:
        f = dsn.plant.robot.functions[MODEL_TERMS[role].robot_function]
        p = dsn.plant.model_parameters()
        n = len(dsn.plant.positions)

        def evaluate(*args):
            given = dict(zip(MODEL_TERMS[role].inputs, args, strict=True))
            full = [given.get(k, np.zeros(n)) if k != "p" else p for k in f.name_in()]
            return f.call([ca.DM(a) for a in full])
        return evaluate
    return lambda *args: law.exports[role].call([ca.DM(a) for a in args])


def _scaled_error(a, b) -> float:
    a, b = np.asarray(ca.DM(a)).ravel(order="F"), np.asarray(ca.DM(b)).ravel(order="F")
    assert a.shape == b.shape
    return float(np.max(np.abs(a - b) / (1 + np.abs(b)), initial=0.0))


def _check_compiled(cc: str, code: LawCode, dsn, law, seed: int) -> int:
    """Every exported function through the compiled library against Python; returns the number of evaluations."""
    library = _build(cc, [code.source], code.directory / f"lib{code.name}.so", shared=True)
    rng = np.random.default_rng(seed)
    count = 0
    for gf in code.functions:
        compiled = ca.external(gf.symbol, str(library))
        assert compiled.name_in() == [p.name for p in gf.inputs]
        assert compiled.name_out() == [p.name for p in gf.outputs]
        reference = _reference(gf.role, dsn, law)
        for _ in range(N_SAMPLES):
            args = [_sample(p.name, p.size, rng) for p in gf.inputs]
            got = compiled.call([ca.DM(a) for a in args])
            want = reference(*args)
            for g, w in zip(got, want, strict=True):
                assert _scaled_error(g, w) <= TOL["algebra"], (gf.symbol, args)
            count += 1
    return count


@pytest.mark.parametrize("kind", slow_cases(sorted(FAMILIES), {"pid_sliding_mode"}, str))
def test_compiled_c_matches_python_law(kind, cc, tmp_path):
    for k, spec in enumerate(_specs_of(kind)):
        loaded = load_spec(spec)
        dsn, law = _law(loaded)
        code = generate_law_code(dsn, law, tmp_path, spec_name=loaded.spec.name, spec_sha256=loaded.sha256)
        assert [f.role for f in code.functions[:5]] == list(LAW_ROLES)
        assert code.source.read_text().count("int main(") == 0
        assert re.findall(r"#include\s*<([^>]+)>", code.source.read_text()) == ["math.h"]
        assert _check_compiled(cc, code, dsn, law, seed=100 + k) == N_SAMPLES * len(code.functions)


def _doc_example(prefix: str) -> str:
    blocks = re.findall(r"```c\n(.*?)```", DOC.read_text(), re.S)
    examples = [b for b in blocks if "int main(" in b]
    assert len(examples) == 1, "docs/codegen.md has one C program"
    return examples[0].replace("posspeed_link", prefix)


@pytest.mark.parametrize("kind", sorted(FAMILIES))
def test_documented_c_example_matches_python_law(kind, cc, tmp_path):
    loaded = load_spec(_specs_of(kind)[0])
    dsn, law = _law(loaded)
    code = codegen(loaded, tmp_path / "out")
    (tmp_path / "example.c").write_text(_doc_example(code.name))
    exe = _build(cc, [tmp_path / "example.c", code.source], tmp_path / "example", shared=False,
                 include=code.directory)
    rng = np.random.default_rng(7)
    cmd = code.function("command")
    samples = [[_sample(p.name, p.size, rng) for p in cmd.inputs] for _ in range(N_SAMPLES)]
    text = "\n".join(" ".join(f"{x:.17g}" for a in s for x in a) for s in samples) + "\n"
    out = subprocess.run([str(exe)], input=text, capture_output=True, text=True, check=True).stdout
    rows = [np.array(line.split(), dtype=float) for line in out.strip().splitlines()]
    assert len(rows) == N_SAMPLES
    for s, row in zip(samples, rows, strict=True):
        assert _scaled_error(row, law.command.call([ca.DM(a) for a in s])[0]) <= TOL["algebra"]


def test_documented_example_output(cc, tmp_path):
    """The number printed in docs/codegen.md is what the example prints."""
    code = codegen(SERVO, tmp_path / "codegen")
    (tmp_path / "example.c").write_text(_doc_example(code.name))
    exe = _build(cc, [tmp_path / "example.c", code.source], tmp_path / "example", shared=False,
                 include=code.directory)
    doc = DOC.read_text()
    shown = re.search(r'echo "0\.5 0 0   1 0 0" \| \./example.*\n(\S+)\n', doc).group(1)
    out = subprocess.run([str(exe)], input="0.5 0 0   1 0 0\n", capture_output=True, text=True, check=True).stdout
    assert out.strip() == shown


def test_every_model_term_and_law_export(cc, tmp_path):
    loaded = load_spec(SIMNOG)
    dsn, law = _law(loaded)
    dsn = dataclasses.replace(dsn, extra={**dsn.extra, "codegen_terms": list(MODEL_TERMS)})
    y, xc, m, r = (law.command.sx_in(i) for i in range(4))
    twice = ca.Function("twice_u", [y, xc, m, r], [2 * law.command(y, xc, m, r)], ["y", "xc", "m", "r"], ["u2"])
    object.__setattr__(law, "exports", {"twice_u": twice})
    code = generate_law_code(dsn, law, tmp_path, spec_name="simnog-all-terms")
    assert [f.role for f in code.functions] == [*LAW_ROLES, *MODEL_TERMS, "twice_u"]
    assert code.function("D_hat").outputs[0].shape == "[2x2]"
    assert code.function("J").outputs[0].shape == "[6x2]"
    assert code.function("h_hat").signature == "simnog_all_terms_h_hat(q[2], qd[2]) -> (h_hat[2])"
    _check_compiled(cc, code, dsn, law, seed=3)


def test_terms_are_the_ones_the_family_declares(tmp_path):
    text = SIMNOG.read_text().replace("zero: -3}", "zero: -3, gravity_feedforward: none}")
    dsn, law = _law(parse_spec(text))
    code = generate_law_code(dsn, law, tmp_path, spec_name="no-gravity")
    assert [f.role for f in code.functions] == list(LAW_ROLES)
    servo = codegen(SERVO, tmp_path)
    assert [f.role for f in servo.functions] == list(LAW_ROLES)
    assert [f.role for f in codegen(SIMNOG, tmp_path).functions] == [*LAW_ROLES, "g_hat"]


def test_law_source_is_the_file_written(tmp_path):
    """``law_source`` (what the ``generated_code`` check compiles) is the ``.c`` file ``generate_law_code`` writes,
    byte for byte, model terms included; it writes nothing."""
    for spec, prefix in ((SERVO, "posspeed_link"), (SIMNOG, "simnog_pid")):
        dsn, law = _law(load_spec(spec))
        code = generate_law_code(dsn, law, tmp_path / "out", name=prefix, spec_name=spec.stem)
        before = sorted(tmp_path.rglob("*"))
        assert law_source(dsn, law, name=prefix, spec_name=spec.stem) == code.source.read_text(encoding="utf-8")
        assert sorted(tmp_path.rglob("*")) == before
    with pytest.raises(SpecError, match="name"):
        law_source(dsn, law, name="1bad")


def test_two_controllers_link_into_one_library(cc, tmp_path):
    codes = [codegen(spec, tmp_path) for spec in (SERVO, ROOT / "specs" / "tracking-pid.yaml", SIMNOG)]
    library = _build(cc, [c.source for c in codes], tmp_path / "libboth.so", shared=True)
    for c in codes:
        assert ca.external(c.function("command").symbol, str(library)).name_out() == ["u"]


def test_c_identifier_and_bad_arguments(tmp_path):
    assert c_identifier("simnog-decentralized-pid") == "simnog_decentralized_pid"
    assert c_identifier("3link.v2") == "spec_3link_v2"
    loaded = load_spec(SERVO)
    dsn, law = _law(loaded)
    for bad in ("bad-name", "9lives", "a b", "", "x" * 65):
        with pytest.raises(SpecError) as err:
            generate_law_code(dsn, law, tmp_path / "out", name=bad)
        assert err.value.path == "name"
    with pytest.raises(SpecError) as err:
        generate_law_code(dsn, law, tmp_path / "out", spec_name="../escape")
    assert err.value.path == "spec_name"
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    with pytest.raises(SpecError) as err:
        generate_law_code(dsn, law, blocker / "sub", spec_name="x")
    assert err.value.path == "out_dir" and "\n" not in str(err.value)
    with pytest.raises(SpecError) as err:
        codegen(SERVO, tmp_path / "out", name="a b")
    assert err.value.path == "name"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]
    assert blocker.read_text() == "not a directory"


def test_rewrite_is_atomic(tmp_path, monkeypatch):
    import designkit.synthesis.codegen as module

    first = codegen(SERVO, tmp_path)
    before = {p: p.read_bytes() for p in first.files}
    second = codegen(SERVO, tmp_path)
    assert {p: p.read_bytes() for p in second.files} == before  # deterministic, same names
    assert sorted(p.name for p in first.directory.iterdir()) == ["posspeed_link.c", "posspeed_link.h"]

    def failing_replace(src, dst):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(module.os, "replace", failing_replace)
    with pytest.raises(SpecError, match="out_dir: cannot write the C code"):
        codegen(SERVO, tmp_path, name="other")
    assert sorted(p.name for p in first.directory.iterdir()) == ["posspeed_link.c", "posspeed_link.h"]
    with pytest.raises(SpecError):
        codegen(SERVO, tmp_path / "fresh" / "deeper")
    assert not (tmp_path / "fresh").exists()


# --- the command line ------------------------------------------------------------------------------------------


def test_cli_codegen_end_to_end(tmp_path, capsys):
    out = tmp_path / "cli"
    assert main(["codegen", str(SIMNOG), "--out", str(out)]) == 0
    printed = capsys.readouterr().out.splitlines()
    written = [Path(line.removeprefix("wrote ")) for line in printed if line.startswith("wrote ")]
    folder = out / "simnog-decentralized-pid"
    assert written == [folder / "simnog_decentralized_pid.c", folder / "simnog_decentralized_pid.h"]
    assert "simnog_decentralized_pid_command" in printed[0] and "simnog_decentralized_pid_g_hat" in printed[0]
    api = codegen(SIMNOG, tmp_path / "api")
    assert [p.read_bytes() for p in written] == [p.read_bytes() for p in api.files]

    header = written[1].read_text()
    assert hashlib.sha256(SIMNOG.read_bytes()).hexdigest() in header
    assert "simnog-decentralized-pid" in header
    for line in ("arg[0] y[4]: measured plant state: q1 (rad), q2 (rad), qd1 (rad/s), qd2 (rad/s)",
                 "arg[1] xc[2]: controller state: x3_1 (rad*s), x3_2 (rad*s)",
                 "arg[2] m[0]: discrete memory: none",
                 "arg[3] r[6]: reference: xD1..xD2 (rad)",
                 "arg[4] gate[2]:",
                 "res[0] u[2]: commanded plant inputs: u1 (N*m), u2 (N*m)",
                 "arg[0] q[2]: joint positions: q1 (rad), q2 (rad)",
                 "res[0] g_hat[2]: nominal gravity torques",
                 "K1 = [385.33333333333337, 32.000000000000007] N*m/rad: proportional",
                 "gravity_feedforward: \"measured\"",
                 "#define simnog_decentralized_pid_N_R 6"):
        assert line in header, line
    for role in LAW_ROLES:
        assert f"int simnog_decentralized_pid_{role}(const casadi_real** arg" in header


def test_cli_codegen_default_folder_and_name(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["codegen", str(SERVO), "--name", "servo"]) == 0
    assert "wrote codegen/posspeed-link/servo.c" in capsys.readouterr().out
    assert "servo_command" in (tmp_path / "codegen" / "posspeed-link" / "servo.h").read_text()


@pytest.mark.parametrize(("args", "message"), [
    (["missing.yaml"], "designkit: error: spec file not found"),
    ([str(SERVO), "--out", "{file}"], "designkit: error: --out: cannot write the C code"),
    ([str(SERVO), "--name", "not-an-identifier"], "designkit: error: --name: must be a C identifier"),
], ids=["missing-spec", "out-is-a-file", "bad-name"])
def test_cli_codegen_bad_input(args, message, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    argv = ["codegen", *[a.replace("{file}", str(blocker)) for a in args]]
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.startswith(message) and captured.err.count("\n") == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]
    assert blocker.read_text() == "not a directory"
