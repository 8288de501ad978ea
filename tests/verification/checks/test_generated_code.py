"""``generated_code``: the C that ``designkit codegen`` writes, compiled and called at every step of the verified
loop, gives the Python law's loop on every example spec; a gain changed in the C text, a C text the compiler
refuses and a machine without a compiler are each reported as such."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import designkit.families
from designkit.cli import main
from designkit.models.codegen import find_compiler
from designkit.runner.run import run_spec
from designkit.schema.loader import load_spec
from designkit.verification import generated_loop
from designkit.verification.generated_loop import TOLERANCE
from designkit.verification.suite import resolve
from tests.marks import slow_cases

ROOT = Path(__file__).resolve().parents[3]
SPECS = sorted(p.stem for p in (ROOT / "specs").glob("*.yaml"))
SLOW = {"hierarchy-puma560-payload", "hierarchy-puma560", "adaptive-ct-puma560", "robel", "smid-simnog",
        "puma560-computed-torque-payload", "puma560-resolved-acceleration-dls", "puma560-resolved-acceleration",
        "puma560-computed-torque", "scara-decentralized-pid", "mrac-vs-selftune", "smid-simnog-single-step"}
"""Specs whose design and run cost several seconds (a six-joint arm, a comparison of controllers)."""

needs_compiler = pytest.mark.skipif(find_compiler() is None, reason="no C compiler (cc, gcc, clang) on PATH")


@pytest.fixture
def cache(tmp_path, monkeypatch):
    """A fresh designkit cache: every library this test needs is compiled by it."""
    monkeypatch.setenv("DESIGNKIT_CACHE_DIR", str(tmp_path / "cache"))
    return tmp_path / "cache"


def _runs(loaded, monkeypatch):
    """The family's own run of each controller of ``loaded`` with the check (and the universal ones) only."""
    monkeypatch.setattr(designkit.families, "check_rules", lambda kind: resolve(("generated_code",)))
    members = [m for _, m in loaded.members()] if loaded.is_comparison else [loaded]
    return [run_spec(m, box=False, verdict_run=True) for m in members]


def _check(run):
    (check,) = [c for c in run.checks if c.name == "generated_code"]
    return check


@needs_compiler
@pytest.mark.parametrize("name", slow_cases(SPECS, SLOW, str))
def test_every_example_runs_its_generated_code_in_the_loop(name, monkeypatch):
    for run in _runs(load_spec(ROOT / "specs" / f"{name}.yaml"), monkeypatch):
        if run.design.law is None:  # a learned input sequence played to a sampled plant: no law, no code
            assert run.design.learning.run is not None and not [c for c in run.checks if c.name == "generated_code"]
            continue
        check = _check(run)
        cert = check.certificate
        assert check.passed is True and check.required, check.detail
        assert cert["state_relative"] <= TOLERANCE and cert["command_relative"] <= TOLERANCE
        learning = run.design.learning
        assert cert["runs"] == (learning.trials if learning else 1) == (len(run.trials.results) if run.trials else 1)
        assert cert["steps"] == run.simulation.time.size
        assert cert["functions"][0].endswith("_command") and len(cert["functions"]) == 5
        # the scale is the largest finite command over the runs, read here from the verdict's runs (same loop and
        # grid; the integrator may differ, hence 1e-3)
        commands = np.concatenate([r.u_command.ravel() for r in (run.trials.results if run.trials else
                                                                 (run.simulation,))])
        assert cert["command_scale"] == pytest.approx(float(np.abs(commands[np.isfinite(commands)]).max()),
                                                      rel=1e-3, abs=1e-12)


def _plant_gain(text: str) -> tuple[str, float]:
    """``text`` with the first constant written in the command's C function multiplied by 1.001, and the constant."""
    body = text.index("static int casadi_f0(")  # the command: the first function generated (LAW_ROLES)
    found = re.compile(r"(a\d+)=(-?\d+\.\d*(?:e[+-]\d+)?);").search(text, body)
    assert found, "no constant in the command's C function"
    value = float(found.group(2))
    planted = f"{found.group(1)}={value * 1.001!r};"
    return text[:found.start()] + planted + text[found.end():], value


