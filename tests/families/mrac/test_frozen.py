"""The frozen-linearization contract: the fixed-gain loops against hand derivations and python-control."""

from __future__ import annotations

import control
import numpy as np
import pytest

from designkit.families import synthesize
from designkit.families.mrac.model import gains_of
from designkit.schema.loader import load_spec, parse_spec
from designkit.verification.designed_loop import designed_loop_check
from tests.families.mrac.conftest import SPECS
from tests.tolerances import TOL


def _pd_poles(Km, tau, K1, K2):
    """Closed-loop poles of the link Km/(s (tau s + 1)) under u = -K1 (x1 - xD) - K2 x2, by python-control: the
    loop L = P (K2 s + K1) with unit feedback (the rate term sits in the feedback path, the poles are the same)."""
    s = control.tf("s")
    loop = Km / (s * (tau * s + 1)) * (K2 * s + K1)
    return np.sort_complex(control.poles(control.feedback(loop, 1)))


def test_the_loop_frozen_at_the_initial_values_has_the_requested_poles(link_result):
    d = link_result.design
    lin = d.linearization
    assert lin.kind == "frozen" and lin.parameters == ("a1", "a2") and lin.initial == (20.0, 9.0)
    assert set(lin.parameters) <= set(d.law.state_names)
    frozen = lin.freeze(lin.initial)
    assert frozen.n_state == 0 and frozen.signals is None  # no adaptation, no model, no sensitivity states
    # by hand: x1'' + ((1 + Km K2)/tau) x1' + (Km K1/tau) x1 = ..., K1 = 0.5*20/2 = 5, K2 = (0.5*9 - 1)/2 = 1.75
    assert (float(d.gains["K1"]), float(d.gains["K2"])) == pytest.approx((5.0, 1.75), rel=1e-15)
    got = np.sort_complex(np.linalg.eigvals(d.closed_loop.A))
    assert np.allclose(got, [-5.0, -4.0], atol=TOL["eigenvalues"])
    assert np.allclose(got, _pd_poles(2.0, 0.5, 5.0, 1.75), atol=TOL["eigenvalues"])


def _frozen_final(result):
    check = next(c for c in result.checks if c.name == "frozen_final")
    final = check.certificate["final"]
    return check, gains_of(final, 2.0, 0.5), np.sort_complex([complex(*p) for p in check.certificate["poles"]])


def test_frozen_final_judges_the_link_the_run_ends_with(link_result):
    """The generic check linearizes the link the run ends with (Km = 1 after the change) with the run's last
    parameters (40, 16): the model's poles -4, -5."""
    check, (K1, K2), got = _frozen_final(link_result)
    assert check.passed is True
    assert np.allclose(check.certificate["final"], (40.0, 16.0), rtol=1e-3)
    assert np.allclose(got, _pd_poles(1.0, 0.5, K1, K2), atol=1e-6)  # Km = 1 after the change: the model's -4, -5


def test_the_nominal_link_can_differ_from_the_plant():
    spec = parse_spec("name: x\nplant: {kind: link, Km: 2.0, tau: 0.5}\n"
                      "controller: {kind: mrac, poles: [-4, -5], gamma: 1, nominal: {Km: 1.0, tau: 0.8}}\n").spec
    d = synthesize(spec)
    K1, K2 = 0.8 * 20 / 1.0, (0.8 * 9 - 1) / 1.0  # realised on the nominal link Km = 1, tau = 0.8
    assert (float(d.gains["K1"]), float(d.gains["K2"])) == pytest.approx((K1, K2), rel=1e-15)
    assert np.allclose(np.sort_complex(np.linalg.eigvals(d.closed_loop.A)), [-5.0, -4.0], atol=1e-9)


def test_the_generic_designed_loop_check_holds_for_the_frozen_law_without_a_plant_change():
    text = (SPECS / "mrac-link.yaml").read_text().replace("  plant_change: {time: 20, values: {Km: 1.0}}\n", "")
    assert "plant_change" not in text
    spec = parse_spec(text).spec
    check = designed_loop_check(spec, synthesize(spec))
    assert check.passed is True, check.detail


def test_designed_loop_is_judged_on_the_designed_plant_without_the_plant_change():
    spec = load_spec(SPECS / "mrac-link.yaml").spec
    assert designed_loop_check(spec, synthesize(spec)).passed is True


ZERO_START = ("name: x\nplant: {kind: link, Km: 2.0, tau: 0.5}\n"
              "controller: {kind: mrac, poles: [-4, -5], gamma: 10000, initial: [4.0e-12, 2.0]}\n"
              "simulation: {duration: 30, trajectory: {kind: square, amplitude: 0.5, period: 4}}\n")


def test_designed_loop_from_zero_gains_is_judged_against_the_reference():
    """Started from a1 = 4e-12, a2 = 2 (K1 = 1e-12, K2 = 0) the frozen loop barely responds (its slow pole is at
    about -2e-12 1/s) while the square wave moves 0.5 rad; relative to that vanishing response the small-signal
    difference is hundreds of times the response; the check judges it against the reference's motion and passes."""
    spec = parse_spec(ZERO_START).spec
    design = synthesize(spec)
    check = designed_loop_check(spec, design)
    assert check.passed is True, check.detail
    assert check.certificate["reference_motion"] == pytest.approx(0.5)
    assert check.certificate["position_scale"] == pytest.approx(0.5)
    assert "judged against the reference's motion" in check.detail
    assert check.certificate["largest_relative_difference"] < 1e-6
    assert np.min(np.abs(np.linalg.eigvals(design.closed_loop.A))) < 1e-10  # the loop frozen at zero gain: no response


def test_designed_loop_from_the_nominal_gains_is_judged_against_its_own_response():
    text = (SPECS / "mrac-link.yaml").read_text().replace("  plant_change: {time: 20, values: {Km: 1.0}}\n", "")
    spec = parse_spec(text).spec
    check = designed_loop_check(spec, synthesize(spec))
    assert check.passed is True, check.detail
    assert "judged against the reference's motion" not in check.detail
    assert check.certificate["largest_relative_difference"] < 1e-3
