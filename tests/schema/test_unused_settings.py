"""Every setting a spec gives is used by its family or refused with its key path (``Family.uses``,
``Family.plant_fields``)."""

from __future__ import annotations

import re

import pytest

from designkit.errors import SpecError
from designkit.families import FAMILIES
from designkit.schema.loader import parse_spec
from designkit.synthesis.family import SETTINGS
from tests.problems import CASES, case_yaml

# one conformance case per family, on its first canonical plant
FIRST = {kind: next(iter(plants)) for kind, plants in CASES.items()}

# each optional setting as text added to a conformance spec
ADD = {
    "simulation.anti_windup": ("simulation", "anti_windup: {kind: saturation, value: 1.0}"),
    "plant.uncertainty.grid": ("plant", "grid: 4"),
    "plant.uncertainty.samples": ("plant", "samples: 3"),
}


LINEAR = ("transfer_function", "state_space")
DISCRETE_ILC = """\
name: discrete-ilc
plant: {kind: state_space, dt: 1.0, A: [[-0.8, -0.22], [1, 0]], B: [[0.5], [1]], C: [[1, 0.5]]}
controller: {kind: ilc, trials: 3, learning: {kind: p_type, gain: 0.5}}
simulation: {duration: 50, trajectory: {kind: sine, amplitude: 1.0, frequency: 0.02}}
"""


def _with_dt(kind: str) -> str:
    """A spec of the family on a discrete-time linear plant: its linear conformance case with ``dt`` (skipped for a
    family with none, whose plant kinds refuse a linear plant before its settings are read)."""
    if kind == "ilc":
        return DISCRETE_ILC
    linear = [p for p in CASES[kind] if p in LINEAR]
    if not linear:
        pytest.skip(f"the {kind} family takes no linear plant")
    text = case_yaml(kind, linear[0])
    plant_line = next(line for line in text.splitlines() if line.startswith("plant: "))
    return text.replace(plant_line, plant_line[:-1] + ", dt: 0.01}")


def _with(kind: str, key: str) -> str:
    """The family's conformance spec with the setting ``key`` given (a parameter box added when it has none)."""
    if key == "plant.dt":
        return _with_dt(kind)
    text = case_yaml(kind, FIRST[kind])
    plant_line = next(line for line in text.splitlines() if line.startswith("plant: "))
    if key == "simulation.anti_windup":
        sim = next(line for line in text.splitlines() if line.startswith("simulation: "))
        return text.replace(sim, sim[:-1].rstrip() + (", " if sim.strip() != "simulation: {}" else "")
                            + ADD[key][1] + "}")
    if "uncertainty" not in plant_line:
        box = "{Km: [1.8, 2.2]}" if "kind: link" in plant_line else (
            "{m2: [2.5, 3.5]}" if "planar2r" in plant_line else None)
        if box is None:
            pytest.skip(f"no parameter box written for {plant_line}")
        new = plant_line[:-1] + f", uncertainty: {box}}}"
        text, plant_line = text.replace(plant_line, new), new
    if key == "plant.uncertainty":
        return text
    box = re.search(r"uncertainty: \{[^}]*\}", plant_line).group(0)
    name = ADD[key][1].split(":")[0]
    bare = re.sub(rf", {name}: \d+", "", box)
    return text.replace(box, bare[:-1] + ", " + ADD[key][1] + "}")


CASES_UNUSED = [(kind, key) for kind in sorted(FIRST) for key in SETTINGS if key not in FAMILIES[kind].uses]
CASES_USED = [(kind, key) for kind in sorted(FIRST) for key in SETTINGS if key in FAMILIES[kind].uses]


def test_the_cases_cover_both_sides():
    assert CASES_UNUSED and CASES_USED
    # every family judges a parameter box in some way; the other settings are refused by some family
    assert all("plant.uncertainty" in fam.uses for fam in FAMILIES.values())
    assert {key for _, key in CASES_UNUSED} == set(SETTINGS) - {"plant.uncertainty"}


@pytest.mark.parametrize(("kind", "key"), CASES_UNUSED, ids=lambda v: str(v))
def test_a_setting_the_family_does_not_use_is_refused(kind, key):
    with pytest.raises(SpecError) as info:
        parse_spec(_with(kind, key))
    message = str(info.value)
    # the first unused setting given is the one named (a box given to a family without one names plant.uncertainty)
    named = message.split(":", 1)[0]
    assert named.startswith("plant.uncertainty") if key.startswith("plant.uncertainty") else named == key
    assert f"the {kind} controller does not use it" in message


@pytest.mark.parametrize(("kind", "key"), CASES_USED, ids=lambda v: str(v))
def test_a_setting_the_family_uses_is_accepted(kind, key):
    spec = parse_spec(_with(kind, key)).spec
    assert spec.controller.kind == kind


