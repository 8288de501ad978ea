"""A comparison runs each controller as its own spec: the same results as alone, metrics checked with NumPy."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from designkit.cli import main
from designkit.pipeline import ComparisonResult, run
from designkit.schema.loader import load_spec, parse_spec

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "specs" / "mrac-vs-selftune.yaml"
MRAC_ALONE = ROOT / "specs" / "mrac-link.yaml"


@pytest.fixture(scope="module")
def comparison() -> ComparisonResult:
    return run(load_spec(EXAMPLE))


def _alone(label: str, block: str) -> str:
    """The example's shared sections with one controller, written by hand (not derived from the loader)."""
    return (f"name: {label}\nplant: {{kind: link, Km: 2.0, tau: 0.5}}\ncontroller:\n{block}"
            "simulation:\n  duration: 40\n  trajectory: {kind: square, amplitude: 0.5, period: 4}\n"
            "  plant_change: {time: 20, values: {Km: 1.0}}\n")


MRAC_BLOCK = "  kind: mrac\n  poles: [-4, -5]\n  gamma: 10000\n  Q: [1, 0.1]\n"
STR_BLOCK = ("  kind: self_tuning\n  sampling_period: 0.01\n  estimator: speed\n  forgetting: 0.99\n"
             "  initial_covariance: 100\n  poles: [-4, -5]\n  nominal: {Km: 1.0, tau: 1.0}\n")


@pytest.mark.parametrize(("label", "block"), [("mrac", MRAC_BLOCK), ("selftune", STR_BLOCK)])
def test_each_controller_is_the_run_of_its_own_spec(comparison, label, block):
    alone = run(parse_spec(_alone(label, block)))
    inside = comparison[label]
    assert [(c.name, c.status) for c in inside.checks] == [(c.name, c.status) for c in alone.checks]
    for a, b in zip(inside.checks, alone.checks, strict=True):
        if isinstance(a.achieved, float):
            assert a.achieved == pytest.approx(b.achieved, rel=1e-9, abs=1e-12), a.name
    np.testing.assert_allclose(inside.simulation.state, alone.simulation.state, rtol=1e-12, atol=1e-12)
    assert inside.verified == alone.verified
    from designkit.comparison.metrics import baseline_simulation, compute_metrics

    own = compute_metrics(alone.loaded.spec, alone.simulation, baseline_simulation(alone.loaded.spec, alone.plant))
    table = comparison.table.row(label).values
    assert own.keys() == table.keys()
    for key, value in own.items():
        assert (value is None and table[key] is None) or table[key] == pytest.approx(value, rel=1e-9, abs=1e-12), key
    assert dict(inside.design.gains.items()).keys() == dict(alone.design.gains.items()).keys()


