"""The bad-input contract on a seeded, bounded corpus of mutated specs (``tests/fuzz.py``).

Every mutant of the fast example specs goes through ``designkit verify --json``: the exit code is
0, 1 or 2, and on 2 there is exactly one ``designkit: error: <key path>: ...`` line, no traceback
and nothing written.  The first mutants that are accepted also go through ``designkit synth``
(reports written), which must give the same exit code.  ``python -m tests.fuzz N SEED`` runs a
larger campaign over every spec.
"""

from __future__ import annotations

import os

import pytest

from tests.fuzz import ROOT, mutants, outcome, violations
from tests.fuzz_families import (
    COMMANDS,
    COMPARISONS,
    FAMILY_BASES,
    SWEEP_BASE,
    family_mutants,
    family_schema,
    fields,
    run_case,
)
from tests.fuzz_fields import CASE_BUDGET, CASE_CPU, GENERATORS, field_mutants

FAST_SPECS = [ROOT / "specs" / f"{name}.yaml" for name in ("posspeed-link", "tracking-pid", "requirements-driven",
                                                            "posspeed-saturation")]
N_MUTANTS = 48
"""Mutants per seed in the suite (about 20 s on one core: most are refused at load time)."""
N_SYNTH = 2
"""Accepted mutants also run through ``synth`` with reports."""
N_FIELDS = int(os.environ.get("DESIGNKIT_FUZZ_CASES", "42"))
"""Field-targeted mutants in the suite (``tests/fuzz_fields.py``): three per field group by default, about 15 s of
CPU time in all.  A larger campaign: ``DESIGNKIT_FUZZ_CASES=1000 python -m pytest tests/test_fuzz.py -k field``, or
``python -m tests.fuzz 1000 SEED fields``, which prints every case with its exit code and CPU time."""


@pytest.mark.parametrize("seed", [0, 1])
def test_mutated_specs_keep_the_bad_input_contract(seed, tmp_path):
    synth_left = N_SYNTH
    problems = []
    for k, mutant in enumerate(mutants(seed, N_MUTANTS, FAST_SPECS)):
        result = outcome(mutant.text, tmp_path / f"v{k}", "verify")
        for bad in violations(result):
            problems.append(f"#{k} {mutant.source} {mutant.operator} {mutant.path}: {bad}: {result.err.strip()[:200]}")
        if result.code in (0, 1) and synth_left:
            synth_left -= 1
            synth = outcome(mutant.text, tmp_path / f"s{k}", "synth")
            if synth.code != result.code:
                problems.append(f"#{k} {mutant.source} {mutant.operator} {mutant.path}: verify exit {result.code}, "
                                f"synth exit {synth.code}: {synth.err.strip()[:200]}")
    assert not problems, "\n".join(problems)


def test_the_corpus_reaches_every_operator():
    ops = {m.operator for seed in (0, 1) for m in mutants(seed, N_MUTANTS, FAST_SPECS)}
    assert ops == {"value", "delete", "extra", "tag", "alias", "duplicate", "nest", "bomb"}


def test_field_mutants_keep_the_contract_within_their_bounds(tmp_path):
    """Robot names and overrides, DH tables, URDF paths and hostile files, payloads, limits, uncertainty boxes, the
    workspace, the computed-torque and resolved-acceleration options, line, circle and via-point references,
    numerics and per-joint lists: every mutant exits 0, 1 or 2 within its CPU bound under ``--budget``; a refused
    one says so on one line and writes nothing (checked again through ``synth``)."""
    options = ("--jobs", "1", "--budget", f"{CASE_BUDGET:g}")
    problems = []
    for k, mutant in enumerate(field_mutants(0, N_FIELDS, tmp_path / "files")):
        label = f"#{k} {mutant.operator} {mutant.path}"
        result = outcome(mutant.text, tmp_path / f"f{k}", "verify", options, cpu=CASE_CPU)
        problems += [f"{label}: {bad}: {result.err.strip()[:200]}" for bad in violations(result)]
        if result.code == 2:
            synth = outcome(mutant.text, tmp_path / f"fs{k}", "synth", options, cpu=CASE_CPU)
            problems += [f"{label} (synth): {bad}" for bad in violations(synth)]
            if synth.code != 2:
                problems.append(f"{label}: verify refused it, synth exit {synth.code}")
    assert not problems, "\n".join(problems)


def test_the_field_corpus_reaches_every_field_group(tmp_path):
    reached = {m.operator for m in field_mutants(0, N_FIELDS, tmp_path)}
    assert reached == {g.__name__[1:] for g in GENERATORS}


N_FAMILY = int(os.environ.get("DESIGNKIT_FUZZ_FAMILY_CASES", "300"))
"""Schema-driven mutants in the suite (``tests/fuzz_families.py``): about 16 per family, 43 comparison specs, 33
sweeps, a sixth of the family mutants through codegen (about 25 s of CPU time).  A larger campaign:
``DESIGNKIT_FUZZ_FAMILY_CASES=3000 python -m pytest tests/test_fuzz.py -k family``, or
``python -m tests.fuzz_families 3000 SEED``, which prints each violation with a shell repro."""
FAMILY_SEED = int(os.environ.get("DESIGNKIT_FUZZ_SEED", "0"))
"""Seed of the schema-driven corpus."""


def test_family_fields_comparisons_sweeps_and_codegen_keep_the_contract(tmp_path):
    """Every family's controller fields, the requirements, simulation and numerics fields, comparison specs, sweep
    sections and codegen: every mutant exits 0, 1 or 2 within its CPU bound; a refused one says so on one line naming
    a key path and writes nothing."""
    problems = []
    for k, case in enumerate(family_mutants(FAMILY_SEED, N_FAMILY)):
        result = run_case(case, tmp_path / f"c{k}")
        problems += [f"#{k} {case.command} {case.base} {case.path} = {case.value}: {bad}: {result.err.strip()[:200]}"
                     for bad in violations(result)]
    assert not problems, "\n".join(problems)


def test_the_family_corpus_reaches_every_family_comparisons_sweeps_and_codegen():
    cases = family_mutants(0, N_FAMILY)
    assert {c.base for c in cases} == {*FAMILY_BASES.values(), *COMPARISONS, SWEEP_BASE}
    assert {c.command for c in cases} == set(COMMANDS)
    assert any(c.path.startswith("sweep.") for c in cases)


def test_the_walk_reaches_every_field_of_every_family():
    """Every field a family's ``controller`` model declares (read from the pydantic model, not from the schema the
    walk reads) is a field the mutants may change."""
    from designkit.families import FAMILIES

    assert set(FAMILY_BASES) == set(FAMILIES)
    for kind, fam in FAMILIES.items():
        declared = set(fam.spec.model_fields) - {"kind"}
        walked = {path.split(".")[0] for path, _ in fields(family_schema(kind))}
        assert declared == walked, kind
