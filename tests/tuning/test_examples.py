"""designkit tune's committed examples: each spec as given misses a requirement (synth exit 1, tests/test_cli.py), and
the tuned spec committed beside its tuning report (reports/<name>/<name>-tuned.yaml) verifies as it is, with the
knob values the report states."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

import designkit as dk
from tests.marks import slow_cases
from tests.report.pdf_text import pdf_text

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = sorted(p.stem for p in (ROOT / "specs").glob("tune-*.yaml"))
SLOW = {"tune-simnog-decentralized-pid"}
"""The tuned spec whose full verify takes more than 5 s."""


def test_every_example_has_its_tuning_report():
    assert len(EXAMPLES) == 5
    for name in EXAMPLES:
        folder = ROOT / "reports" / name
        assert (folder / f"{name}-tuned.yaml").is_file() and (folder / f"{name}-tuning.html").is_file()
        assert (folder / f"{name}-tuning.pdf").read_bytes().startswith(b"%PDF")


@pytest.mark.parametrize("name", slow_cases(EXAMPLES, SLOW, str))
def test_the_committed_tuned_spec_verifies(name):
    folder = ROOT / "reports" / name
    run = dk.run(dk.load_spec(folder / f"{name}-tuned.yaml"))
    assert run.verified, [c.name for c in run.failed]
    html = (folder / f"{name}-tuning.html").read_text(encoding="utf-8")
    assert re.search(r"TUNED AND VERIFIED|tuned and verified", html, re.IGNORECASE)
    assert "TUNED AND VERIFIED" in pdf_text(folder / f"{name}-tuning.pdf")
