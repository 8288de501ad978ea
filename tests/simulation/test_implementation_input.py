"""Bad ``implementation:`` sections: refused with the key path (exit 2 from ``designkit verify``, one line, nothing
written; :class:`~designkit.errors.SpecError` from the API); the section is accepted by every family's spec."""

from __future__ import annotations

from pathlib import Path

import pytest

from designkit.cli import main
from designkit.errors import SpecError
from designkit.schema.loader import parse_spec
from designkit.simulation.run import build
from tests.simulation.helpers import design_of

ROOT = Path(__file__).resolve().parents[2]
LINK = """\
name: impl-input
plant: {kind: link, Km: 2.0, tau: 0.5}
controller: {kind: pid_servo, poles: [-4, -5, -20], zero: -3}
"""


def _verify(tmp_path: Path, capsys, text: str) -> tuple[int, str, str]:
    spec = tmp_path / "spec.yaml"
    spec.write_text(text)
    before = sorted(p.name for p in tmp_path.iterdir())
    code = main(["verify", str(spec)])
    captured = capsys.readouterr()
    assert sorted(p.name for p in tmp_path.iterdir()) == before  # nothing written
    return code, captured.out, captured.err


BUILD_ERRORS = [
    # (spec text, key path, words in the message)
    (LINK + "simulation: {duration: 3.0}\nimplementation: {sampling_period: 5.0}\n",
     "implementation.sampling_period", "not shorter than the run (3 s"),
    (LINK + "implementation: {sampling_period: 100.0}\n",  # the default duration, 2.5 s
     "implementation.sampling_period", "not shorter than the run (2.5 s"),
    (LINK + "simulation: {duration: 3.0}\nimplementation: {delay: 4.0}\n",
     "implementation.delay", "not shorter than the run (3 s"),
    (LINK + "simulation: {duration: 3.0, dt: 0.001}\nimplementation: {sampling_period: 0.0015}\n",
     "simulation.dt", "must divide implementation.sampling_period = 0.0015 s"),
    (LINK + "simulation: {duration: 3.0, dt: 0.001}\nimplementation: {delay: 0.0025}\n",
     "simulation.dt", "must divide implementation.delay = 0.0025 s"),
    (LINK + "simulation: {duration: 3.0, sampling_period: 0.002}\nimplementation: {sampling_period: 0.001}\n",
     "implementation.sampling_period", "conflicts with simulation.sampling_period = 0.002 s"),
    (LINK + "simulation: {duration: 3.0, delay: 0.002}\nimplementation: {delay: 0.001}\n",
     "implementation.delay", "conflicts with simulation.delay = 0.002 s"),
    (LINK + "simulation: {duration: 3.0}\nimplementation: {quantization: [0.1, 0.1, 0.1]}\n",
     "implementation.quantization", "one per measured state (2), got 3"),
    (LINK + "simulation: {duration: 3.0}\nimplementation: {actuator: {limit: [1.0, 2.0]}}\n",
     "implementation.actuator.limit", "one per input (1), got 2"),
    (LINK + "simulation: {duration: 3.0}\nimplementation: {actuator: {bandwidth: [10.0, 20.0]}}\n",
     "implementation.actuator.bandwidth", "one per input (1), got 2"),
    (LINK + "simulation: {duration: 3.0}\nimplementation: {sampling_period: 1.0e-6}\n",
     "implementation.sampling_period", "1e-06 s sets the integration step"),
    (LINK + "simulation: {duration: 3.0}\nimplementation: {delay: 1.0e-6}\n",
     "implementation.delay", "3 s needs at least 3000000 steps"),
    (LINK + "simulation: {duration: 3.0}\nimplementation: {delay: 1.0e-4, actuator: {bandwidth: 1.0e+6}}\n",
     "implementation.actuator.bandwidth", "1e+06 rad/s sets the integration step"),
]

MODEL_ERRORS = [
    (LINK + "implementation: {sampling_period: 0}\n", "implementation.sampling_period"),
    (LINK + "implementation: {sampling_period: -0.001}\n", "implementation.sampling_period"),
    (LINK + "implementation: {delay: -0.001}\n", "implementation.delay"),
    (LINK + "implementation: {quantization: 0}\n", "implementation.quantization"),
    (LINK + "implementation: {actuator: {limit: -5}}\n", "implementation.actuator.limit"),
    (LINK + "implementation: {actuator: {bandwidth: 0}}\n", "implementation.actuator.bandwidth"),
    (LINK + "implementation: {actuator: {lag: 3}}\n", "implementation.actuator.lag"),
    (LINK + "implementation: {period: 3}\n", "implementation.period"),
]


@pytest.mark.parametrize(("text", "key", "words"), BUILD_ERRORS, ids=[f"{c[1]}-{k}" for k, c in
                                                                        enumerate(BUILD_ERRORS)])
def test_bad_implementation_is_refused_by_verify_and_the_api(tmp_path, capsys, text, key, words):
    code, out, err = _verify(tmp_path, capsys, text)
    assert code == 2, err
    assert err.startswith(f"designkit: error: {key}: ") and err.count("\n") == 1, err
    assert words in err and out == ""
    spec = parse_spec(text).spec
    with pytest.raises(SpecError) as exc:
        build(spec, design_of(spec))
    assert exc.value.path == key and words in exc.value.message


@pytest.mark.parametrize(("text", "key"), MODEL_ERRORS, ids=[c[1] for c in MODEL_ERRORS])
def test_non_positive_and_unknown_values_are_refused_naming_the_key(tmp_path, capsys, text, key):
    code, out, err = _verify(tmp_path, capsys, text)
    assert code == 2 and err.startswith(f"designkit: error: {key}") and err.count("\n") == 1, err
    with pytest.raises(SpecError) as exc:
        parse_spec(text)
    assert exc.value.path == key


def test_a_law_with_its_own_period_refuses_another_implemented_period(tmp_path, capsys):
    text = (ROOT / "specs" / "selftune-speed.yaml").read_text() + "implementation: {sampling_period: 0.005}\n"
    code, _, err = _verify(tmp_path, capsys, text)
    assert code == 2 and err.startswith("designkit: error: implementation.sampling_period: "), err
    assert "controller.sampling_period" in err and "0.01" in err


def test_the_section_is_not_refused_as_an_unused_setting_by_any_family():
    from designkit.schema.spec import given_settings

    text = (ROOT / "specs" / "sliding-mode-link.yaml").read_text() + "implementation: {sampling_period: 0.001}\n"
    spec = parse_spec(text).spec
    assert spec.implementation.sampling_period == 0.001
    assert not any(k.startswith("implementation") for k in given_settings(spec))


def test_a_comparison_applies_the_section_to_every_controller():
    text = (ROOT / "specs" / "mrac-vs-selftune.yaml").read_text() + "implementation: {delay: 0.001}\n"
    from designkit.schema.loader import parse_spec as parse

    loaded = parse(text)
    members = loaded.spec.members()
    assert len(members) >= 2 and all(m.implementation.delay == 0.001 for _, m in members)


def test_a_sweep_refuses_the_section(tmp_path, capsys):
    from tests.sweep.specs import link, write

    spec = write(tmp_path, link() + "implementation: {sampling_period: 0.001}\n")
    out = tmp_path / "out"
    code = main(["sweep", str(spec), "--out", str(out), "--samples", "4"])
    err = capsys.readouterr().err
    assert code == 2 and err.startswith("designkit: error: implementation: ") and err.count("\n") == 1, err
    assert not out.exists() or not any(out.rglob("*"))
