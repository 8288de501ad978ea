"""The bad-input contract on a seeded, bounded corpus of mutated specs (``tests/fuzz.py``).

Every mutant of the fast example specs goes through ``designkit verify --json``: the exit code is
0, 1 or 2, and on 2 there is exactly one ``designkit: error: <key path>: ...`` line, no traceback
and nothing written.  The first mutants that are accepted also go through ``designkit synth``
(reports written), which must give the same exit code.  ``python -m tests.fuzz N SEED`` runs a
larger campaign over every spec.
"""

from __future__ import annotations

import pytest

from tests.fuzz import ROOT, mutants, outcome, violations

FAST_SPECS = [ROOT / "specs" / f"{name}.yaml" for name in ("posspeed-link", "tracking-pid", "requirements-driven",
                                                            "posspeed-saturation")]
N_MUTANTS = 48
"""Mutants per seed in the suite (about 20 s on one core: most are refused at load time)."""
N_SYNTH = 2
"""Accepted mutants also run through ``synth`` with reports."""


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
