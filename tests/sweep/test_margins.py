"""The sweep's per-sample margins against the pipeline's own verdict on the same runs (independent routes):

* each sample run through the single-run simulator and scored by the pipeline's time-domain checks;
* a worst sample written as a spec and run through the whole pipeline (``designkit synth``'s path).
"""

from __future__ import annotations

import numpy as np
import pytest

from designkit.pipeline import run
from designkit.schema.loader import parse_spec
from designkit.sweep.api import sweep
from designkit.sweep.chunk import prepared, run_samples
from designkit.verification.time_domain import time_domain_checks
from tests.sweep.specs import SIMNOG, link, write

TRAJECTORY = """\
name: tracking-sweep
plant: {kind: link, Km: 2.0, tau: 0.5, uncertainty: {Km: [1.0, 3.0], tau: [0.3, 0.9]}}
controller: {kind: pid_tracking, poles: [-4, -5, -20]}
requirements: {overshoot: 20, settling_time: 2.0, steady_state_error: 0.01, tracking_error: 0.2, max_control: 40}
simulation: {duration: 3.0, trajectory: {kind: quintic, amplitude: 1.0, duration: 1.0}}
numerics: {integrator: rk4}
"""


@pytest.mark.parametrize("text", [SIMNOG, link(km=(1.2, 3.0), tau=(0.3, 0.8), duration=8.0).replace(
    "requirements: {steady_state_error: 0.5}",
    "requirements: {overshoot: 30, settling_time: 2.5, rise_time: 0.5, steady_state_error: 0.01, "
    "tracking_error: 1.2, max_control: 60}"), TRAJECTORY], ids=["simnog", "link", "trajectory"])
def test_margins_equal_the_pipeline_checks_on_the_same_runs(text):
    prep = prepared(text, "<test>", 6)
    values, seeds = prep.space.draw(11, np.arange(6))
    m, failed = run_samples(prep, values, seeds)
    assert not failed.any()
    verdicts = []
    for i in range(6):
        params = {d.key: float(values[i, k]) for k, d in enumerate(prep.space.dimensions)}
        checks = {c.name: c for c in time_domain_checks(prep.requirements, prep.simulator.run(parameters=params))}
        assert set(checks) == set(m.names)
        for name, c in checks.items():
            if c.margin is None:
                assert np.isnan(m.margin[name][i]), name
            else:
                assert m.margin[name][i] == pytest.approx(c.margin, rel=1e-9, abs=1e-12), name
        verdicts.append(all(c.passed for c in checks.values()))
    assert m.passed.tolist() == verdicts
    if text is SIMNOG:
        assert 0 < sum(verdicts) < 6  # the box straddles the requirements


@pytest.mark.parametrize("integrator", ["rk4", "default"])
def test_a_worst_sample_written_as_a_spec_gives_the_pipeline_the_same_margins(tmp_path, integrator):
    text = SIMNOG if integrator == "rk4" else SIMNOG.replace("numerics: {integrator: rk4}\n", "")
    spec = write(tmp_path, text)
    res = sweep(spec, 12, seed=4, engine="process", out=tmp_path / "out", falsification=False, report=False)
    worst = res.worst[0]
    assert worst.objective == min(np.min(res.margin[i] / np.array([res.limits[k] for k in res.requirements]))
                                  for i in range(res.samples))
    text = (tmp_path / "out" / "worst" / f"{res.name}-worst-1.yaml").read_text()
    result = run(parse_spec(text))
    checks = {c.name: c for c in result.checks if c.name in res.requirements}
    assert set(checks) == set(res.requirements)
    for name, c in checks.items():
        assert worst.margins[name] == pytest.approx(c.margin, rel=1e-9, abs=1e-12), name
    m2 = result.simulation.settings["plant_change"]["values"]["m2"]  # the true plant from t = 0
    assert m2 == pytest.approx(worst.values["m2"])
    assert result.design.gains.to_json() == run(parse_spec(text), simulate=False).design.gains.to_json()


def test_a_swept_initial_position_and_noise_seed_reach_the_pipeline(tmp_path):
    text = link(km=(1.0, 3.0), tau=(0.3, 0.8), duration=3.0, extra="sweep: {initial_position: [[-0.5, 0.5]], "
                "noise: true}\n").replace("simulation: {duration: 3.0}",
                                          "simulation: {duration: 3.0, noise: {std: 0.001, seed: 1}}")
    text = text.replace("requirements: {steady_state_error: 0.5}",
                        "requirements: {overshoot: 10, settling_time: 1.0, steady_state_error: 0.005}")
    spec = write(tmp_path, text)
    res = sweep(spec, 6, seed=2, engine="process", out=tmp_path / "out", falsification=False, report=False)
    for w in res.worst[:2]:
        assert set(w.values) == {"Km", "tau", "q0_1"} and w.noise_seed is not None
        result = run(parse_spec((tmp_path / "out" / "worst" / f"{res.name}-worst-{w.rank}.yaml").read_text()))
        assert result.simulation.state[0, 0] == pytest.approx(w.values["q0_1"])
        for c in result.checks:
            if c.name in res.requirements:
                assert w.margins[c.name] == pytest.approx(c.margin, rel=1e-9, abs=1e-12), c.name


def test_a_start_the_design_depends_on_is_not_swept(tmp_path):
    """The decentralized PID designs each joint at the start configuration: a swept start would change it."""
    from designkit.errors import SpecError

    text = SIMNOG + "sweep: {initial_position: [[-0.3, 0.3], [0.0, 0.2]]}\n"
    with pytest.raises(SpecError) as err:
        sweep(write(tmp_path, text), 4, engine="process")
    assert err.value.path == "sweep.initial_position"