def test_metrics_against_numpy(comparison):
    """The square wave's metrics recomputed here: its jumps every 2 s (and at 0, the run starting at 0 rad off the
    reference's 0.5 rad), the error over the last quarter of each 2-s level, each jump's 90 % rise time by a direct
    search, and the error against the MRAC's recorded reference model."""
    tc = 20.0
    for label, res in zip(comparison.labels, comparison.results, strict=True):
        sim = res.simulation
        t = np.asarray(sim.time)
        xd = np.asarray(sim.desired).ravel()
        x = np.asarray(sim.state)[:, 0]
        e = np.abs(xd - x)
        u = np.abs(np.asarray(sim.u_command).ravel())
        before, after = t < tc, t >= tc
        row = comparison.table.row(label).values
        # the raw error rows are not reported: with repeated jumps they measure the jumps (each a 1 rad error)
        for key in ("rms_error_before", "rms_error_after", "max_error_before", "max_error_after", "rms_error_final",
                    "overshoot", "max_error_load"):
            assert row[key] is None, key
        since = np.mod(t, 2.0)  # time since the latest jump (a jump every 2 s from 0)
        settled = since >= 1.5 - 1e-9
        assert row["rms_settled_before"] == pytest.approx(math.sqrt(np.mean(e[before & settled] ** 2)), rel=1e-9)
        assert row["rms_settled_after"] == pytest.approx(math.sqrt(np.mean(e[after & settled] ** 2)), rel=1e-9)
        assert row["max_settled_after"] == pytest.approx(e[after & settled].max(), rel=1e-12)
        assert row["max_settled_after"] < 0.05  # not a jump: every jump is 1 rad
        last = t >= t[-1] - 4.0
        assert row["rms_settled_final"] == pytest.approx(math.sqrt(np.mean(e[last & settled] ** 2)), rel=1e-9)
        rises = []
        for edge in np.arange(0.0, 40.0, 2.0):  # the jump at 40 s, the run's last sample, has no level after it
            i = int(np.searchsorted(t, edge - 1e-9))
            start, target = (x[i - 1] if i > 0 else x[0]), xd[i]
            k = i + int(np.argmax((x[i:] - (start + 0.9 * (target - start))) * np.sign(target - start) >= 0))
            rises.append((edge, t[k] - t[i]))
        assert row["rise_time_before"] == pytest.approx(np.mean([r for at, r in rises if at < tc]), abs=1e-12)
        assert row["rise_time_after"] == pytest.approx(np.mean([r for at, r in rises if at >= tc]), abs=1e-12)
        assert row["peak_command"] == pytest.approx(u.max(), rel=1e-12)
        assert row["rms_command"] == pytest.approx(math.sqrt(np.mean(u ** 2)), rel=1e-12)
        # the unchanged-link run, simulated independently from a spec without the plant change
        text = EXAMPLE.read_text().replace("  plant_change: {time: 20, values: {Km: 1.0}}\n", "")
        base = run(parse_spec(text))[label].simulation
        d = np.abs(np.asarray(sim.state)[:, 0] - np.asarray(base.state)[:, 0])
        assert np.all(d[before] < 1e-9)  # the same run until the change
        assert row["rms_deviation"] == pytest.approx(math.sqrt(np.mean(d[after] ** 2)), rel=1e-9)
        band = 0.01 * 1.0  # 1 % of the square wave's range, 1 rad
        above = np.flatnonzero(after & (d > band))
        assert row["reconvergence"] == pytest.approx(t[above[-1] + 1] - tc, abs=1e-9)
        if "ym" in sim.signals:  # the MRAC records its reference model's output
            em = np.abs(np.asarray(sim.signals["ym"]) - x)
            assert row["rms_model_error_after"] == pytest.approx(math.sqrt(np.mean(em[after] ** 2)), rel=1e-9)
            # on the unchanged link the MRAC follows its model exactly (matched initial coefficients), so the error
            # against the model after the change is the departure the change causes
            assert row["rms_model_error_before"] < 1e-12
            assert row["rms_model_error_after"] == pytest.approx(row["rms_deviation"], rel=1e-6)
        else:
            assert row["rms_model_error_before"] is None and row["rms_model_error_after"] is None


def test_winners_say_who_wins_and_by_how_much(comparison):
    table = comparison.table
    sentences = {w.metric.key: w for w in table.winners()}
    rec = sentences["reconvergence"]
    values = {label: table.value(label, "reconvergence") for label in comparison.labels}
    assert rec.label == min(values, key=values.get)
    assert rec.value == min(values.values()) and rec.second == max(values.values())
    assert "times lower" in rec.sentence or "% lower" in rec.sentence


def test_verdict_is_every_controllers(comparison):
    assert comparison.verified is all(r.verified for r in comparison.results)
    assert comparison.failed == ()


FAILING = """\
name: cmp-failing
plant: {kind: link, Km: 2.0, tau: 0.5}
controllers:
  - {kind: mrac, poles: [-4, -5], gamma: 10000, Q: [1, 0.1], label: fine}
  - {kind: mrac, poles: [-4, -5], gamma: 10000000, Q: [1, 0.1], label: too-fast}
simulation:
  duration: 24
  trajectory: {kind: square, amplitude: 0.5, period: 4}
  plant_change: {time: 8, values: {Km: 1.0}}
"""


