"""Certificates and number formats: four significant digits, matrices, tables, grids, edge cases."""

from __future__ import annotations

import numpy as np
import pytest

from designkit.display.numbers import fmt_number
from designkit.report.certificates import render_certificate


def test_lyapunov_certificate_matrix_has_four_significant_digits(servo_model):
    cert = {e.key: e for e in servo_model.checks[1].certificate}
    P = cert["P"].matrix
    assert P is not None and cert["P"].header is None
    assert P[0] == ("1", "0.1235", "-3.3e-05")
    assert P[2] == ("-3.3e-05", "0.01", "0.25")
    assert cert["eig_P"].text == "0.2, 0.5, 1"
    assert cert["eig_P"].label == "eigenvalues of P"
    assert cert["solver_status"].text == "optimal"
    assert cert["eig_A"].text == "-4, -5, -20"  # [re, im] pairs shown as (real) complex numbers, no brackets


def test_certificate_records_become_a_table(servo_model):
    cert = {e.key: e for e in servo_model.checks[0].certificate}
    cond = cert["conditions"]
    assert cond.header == ("condition", "value", "threshold", "margin", "unit")
    assert cert["coefficients"].label == "characteristic coefficients"
    assert cond.matrix[0] == ("K2 > -1/Km", "6.75", "-0.5", "7.25", "N·m·s/rad")
    assert cert["coefficients"].text == "0.5, 14.5, 100, 200"


def test_certificate_grid_is_summarised(servo_model):
    (entry,) = servo_model.checks[3].certificate
    assert entry.key == "grid"
    assert "Km ∈ [1.5, 2.5] (rad/s)/(N·m) (5 points)" in entry.text and "robustness figure" in entry.text


def test_render_certificate_edge_cases():
    big = np.arange(100.0).reshape(10, 10).tolist()
    entries = {e.key: e for e in render_certificate({
        "M": big, "v": list(range(20)), "nested": {"a": 1.23456, "b": "x"}, "none": None,
        "evidence": {"eigenvalue": [0.5, -2.0]}, "flag": True, "pair": [1.0, 2.0],
    })}
    M = entries["M"].matrix
    assert len(M) == 8 and M[-1][0] == "⋮" and len(M[0]) == 8 and M[0][-1] == "…"
    assert entries["v"].text.endswith("(20 items)") and "…" in entries["v"].text
    assert entries["nested.a"].text == "1.235" and entries["nested.b"].text == "x"
    assert entries["nested.a"].label == "nested › a"  # no dotted internal key is shown
    assert entries["none"].text == "—"
    assert entries["evidence.eigenvalue"].text == "0.5 - j2"
    assert entries["flag"].text == "yes"
    assert entries["pair"].text == "1, 2"


@pytest.mark.parametrize(("value", "text"), [
    ({}, "none"), ((), "none"), ([], "none"), (None, "—"), ([[-20, -5, -4]], "-20, -5, -4"),
    ([[1, 2], [3, 4]], "(1, 2); (3, 4)"), ({"a_b": 1, "c": {"d": None}}, "a b = 1, c = (d = —)"),
    (-15.5423 - 15.7453j, "-15.54 - j15.75"), (2j, "j2"),
])
def test_fmt_compact_writes_no_python_notation(value, text):
    from designkit.report.certificates import fmt_compact

    assert fmt_compact(value) == text


@pytest.mark.parametrize(("key", "label"), [
    ("largest_deviation_from_decoupled_form", "largest deviation from the decoupled form"),
    ("loops.0.gain_crossover_rad_s", "loops › no. 1 › gain crossover (rad/s)"),
    ("settle_time_s", "settle time (s)"), ("eig_AtP_PA", "eigenvalues of AᵀP + PA"),
])
def test_human_key(key, label):
    from designkit.report.certificates import human_key

    assert human_key(key) == label


@pytest.mark.parametrize(("value", "text"), [
    (0.0, "0"), (1.0, "1"), (123456.0, "1.235e+05"), (-0.000123456, "-0.0001235"), (float("inf"), "∞"),
    (float("-inf"), "-∞"), (float("nan"), "nan"), (None, "—"), (3 + 4j, "3 + j4"), (-2.0 + 0j, "-2"),
    (np.float64(2.5), "2.5"), (np.int64(7), "7"), ("text", "text"),
])
def test_fmt_number(value, text):
    assert fmt_number(value).replace("−", "-") == text
