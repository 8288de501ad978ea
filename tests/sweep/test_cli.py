"""``designkit sweep --json``: the output contract, the files written, the exit code, the payload's route."""

from __future__ import annotations

import json

import numpy as np
import pytest

from designkit.cli import main
from designkit.pipeline import run
from designkit.schema.loader import parse_spec
from tests.sweep.specs import SIMNOG, write


def test_the_json_object_and_the_files(tmp_path, capsys):
    spec = write(tmp_path, SIMNOG)
    code = main(["sweep", str(spec), "--samples", "16", "--seed", "3", "--workers", "1", "--chunk", "8",
                 "--out", str(tmp_path / "out"), "--json"])
    payload = json.loads(capsys.readouterr().out)
    assert code == (0 if payload["passed"] == 16 and not payload["falsification"]["breaks_a_requirement"] else 1)
    for key in ("samples", "passed", "pass_fraction", "confidence", "requirements", "worst"):
        assert key in payload
    assert payload["samples"] == 16 and payload["pass_fraction"] == payload["passed"] / 16
    lo, hi = payload["confidence"]
    assert lo <= payload["pass_fraction"] <= hi
    assert set(payload["requirements"]) == {"overshoot", "settling_time", "rise_time", "steady_state_error",
                                            "max_control"}
    assert all(set(w["parameters"]) == {"m2"} for w in payload["worst"])
    folder = tmp_path / "out" / "simnog-sweep"
    for name in ("samples.csv", "sweep.json", "report.html", "report.pdf"):
        assert (folder / name).is_file(), name
    assert len(list((folder / "chunks").glob("chunk-*.npz"))) == 2
    html = (folder / "report.html").read_text()
    assert ("PASS" if code == 0 else "FAIL") in html and "N·m" in html and "N*m" not in html


def test_a_swept_payload_is_the_link_mass_the_pipeline_sees(tmp_path):
    from designkit.sweep.api import sweep

    text = SIMNOG.replace("  uncertainty: {m2: [2.0, 4.0]}\n", "") + "sweep: {payload: {mass: [0.0, 1.5]}}\n"
    res = sweep(write(tmp_path, text), 4, seed=1, engine="process", out=tmp_path / "o", falsification=False,
                report=False)
    w = res.worst[0]
    assert set(w.values) == {"payload"}
    result = run(parse_spec((tmp_path / "o" / "worst" / f"{res.name}-worst-1.yaml").read_text()))
    assert result.simulation.settings["plant_change"]["values"]["m2"] == pytest.approx(3.0 + w.values["payload"])
    for c in result.checks:
        if c.name in res.requirements:
            assert w.margins[c.name] == pytest.approx(c.margin, rel=1e-9, abs=1e-12), c.name
    assert np.all((res.values >= 0.0) & (res.values <= 1.5))


def test_no_progress_bar_when_stderr_is_not_a_terminal(tmp_path, capsys):
    from tests.sweep.specs import link

    code = main(["sweep", str(write(tmp_path, link(km=(0.5, 1.0), tau=(0.5, 0.7), duration=5.0))), "--samples", "6",
                 "--workers", "1", "--out", str(tmp_path / "out")])
    captured = capsys.readouterr()
    assert code == 0 and "sweep [" not in captured.err and "samples, " not in captured.err  # no progress line
    assert "6 of 6 samples met every requirement" in captured.out and captured.out.rstrip().endswith("VERIFIED")


def test_the_progress_line_says_samples_rate_and_time_left(capsys):
    from designkit.sweep.engine import _progress

    show = _progress(100, True)
    show(0)
    show(50)
    show(100)
    err = capsys.readouterr().err
    assert "50/100 samples" in err and "/s" in err and "s left" in err and err.endswith("\n")
    quiet = _progress(100, False)
    quiet(50)
    assert capsys.readouterr().err == ""