def test_exit_codes_and_json(tmp_path, capsys):
    code = main(["synth", str(EXAMPLE), "--no-report", "--json", "--no-studies"])  # studies: tests/studies
    payload = json.loads(capsys.readouterr().out)
    assert code == 0 and payload["passed"] is True
    assert [c["label"] for c in payload["comparison"]] == ["mrac", "selftune"]
    assert [c["kind"] for c in payload["comparison"]] == ["mrac", "self_tuning"]
    assert all(c["verified"] is True and "rms_settled_after" in c["metrics"] for c in payload["comparison"])
    assert "rms_error_after" not in payload["comparison"][0]["metrics"]  # a square wave's RMS measures its jumps
    winners = {w["metric"]: w for w in payload["winners"]}
    assert winners["rms_command"]["tie"] is True and winners["rms_command"]["tied"] == ["mrac", "selftune"]
    assert winners["reconvergence"] == {**winners["reconvergence"], "tie": False, "tied": [], "label": "selftune"}
    assert "rms_model_error_after" not in winners  # recorded by one controller only: nothing to compare

    spec = tmp_path / "failing.yaml"
    spec.write_text(FAILING)
    code = main(["verify", str(spec), "--json"])
    payload = json.loads(capsys.readouterr().out)
    assert code == 1 and payload["passed"] is False
    verdicts = {c["label"]: c["verified"] for c in payload["comparison"]}
    assert verdicts == {"fine": True, "too-fast": False}

    spec.write_text(FAILING.replace("gamma: 10000000", "gamma: -5"))
    assert main(["synth", str(spec), "--no-report"]) == 2
    err = capsys.readouterr().err
    assert "controllers[1].gamma" in err
    assert main(["codegen", str(EXAMPLE), "--out", str(tmp_path)]) == 2
    assert "controllers" in capsys.readouterr().err
    assert main(["simulate", str(EXAMPLE)]) == 2
    assert "controllers" in capsys.readouterr().err


STEP = """\
name: step-comparison
plant: {kind: link, Km: 2.0, tau: 0.5}
controllers:
  - {kind: pid_servo, poles: [-4, -5, -20], zero: -3, label: slow}
  - {kind: pid_servo, poles: [-8, -10, -40], zero: -6, label: fast}
"""


def test_step_metrics_against_numpy():
    result = run(parse_spec(STEP))
    for label in ("slow", "fast"):
        sim = result[label].simulation
        t = np.asarray(sim.time)
        x = np.asarray(sim.state)[:, 0]
        target = float(np.asarray(sim.desired).ravel()[-1])
        step = target - x[0]
        row = result.table.row(label).values
        assert row["overshoot"] == pytest.approx(max(0.0, (x.max() - x[0]) / step - 1.0) * 100.0, abs=1e-9)
        outside = [k for k in range(len(t)) if abs(x[k] - target) > 0.02 * abs(step)]
        assert row["settling_time"] == pytest.approx(t[outside[-1] + 1], abs=1e-12)
        assert row["rms_error_after"] is None and row["reconvergence"] is None  # no plant change
    assert result.table.value("fast", "settling_time") < result.table.value("slow", "settling_time")


def test_metric_words_follow_the_scenario():
    """Without a plant change "before the change" is the whole run, and without a periodic reference the last
    window is the last quarter of the run, named with its length; with both, the words are the definitions'."""
    from types import SimpleNamespace

    from designkit.comparison.table import METRICS, _worded

    step = parse_spec("name: s\nplant: {kind: link, Km: 2.0, tau: 0.5}\ncontroller: {kind: pid_servo, poles: "
                      "[-4, -5, -20]}\nsimulation: {duration: 4.0, perturbation: {value: 0.5, time: 2.0}}\n").spec
    run_ = [SimpleNamespace(loaded=SimpleNamespace(spec=step), simulation=SimpleNamespace(time=np.linspace(0, 4, 9)))]
    words = {m.key: _worded(m, run_) for m in METRICS}
    assert words["rms_error_before"].label == "RMS tracking error over the run"
    assert words["max_error_before"].meaning == "largest |xD − x| over the whole run"
    assert words["rms_error_final"].label == "RMS tracking error over the last 1 s"
    square = load_spec(EXAMPLE).spec  # a square wave of period 4 s and a plant change at 20 s
    run_ = [SimpleNamespace(loaded=SimpleNamespace(spec=square), simulation=SimpleNamespace(time=np.arange(41.0)))]
    assert [_worded(m, run_) for m in METRICS] == list(METRICS)
