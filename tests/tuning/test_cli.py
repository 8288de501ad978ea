"""``designkit tune`` on the command line: exit 2 with one line and nothing written on bad input, exit 1 with the
conflicting pair and the actuator's bound on infeasible requirements."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from designkit.cli import main
from tests.tuning.specs import LINK, write

SPECS = Path(__file__).resolve().parents[2] / "specs"


def _code(argv: list[str]) -> int:
    """The exit code of ``designkit argv`` (argparse's own errors leave by SystemExit)."""
    try:
        return main(argv)
    except SystemExit as exc:
        return int(exc.code)


@pytest.mark.parametrize(("text", "args", "where"), [
    (LINK.replace("tune: {fixed: [zero]}", "tune: {ranges: {poles: [5, 2]}}"), [], "tune.ranges.poles: needs lo < hi"),
    (LINK.replace("tune: {fixed: [zero]}", "tune: {ranges: {poles: [3, 3]}}"), [], "tune.ranges.poles: needs lo < hi"),
    (LINK.replace("fixed: [zero]", "fixed: [zero, K9]"), [], "tune.fixed[1]: the pid_servo family has no knob 'K9'"),
    (LINK.replace("tune: {fixed: [zero]}", "tune: {ranges: {gamma: [1, 2]}}"), [], "tune.ranges.gamma: the pid_servo"),
    (LINK.replace("tune: {fixed: [zero]}", "tune: {ranges: {poles: [1e-5, 2]}}"), [],
     "tune.ranges.poles: [1e-05, 2] leaves the knob's declared range"),
    (LINK.replace("requirements: {overshoot: 5, settling_time: 1.5, max_control: 40}\n", ""), [],
     "requirements: the spec gives no requirement to tune for"),
    (LINK.replace("fixed: [zero]", "fixed: [poles, zero]"), [], "tune: nothing to tune"),
    (LINK, ["--budget", "0"], "--budget: must be a positive number of seconds"),
    (LINK, ["--budget", "-3"], "--budget: must be a positive number of seconds"),
], ids=["range-reversed", "range-empty", "fixed-unknown", "range-unknown", "range-outside", "no-requirements",
        "all-fixed", "budget-zero", "budget-negative"])
def test_bad_input_exits_2_with_one_line_and_writes_nothing(tmp_path, capsys, text, args, where):
    spec = write(tmp_path, text)
    out = tmp_path / "out"
    assert _code(["tune", str(spec), "--out", str(out), *args]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("designkit: error: ") and where in err, err
    assert not out.exists()


@pytest.mark.parametrize(("args", "where"), [
    (["--method", "gradient"], "method: the gradient search needs a smooth loop, and this one is not: the law is "
     "discontinuous"),
    (["--method", "newton"], "--method: invalid choice: 'newton'"),
], ids=["gradient-on-switching", "unknown"])
def test_a_method_the_loop_cannot_take_exits_2(tmp_path, capsys, args, where):
    out = tmp_path / "out"
    assert _code(["tune", str(SPECS / "tune-vsc-link.yaml"), "--out", str(out), *args]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("designkit: error: ") and where in err, err
    assert not out.exists()


@pytest.mark.slow  # about 25 s: a search of 20 s (the gradient search needs a dozen iterations to find the pair)
def test_infeasible_requirements_exit_1_naming_the_conflict_and_the_bound(tmp_path, capsys):
    code = main(["tune", str(SPECS / "infeasible-requirements.yaml"), "--out", str(tmp_path), "--budget", "20"])
    text = capsys.readouterr().out
    assert code == 1
    assert "NOT MET: no tuning found meets every requirement" in text
    # the settling time and the torque limit are the pair: a faster loop asks for more torque
    assert re.search(r"conflict: (settling_time and max_control|max_control and settling_time) conflict", text)
    assert "the settling time of 0.3 s asked for is infeasible for every controller" in text
    assert (tmp_path / "infeasible-requirements-tuned.yaml").is_file()
    html = (tmp_path / "infeasible-requirements-tuning.html").read_text(encoding="utf-8")
    assert "Why no tuning meets every requirement" in html and "<svg" in html
