"""Bad input to ``designkit sweep``: one line naming the flag or key path, exit 2, nothing written."""

from __future__ import annotations

import socket
import time

import pytest

from designkit.cli import main
from tests.sweep.specs import SIMNOG, link, write


def _run(capsys, tmp_path, text, *flags):
    spec = write(tmp_path, text)
    out = tmp_path / "out"
    code = main(["sweep", str(spec), "--out", str(out), *flags])
    err = capsys.readouterr().err.strip()
    return code, err, out


@pytest.mark.parametrize(("flags", "key"), [
    (["--samples", "0"], "--samples"),
    (["--samples", "-5"], "--samples"),
    (["--samples", "10000001"], "--samples"),
    (["--samples", "10", "--seed", "-1"], "--seed"),
    (["--samples", "10", "--workers", "0"], "--workers"),
    (["--samples", "10", "--chunk", "0"], "--chunk"),
])
def test_flags_out_of_range(capsys, tmp_path, flags, key):
    code, err, out = _run(capsys, tmp_path, SIMNOG, *flags)
    assert code == 2 and err.startswith(f"designkit: error: {key}:") and "\n" not in err
    assert not out.exists()


@pytest.mark.parametrize(("text", "key"), [
    (SIMNOG + "sweep: {parameters: {m9: [1, 2]}}\n", "sweep.parameters.m9"),
    (SIMNOG + "sweep: {bogus: 1}\n", "sweep.bogus"),
    (SIMNOG + "sweep: {distribution: lognormal}\n", "sweep.distribution"),
    (SIMNOG + "sweep: {cut: 50}\n", "sweep.cut"),
    (SIMNOG + "sweep: {payload: {mass: [2, 1]}}\n", "sweep.payload.mass"),
    (SIMNOG + "sweep: {noise: true}\n", "sweep.noise"),
    (SIMNOG + "sweep: {initial_position: [[0, 1]]}\n", "sweep.initial_position"),
    (SIMNOG.replace("  uncertainty: {m2: [2.0, 4.0]}\n", ""), "plant.uncertainty"),
    (SIMNOG.replace("  uncertainty: {m2: [2.0, 4.0]}\n", "  uncertainty: {m2: [3.0, 3.0]}\n"), "plant.uncertainty"),
    (link().replace("requirements: {steady_state_error: 0.5}\n", ""), "requirements"),
    (SIMNOG.replace("  step: [1.0, -0.5]", "  step: [1.0, -0.5]\n  plant_change: {time: 1.0, values: {m2: 3.5}}"),
     "simulation.plant_change"),
])
def test_bad_sweep_sections_name_their_key_path(capsys, tmp_path, text, key):
    code, err, out = _run(capsys, tmp_path, text, "--samples", "10")
    assert code == 2, err
    assert err.startswith(f"designkit: error: {key}:"), err
    assert not (out / "simnog-sweep").exists() and not (out / "link-sweep").exists()


def test_an_unreachable_scheduler_is_refused_within_seconds(capsys, tmp_path):
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    start = time.monotonic()
    code, err, out = _run(capsys, tmp_path, SIMNOG, "--samples", "10", "--scheduler", f"tcp://127.0.0.1:{port}")
    assert time.monotonic() - start < 20
    assert code == 2 and err.startswith("designkit: error: --scheduler:"), err


def test_the_spec_s_own_errors_keep_their_key_paths(capsys, tmp_path):
    code, err, _ = _run(capsys, tmp_path, SIMNOG.replace("poles: [-4, -5, -20]", "poles: [-4, -5]"), "--samples", "5")
    assert code == 2 and err.startswith("designkit: error: controller.poles"), err
