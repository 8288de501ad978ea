"""Weak margins flagged, margin requirements deciding the verdict, crossovers at the numerical resolution read as none.

Independent routes: the PID servo's loop ``L = Km (K2 s^2 + K1 s + K3)/(s^2 (tau s + 1))`` in closed form, whose phase
crossover satisfies ``w^2 = (tau K3 - K1)/(tau K2)`` (the imaginary part of ``(K3 - K2 w^2 + j K1 w)(1 - j tau w)`` is
``w (K1 - tau K3 + tau K2 w^2)``), so there is none when ``tau K3 <= K1``; python-control's ``stability_margins``
for the margins of a loop with genuine crossovers.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import designkit as dk
from designkit.verification.loop import classical_margins, loop_margins_check, loop_matrices


def _check(spec_text_or_path, **requirements):
    loaded = dk.load_spec(spec_text_or_path) if spec_text_or_path.endswith(".yaml") else dk.parse_spec(
        spec_text_or_path)
    spec = loaded.spec
    if requirements:
        from designkit.spec.sections import Requirements

        base = spec.requirements.model_dump() if spec.requirements is not None else {}
        spec = spec.model_copy(update={"requirements": Requirements(**{**base, **requirements})})
    design = dk.synthesize(spec)
    return design, loop_margins_check(design, spec)


def test_no_phase_crossover_in_closed_form_reads_infinite_gain_margin():
    """posspeed-link and the SCARA's prismatic joint: tau K3 - K1 is zero (to rounding), where the roots alone would put
    a 'crossover' at 1e-7 rad/s with a gain margin of 5.6e-17."""
    for path, joint in (("specs/posspeed-link.yaml", 0), ("specs/scara-decentralized-pid.yaml", 2)):
        design, check = _check(path)
        loop = design.loops[joint] if design.loops else design
        K1, K2, K3 = (float(np.atleast_1d(loop.gains[k])[0]) for k in ("K1", "K2", "K3"))
        tau = float(loop.plant.tau) if design.loops else float(design.plant.tau)
        assert (tau * K3 - K1) / (tau * K2) <= 1e-9 * (K1 / (tau * K2))  # no phase crossover at w > 0
        row = check.certificate["loops"][joint]
        assert row["gain_margin"] is None and row["phase_crossover_rad_s"] is None


def test_genuine_crossovers_agree_with_python_control():
    control = pytest.importorskip("control")
    design, check = _check("specs/scara-decentralized-pid.yaml")
    A, b, c = loop_matrices(design, 3)
    gm, pm, wpc, wgc = classical_margins(A, b, c)
    ref = control.stability_margins(control.ss(A, b.reshape(-1, 1), c.reshape(1, -1), 0))
    assert gm == pytest.approx(ref[0], rel=1e-6) and pm == pytest.approx(ref[1], rel=1e-6)


def test_weak_margins_are_flagged_without_a_requirement():
    _, check = _check("specs/scara-decentralized-pid.yaml")
    assert check.required is False and check.passed is True
    text = " ".join(check.warnings)
    assert "u4: phase margin 19.2°, below 30°" in text and "u4: gain margin 2.15 dB, below 6 dB" in text
    assert "u4: modulus margin min |1 + L| 0.212, below 0.5" in text
    # joints 1 and 2 have gain margins below 1 (conditionally stable): a 26 dB reduction is not weak
    assert "u1" not in text and "u2" not in text
    _, calm = _check("specs/posspeed-link.yaml")
    assert calm.warnings == ()


def test_margin_requirements_decide_the_verdict():
    _, failing = _check("specs/scara-decentralized-pid.yaml", phase_margin=30.0)
    assert failing.required is True and failing.passed is False
    assert "u4: phase margin 19.2°, below 30°" in failing.detail and failing.warnings == ()
    _, passing = _check("specs/posspeed-link.yaml", phase_margin=60.0, gain_margin=6.0, modulus_margin=0.5)
    assert passing.required is True and passing.passed is True
    assert passing.certificate["limits_source"] == "requirements"


def test_a_margin_requirement_is_read_from_the_spec():
    text = ("name: m\nplant: {kind: link, Km: 2.0, tau: 0.5}\ncontroller: {kind: pid_servo, poles: [-4, -5, -20]}\n"
            "requirements: {phase_margin: 45, gain_margin: 6}\n")
    result = dk.run(dk.parse_spec(text), simulate=False)
    check = next(c for c in result.checks if c.name == "loop_margins")
    assert check.required and check.target == "gain margin ≥ 6 dB, phase margin ≥ 45°"
    assert check.passed is (check.certificate["loops"][0]["phase_margin_deg"] >= 45)
    assert math.isfinite(check.achieved)
