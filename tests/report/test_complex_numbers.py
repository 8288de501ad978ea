"""Complex numbers reach the reader as an engineer writes them, never as Python does.

A PID servo with a real pole and a complex pair is run through the pipeline; checks as the
verification layer words them today (``f"{z:.4g}"`` and list reprs of complex numbers) are added,
and the HTML text of the report must hold no ``+0j``, no ``(-3+4j)`` and no ``a+bj`` written by
Python, while the poles themselves are shown (``-4 + j3``, pairs as ``-4 ± j3``).
"""

from __future__ import annotations

import dataclasses
import re
from html import unescape

import numpy as np
import pytest

from designkit.display.numbers import fmt_complex, fmt_number, fmt_poles, plain_complex
from designkit.pipeline import run
from designkit.report.html import render_html
from designkit.report.model import build_report_model
from designkit.schema.loader import parse_spec
from designkit.verification.check import Check

SPEC = """\
name: report-complex-poles
description: PID servo with a real pole and a complex pair.
plant: {kind: link, Km: 2.0, tau: 0.5}
controller: {kind: pid_servo, poles: ["-4+3j", "-4-3j", -20], zero: -3}
requirements: {overshoot: 30, settling_time: 3.0}
simulation: {duration: 3.0}
"""

# Python's own notation of complex numbers: "+0j", "(-3+4j)", "-3-4j", NumPy's "-3.+4.j"
PYTHON_COMPLEX = re.compile(r"\d\.?[+-]\d*\.?\d*(?:e[+-]?\d+)?j|\+0j|\([^()]*\dj\)")


def _text(html: str) -> str:
    html = re.sub(r"<style>.*?</style>|<svg.*?</svg>|<pre class=\"spec\">.*?</pre>", " ", html, flags=re.S)
    html = re.sub(r'alttext="[^"]*"', "", html)
    return unescape(re.sub(r"<[^>]+>", " ", html))


@pytest.fixture(scope="module")
def complex_report():
    result = run(parse_spec(SPEC, path="<string>"))
    poles = np.linalg.eigvals(np.asarray(result.design.closed_loop.A, float))
    worded = (  # as verification/coupling.py and verification/pole_zero.py write them
        Check("coupling", True, target="<= 1000 %", achieved=710.0, margin=290.0, unit="%",
              detail=f"coupling moves the requested poles by up to 710 % ({complex(-20):.4g} -> {complex(-162):.4g} "
                     f"1/s); {complex(-4, 3):.4g} stays"),
        Check("pole_listing", True, target="as requested", achieved=str(np.round(poles, 9).tolist()[0]), margin=0.0,
              unit="1/s", detail=f"poles {np.round(poles, 9).tolist()} != requested {[complex(-4, 3), -20j]}",
              certificate={"note": f"eigenvalues {poles}", "poles": [[-4.0, 3.0], [-4.0, -3.0], [-20.0, 0.0]]}),
    )
    result = dataclasses.replace(result, checks=(*result.checks, *worded))
    model = build_report_model(result, studies=False)
    return result, model, _text(render_html(model))


def test_the_report_holds_no_python_complex_notation(complex_report):
    _, model, text = complex_report
    found = [text[max(0, m.start() - 50):m.end() + 20] for m in PYTHON_COMPLEX.finditer(text)]
    assert found == []
    assert "+0j" not in text and "0j)" not in text


def test_the_poles_are_written_as_numbers(complex_report):
    _, model, text = complex_report
    achieved = {row.achieved for row in model.poles}
    assert achieved == {"-4 + j3", "-4 - j3", "-20"}  # a real pole is a real number
    assert "(-20 -> -162 1/s); -4 + j3 stays" in text  # the check's own sentence, its numbers rewritten
    assert "poles [-20, -4 + j3, -4 - j3]" in text or "poles [-4 + j3, -4 - j3, -20]" in text


@pytest.mark.parametrize(("value", "text"), [
    (-20 + 0j, "-20"), (-3 + 4j, "-3 + j4"), (-3 - 4j, "-3 - j4"), (4j, "j4"), (-2j, "-j2"),
    (complex(-162.0, 1e-15), "-162"), (np.complex128(-1.23456 + 7.5j), "-1.235 + j7.5"),
])
def test_fmt_complex(value, text):
    assert fmt_complex(value) == text == fmt_number(value)


def test_fmt_poles_writes_a_conjugate_pair_once():
    assert fmt_poles([-3 - 4j, -20, -3 + 4j]) == "-20, -3 ± j4"
    assert fmt_poles([-1.0, -2.0 + 1e-12j]) == "-2, -1"


@pytest.mark.parametrize(("text", "plain"), [
    ("(-20+0j -> -162+0j 1/s)", "(-20 -> -162 1/s)"),
    ("[(-3+4j), (-3-4j)]", "[-3 + j4, -3 - j4]"),
    ("array([-3.+4.j, -3.-4.j])", "array([-3 + j4, -3 - j4])"),
    ("(-0-4j) and 1e-05+2e-06j", "-j4 and 1e-05 + j2e-06"),
    ("x1-2j, K1-2j, -3 + j4, 2j, N*m", "x1-2j, K1-2j, -3 + j4, 2j, N*m"),  # names, our own notation, words
])
def test_plain_complex_rewrites_python_notation_only(text, plain):
    assert plain_complex(text) == plain
