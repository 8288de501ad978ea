"""Every registered family through the whole pipeline on the canonical problems (tests/problems.py).

For each family and each canonical plant it is designed for: the spec round-trips through its
JSON Schema; the pipeline synthesises, simulates and verifies; every check the family offers
and the design exposes actually runs; every decided check's evidence is re-checked here with
NumPy (not by the module that produced it); the report renders in both formats.
"""

from __future__ import annotations

import json

import jsonschema
import numpy as np
import pytest
import yaml
from pydantic import TypeAdapter

from designkit.families import FAMILIES, check_rules
from designkit.pipeline import run
from designkit.report import write_report
from designkit.schema.loader import parse_spec
from designkit.schema.spec import Spec
from designkit.spec.plants import PlantSpec
from designkit.verification.lmi import lyapunov_recheck
from designkit.verification.suite import Context
from tests.marks import slow_cases
from tests.problems import CASES, PLANTS, case_yaml

CASE_IDS = [(kind, plant) for kind, plants in CASES.items() for plant in plants]


def test_every_family_has_a_case_on_every_canonical_plant_it_accepts():
    plant_kinds = {name: TypeAdapter(PlantSpec).validate_python(yaml.safe_load(text)).kind
                   for name, text in PLANTS.items()}
    for kind, fam in FAMILIES.items():
        assert kind in CASES, f"family {kind} has no conformance case in tests/problems.py"
        accepted = {name for name, pk in plant_kinds.items() if pk in fam.plants}
        if "plant.dt" in fam.uses:  # learning on a linear plant refuses the canonical plants' parameter boxes: its
            accepted -= {name for name, pk in plant_kinds.items() if pk in ("transfer_function", "state_space")}
            # cases are tests/families/ilc/test_linear.py's (Moore's plant, a continuous plant by ZOH)
        assert accepted <= set(CASES[kind]), f"{kind}: no case for {sorted(accepted - set(CASES[kind]))}"


class _Runs(dict):
    """Each case's parsed spec and pipeline result, run the first time a test asks for it (under pytest-xdist a
    worker runs only the cases of the tests it is given)."""

    def __missing__(self, case):
        loaded = parse_spec(case_yaml(*case))
        self[case] = (loaded, run(loaded))
        return self[case]


SPREAD_UNDER_XDIST = True
"""The runs fill lazily per case, so the tests stay spread over the workers (tests/conftest.py)."""


@pytest.fixture(scope="module")
def results():
    return _Runs()


@pytest.mark.parametrize(("kind", "plant"), CASE_IDS, ids=[f"{k}-{p}" for k, p in CASE_IDS])
def test_spec_round_trips_through_the_json_schema(kind, plant):
    loaded = parse_spec(case_yaml(kind, plant))
    data = json.loads(loaded.spec.model_dump_json())
    jsonschema.validate(data, Spec.model_json_schema())
    assert Spec.model_validate(data) == loaded.spec


@pytest.mark.parametrize(("kind", "plant"), slow_cases(CASE_IDS, {"pid_sliding_mode-puma560"}, lambda c: "-".join(c)))
def test_pipeline_runs_offered_checks_and_their_evidence_rechecks(kind, plant, results, tmp_path):
    loaded, result = results[kind, plant]
    design, checks = result.design, result.checks
    assert design.kind == kind and result.simulation is not None
    assert np.all(np.isfinite(result.simulation.state))
    names = [c.name for c in checks]
    ctx = Context(loaded.spec, result.simulation, "CLARABEL", result.plant, design.law, result.trials)
    rules = check_rules(kind)
    for rule in rules:
        if rule.offered_for(design, ctx):  # what the design exposes, the suite must run
            assert all(c.name in names for c in rule.run(design, ctx)), (rule.name, names)
    if not design.linearization.linear:  # the contract says none: no check that reads a linear loop is offered
        assert not any(r.offered_for(design, ctx) for r in rules if r.linear)
    for check in checks:
        assert check.passed in (True, False, None) and check.detail
        json.dumps(check.to_dict())
        _recheck(check, design, result)
    assert result.verified, [(c.name, c.detail) for c in result.failed]
    files = write_report(result, tmp_path, studies=False)
    html = files.html.read_text().replace("<wbr>", "")
    from html import unescape

    from designkit.report.labels import check_label

    text = unescape(html)
    assert all(check_label(c) in text for c in checks), [c.name for c in checks if check_label(c) not in text]
    assert files.pdf.read_bytes().startswith(b"%PDF")


def _recheck(check, design, result) -> None:
    """Re-decide a check from its own evidence with NumPy, where the evidence is self-contained."""
    base = check.name.split("[")[0]
    loop = design
    if "[" in check.name:
        loop = design.loops[design.loop_names.index(check.name.split("[")[1].rstrip("]"))]
    cert = check.certificate
    if base == "lyapunov" and check.passed is True:
        if "equation_route" in cert:  # a stiff loop: the equation's P, exact to its rounding bounds
            A, P = loop.closed_loop.A, np.array(cert["equation_route"]["P"])
            assert np.all(np.linalg.eigvalsh(P) > 0) and np.all(np.linalg.eigvalsh(A.T @ P + P @ A) < 0)
        else:
            assert lyapunov_recheck([loop.closed_loop.A], np.array(cert["P"])).ok
    if base == "pole_placement":
        got = np.sort_complex(np.linalg.eigvals(loop.closed_loop.A))
        want = np.sort_complex(np.array(loop.poles, dtype=complex))
        assert bool(np.max(np.abs(got - want)) <= 1e-6 * np.max(np.abs(want))) is bool(check.passed)
    if base == "robust_box" and check.passed is True:
        lo = {n: v[0] for n, v in result.loaded.spec.plant.uncertainty.intervals.items()}
        hi = {n: v[1] for n, v in result.loaded.spec.plant.uncertainty.intervals.items()}
        for cond in design.characteristic.linear_conditions(design.gains):
            for corner in np.array(np.meshgrid(*[[lo[n], hi[n]] for n in lo])).T.reshape(-1, len(lo)):
                assert cond.value(**dict(zip(lo, corner, strict=True))) > 0
    if base == "singularity":  # the worst condition number again, from the robot's own Jacobian
        robot, p = design.plant.robot, design.plant.model_parameters()
        J = robot.jacobian(np.array(cert["worst_configuration"]), p=p)
        rows = list(design.motion.space.rows)
        sv = np.linalg.svd(J[rows, :], compute_uv=False)
        assert sv[0] / sv[-1] == pytest.approx(cert["worst_condition"], rel=1e-6)
        if design.motion.damping is None:
            assert bool(cert["worst_condition"] <= cert["max_condition_allowed"]) is bool(check.passed)
    if base in ("robust_vertices", "robust_grid") and check.passed is True:
        assert check.margin > 0
    if base in ("overshoot", "settling_time", "steady_state_error") and check.achieved is not None:
        assert bool(check.margin >= 0) is bool(check.passed)