def test_declared_lattice_settings_follow_the_checks_offered():
    """The box's lattice is read by robust_grid (the robustness check), its samples by robustness, tracking_bounds
    and box_runs: a family declares them exactly when it offers one of these."""
    for fam in FAMILIES.values():
        names = {c if isinstance(c, str) else c.name for c in fam.checks}
        assert ("plant.uncertainty.grid" in fam.uses) == ("robustness" in names), fam.kind
        reads_samples = bool(names & {"robustness", "tracking_bounds", "box_runs"})
        assert ("plant.uncertainty.samples" in fam.uses) == reads_samples, fam.kind


def test_anti_windup_is_declared_only_by_families_whose_law_has_an_integral():
    """A family that honours an anti-windup has an integral to limit (one with an integral may still refuse it:
    the PID/sliding-mode law's integral is part of its sliding variable)."""
    from designkit import pipeline
    from designkit.schema.loader import parse_spec as parse

    for kind in sorted(FIRST):
        loaded = parse(case_yaml(kind, FIRST[kind]))
        design = pipeline.design(loaded)
        if "simulation.anti_windup" in FAMILIES[kind].uses:
            assert design.law.integral_states, kind


def test_workspace_on_a_link_pid_sliding_mode_is_refused():
    text = case_yaml("pid_sliding_mode", "link").replace("kind: pid_sliding_mode", "kind: pid_sliding_mode, "
                                                         "workspace: joint_limits")
    with pytest.raises(SpecError, match=r"^controller\.workspace: the pid_sliding_mode controller reads it on a "
                                        r"robot plant only .* not on the link plant"):
        parse_spec(text)


@pytest.mark.parametrize("field", ["gravity_feedforward: none", "work_limit: 20"])
def test_other_robot_fields_on_a_link_are_refused(field):
    text = case_yaml("pid_sliding_mode", "link").replace("kind: pid_sliding_mode", f"kind: pid_sliding_mode, {field}")
    with pytest.raises(SpecError, match=rf"^controller\.{field.split(':')[0]}: "):
        parse_spec(text)


def test_anti_windup_on_ilc_is_refused_by_the_cli(tmp_path, capsys):
    from designkit.cli import main

    path = tmp_path / "ilc.yaml"
    path.write_text(_with("ilc", "simulation.anti_windup"))
    code = main(["verify", str(path)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1
    assert err[0].startswith("designkit: error: simulation.anti_windup: the ilc controller does not use it")


def test_a_default_value_written_out_is_not_refused():
    """A canonical dump writes every default (``grid: 21``, ``workspace: null``): it gives nothing and passes."""
    from designkit.schema.loader import LoadedSpec

    loaded = parse_spec(case_yaml("sliding_mode", "link"))
    again = parse_spec(LoadedSpec.from_spec(loaded.spec).text)
    assert again.spec == loaded.spec


# requirements: each is judged by a check that reads it (CheckRule.reads), or refused
REQUIREMENT_VALUES = {"overshoot": "5", "settling_time": "2.0", "rise_time": "1.0", "steady_state_error": "0.01",
                      "tracking_error": "0.1", "max_control": "100", "settling_band": "0.05", "gain_margin": "6",
                      "phase_margin": "40", "modulus_margin": "0.5",
                      "max_reversal_rate": "1000", "max_command_variation": "1000", "max_chatter_amplitude": "1.0"}


def _reads(kind: str) -> set[str]:
    from designkit.verification.suite import resolve

    return {key for rule in resolve(FAMILIES[kind].checks) for key in rule.reads}


def test_every_requirement_is_read_by_some_check():
    """A requirement is read by a generic check, or by a family's own check (``max_chatter_amplitude``, by the
    switching families' chattering checks)."""
    from designkit.spec.sections import Requirements
    from designkit.verification.suite import generic

    read = {key for rule in generic().values() for key in rule.reads}
    read |= {key for kind in FAMILIES for key in _reads(kind)}
    assert read == {f"requirements.{k}" for k in Requirements.model_fields} == {
        f"requirements.{k}" for k in REQUIREMENT_VALUES}


@pytest.mark.parametrize("kind", sorted(FIRST))
def test_a_requirement_no_check_of_the_family_reads_is_refused(kind):
    base = case_yaml(kind, FIRST[kind])
    line = next(x for x in base.splitlines() if x.startswith("requirements: "))
    for name, value in REQUIREMENT_VALUES.items():
        text = base.replace(line, f"requirements: {{{name}: {value}}}")
        if f"requirements.{name}" in _reads(kind):
            assert parse_spec(text).spec.requirements is not None
        else:
            with pytest.raises(SpecError, match=rf"^requirements\.{name}: no check of the {kind} controller measures"):
                parse_spec(text)


def test_margins_on_a_sliding_mode_law_are_refused():
    """The sliding-mode law has no linear loop to break: its margins cannot be measured."""
    text = case_yaml("sliding_mode", "link")
    line = next(x for x in text.splitlines() if x.startswith("requirements: "))
    with pytest.raises(SpecError, match=r"^requirements\.gain_margin: "):
        parse_spec(text.replace(line, "requirements: {gain_margin: 6}"))