@needs_compiler
def test_a_gain_changed_in_the_c_text_fails_with_the_difference(cache, monkeypatch):
    original = generated_loop.law_source
    seen = {}

    def planted(*args):
        text, seen["value"] = _plant_gain(original(*args))
        return text

    monkeypatch.setattr(generated_loop, "law_source", planted)
    (run,) = _runs(load_spec(ROOT / "specs" / "posspeed-link.yaml"), monkeypatch)
    check = _check(run)
    assert check.passed is False
    assert "largest state difference" in check.detail and "largest command difference" in check.detail
    cert = check.certificate
    assert cert["command_relative"] > TOLERANCE and cert["state_difference"] > 0
    # the posspeed law's first constant, -K1 = -50 N*m/rad, multiplies the position error x1 - xD: at the first step
    # the plant is at rest at 0 and the reference at 1 rad, so the two commands differ there by 0.001 * 50 * 1 N*m
    assert seen["value"] == -50.0
    sim = run.simulation
    error0 = float(sim.state[0, 0] - sim.reference[0, 0, 0])
    assert cert["first_difference_s"] == 0.0
    assert cert["command_difference"] >= 0.001 * 50.0 * abs(error0) * (1 - 1e-9)
    assert f"{cert['command_difference']:.3g}" in check.detail


@needs_compiler
def test_a_planted_gain_makes_verify_exit_1(cache, monkeypatch, capsys):
    original = generated_loop.law_source
    monkeypatch.setattr(generated_loop, "law_source", lambda *args: _plant_gain(original(*args))[0])
    assert main(["verify", "--jobs", "1", str(ROOT / "specs" / "posspeed-link.yaml")]) == 1
    out = capsys.readouterr().out
    assert "generated" in out.lower()


@needs_compiler
def test_c_the_compiler_refuses_fails_with_its_message(cache, monkeypatch):
    original = generated_loop.law_source
    monkeypatch.setattr(generated_loop, "law_source", lambda *args: original(*args) + "\nthis is not C;\n")
    (run,) = _runs(load_spec(ROOT / "specs" / "posspeed-link.yaml"), monkeypatch)
    check = _check(run)
    assert check.passed is False
    assert check.detail.startswith("the generated C does not compile:")
    assert "error" in check.certificate["compiler_message"].lower()
    assert not list(cache.glob("codegen/dk_law_*")) and not list(cache.glob("codegen/tmp*"))  # nothing half-built


def test_without_a_compiler_the_check_is_undecided(monkeypatch):
    monkeypatch.setattr(generated_loop, "find_compiler", lambda: None)
    (run,) = _runs(load_spec(ROOT / "specs" / "posspeed-link.yaml"), monkeypatch)
    check = _check(run)
    assert check.passed is None and check.status == "UNDECIDED" and check.required
    assert "no C compiler" in check.detail


@needs_compiler
def test_the_library_is_cached_by_content(cache, monkeypatch):
    run = run_spec(load_spec(ROOT / "specs" / "posspeed-link.yaml"), box=False)
    first, again = (generated_loop.compare_generated_code(run.loaded.spec, run.design, plant=run.plant)
                    for _ in range(2))
    assert first.compiled_now is True and again.compiled_now is False
    assert first.library == again.library and Path(first.library).parent == cache / "codegen"
    assert Path(first.library).exists()


def test_the_code_compiled_is_the_file_codegen_writes(tmp_path):
    from designkit.pipeline import codegen
    from designkit.pipeline import design as design_of
    from designkit.synthesis.codegen import c_identifier

    path = ROOT / "specs" / "pid-sm-link.yaml"
    written = codegen(path, tmp_path).source.read_text(encoding="utf-8")
    loaded = load_spec(path)
    design = design_of(loaded)
    assert generated_loop.law_source(design, design.law, c_identifier(loaded.spec.name), loaded.spec.name) == written
