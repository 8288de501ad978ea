"""The ad hoc modifications of the gradient rule (``controller.modification``) against the same equations written
again here by hand and integrated by scipy's ``solve_ivp``: the normalised rule, the dead zone, the projection.

Hand derivation (docs/families/mrac.md): the plain rule's rate is ``r = Gamma S' Q e``; normalised,
``alpha' = r/(1 + tr(Gamma S' Q S)/nu)``; with a dead zone of width ``d``, ``alpha' = r max(0, |e1| - d)/max(|e1|,
d)``; projected on ``[low, high]``, ``alpha_i' = 0`` where ``alpha_i >= high_i, r_i > 0`` or ``alpha_i <= low_i, r_i
< 0``, else ``r_i``.  The sensitivity filters are the hand-derived ones (``s1'' + a2 s1' + a1 s1 = r - y1``, ``s2'' +
a2 s2' + a1 s2 = -y1'``), not the family's CasADi Jacobians.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from designkit.pipeline import run
from designkit.schema.loader import parse_spec
from tests.families.mrac.numpy_mrac import square

A, NOMINAL, GAMMA, Q = (20.0, 9.0), (2.0, 0.5), (1e4, 1e4), np.diag([1.0, 0.1])
AMPLITUDE, PERIOD, CHANGE, DURATION = 0.5, 4.0, (12.0, 1.0), 24.0
# Measured: RMS of e within 3e-11 (normalised), 1.4e-8 (dead zone), 7.7e-8 (projection) of scipy's, the parameter
# trajectories within 2e-11, 4.3e-8 and 2.7e-7 relative (the run's RK4 step is 2.5 ms).
AGREE = 1e-5

SPEC = f"""
name: mrac-modified
plant: {{kind: link, Km: 2.0, tau: 0.5}}
controller:
  kind: mrac
  poles: [-4, -5]
  gamma: 10000
  Q: [1, 0.1]
  modification: MODIFICATION
simulation:
  duration: {DURATION}
  trajectory: {{kind: square, amplitude: {AMPLITUDE}, period: {PERIOD}}}
  plant_change: {{time: {CHANGE[0]}, values: {{Km: {CHANGE[1]}}}}}
"""


def _rate(alpha, e, S, modification):
    """``alpha'`` by hand (module docstring)."""
    r = np.asarray(GAMMA) * (S.T @ Q @ e)
    kind = modification["kind"]
    if kind == "normalized":
        return r / (1.0 + np.trace(np.diag(GAMMA) @ S.T @ Q @ S) / modification["rate"])
    if kind == "dead_zone":
        d = modification["width"]
        return r * max(abs(e[0]) - d, 0.0) / max(abs(e[0]), d)
    low, high = modification["low"], modification["high"]
    return np.array([0.0 if (alpha[i] >= high[i] and r[i] > 0) or (alpha[i] <= low[i] and r[i] < 0) else r[i]
                     for i in range(2)])


def _rhs(t, s, Km, tau, ref, modification):
    x1, x2, y1, y2, s11, s21, s12, s22, al1, al2 = s
    a1, a2 = A
    K1, K2 = NOMINAL[1] * al1 / NOMINAL[0], (NOMINAL[1] * al2 - 1.0) / NOMINAL[0]
    u = -K1 * (x1 - ref) - K2 * x2
    e = np.array([y1 - x1, y2 - x2])
    S = np.array([[s11, s12], [s21, s22]])
    alpha_dot = _rate((al1, al2), e, S, modification)
    return np.array([x2, -x2 / tau + Km / tau * u, y2, -a1 * y1 - a2 * y2 + a1 * ref,
                     s21, -a1 * s11 - a2 * s21 + (ref - y1), s22, -a1 * s12 - a2 * s22 - y2,
                     alpha_dot[0], alpha_dot[1]])


def _scipy(t_eval, modification):
    """The loop from rest, integrated piecewise between the reference's jumps and the plant change."""
    wave = square(AMPLITUDE, PERIOD)
    events = sorted({0.0, DURATION, CHANGE[0], *(k * PERIOD / 2 for k in range(1, int(DURATION / (PERIOD / 2)) + 1))})
    s = np.array([0.0] * 8 + list(A))
    out = np.empty((t_eval.size, 10))
    for lo, hi in zip(events[:-1], events[1:], strict=True):
        mid = 0.5 * (lo + hi)
        Km = CHANGE[1] if mid >= CHANGE[0] else 2.0
        sol = solve_ivp(_rhs, (lo, hi), s, method="DOP853", rtol=1e-10, atol=1e-12, dense_output=True,
                        args=(Km, 0.5, wave(mid), modification), max_step=0.01)
        inside = (t_eval >= lo - 1e-12) & (t_eval <= hi + 1e-12)
        out[inside] = sol.sol(t_eval[inside]).T
        s = sol.y[:, -1]
    return out


def _rms(x):
    return float(np.sqrt(np.mean(np.asarray(x) ** 2)))


CASES = {
    "normalized": ("{kind: normalized, rate: 2.0}", {"kind": "normalized", "rate": 2.0}),
    "dead_zone": ("{kind: dead_zone, width: 0.01}", {"kind": "dead_zone", "width": 0.01}),
    "projection": ("{kind: projection, low: [10, 5], high: [30, 36]}",
                   {"kind": "projection", "low": [10.0, 5.0], "high": [30.0, 36.0]}),
}


@pytest.fixture(scope="module")
def runs():
    plain = run(parse_spec(SPEC.replace("  modification: MODIFICATION\n", "")))
    return {"plain": plain, **{k: run(parse_spec(SPEC.replace("MODIFICATION", text))) for k, (text, _) in
                               CASES.items()}}


@pytest.mark.parametrize("kind", list(CASES))
def test_the_modified_rule_is_the_hand_written_one(runs, kind):
    sim = runs[kind].simulation
    ref = _scipy(np.asarray(sim.time), CASES[kind][1])
    e_ref = ref[:, 2] - ref[:, 0]
    assert _rms(sim.signals["e"]) == pytest.approx(_rms(e_ref), rel=AGREE)
    a = np.asarray(sim.controller_state[:, -2:], dtype=float)
    assert np.max(np.abs(a - ref[:, 8:]) / np.abs(ref[:, 8:])) < AGREE  # the whole parameter trajectory
    assert np.max(np.abs(sim.state[:, 0] - ref[:, 0])) < AGREE * AMPLITUDE


def test_each_modification_changes_the_run_as_derived(runs):
    plain = np.asarray(runs["plain"].simulation.controller_state[:, -2:], dtype=float)
    # matching after Km 2 -> 1: a1 = 40, a2 = 16 (tests/families/mrac/test_adaptation.py); the box [10, 30] x [5, 36]
    # stops a1 at 30, and a2, pushed up to make up for it, at 36
    proj = np.asarray(runs["projection"].simulation.controller_state[:, -2:], dtype=float)
    assert plain[:, 0].max() > 35.0
    assert proj[:, 0].max() == pytest.approx(30.0, abs=0.05) and proj[:, 1].max() == pytest.approx(36.0, abs=0.05)
    # the normalised rule adapts more slowly: its parameters are further from matching at the end
    norm = np.asarray(runs["normalized"].simulation.controller_state[-1, -2:], dtype=float)
    assert abs(norm[0] - 40.0) > abs(plain[-1, 0] - 40.0)
    # the dead zone: no parameter moves while |e1| <= d
    sim = runs["dead_zone"].simulation
    e = np.asarray(sim.signals["e"], dtype=float)
    a = np.asarray(sim.controller_state[:, -2:], dtype=float)
    quiet = (np.abs(e[:-1]) < 0.5 * 0.01) & (np.abs(e[1:]) < 0.5 * 0.01)  # a whole step well inside the zone
    assert quiet.sum() > 1000
    assert np.max(np.abs(np.diff(a, axis=0))[quiet]) < 1e-12


def test_the_modification_is_in_the_design_and_its_words(runs):
    d = runs["normalized"].design
    assert dict(d.data.modification) == {"kind": "normalized", "rate": 2.0}
    assert "normalised gradient rule" in d.formulas[-1]
    default = run(parse_spec(SPEC.replace("MODIFICATION", "{kind: normalized}"))).design
    assert default.data.modification["rate"] == pytest.approx(math.sqrt(20.0))  # the model's natural frequency


@pytest.mark.parametrize(("text", "path"), [
    ("{kind: dead_zone}", "controller.modification.width"),
    ("{kind: dead_zone, width: 0.01, rate: 3}", "controller.modification.rate"),
    ("{kind: projection, low: [5, 2], high: [4, 36]}", "controller.modification.high[0]"),
    ("{kind: projection, low: [5], high: [80, 36]}", "controller.modification.low"),
    ("{kind: projection, low: [25, 2], high: [80, 36]}", "controller.modification.low[0]"),
    ("{kind: nudge}", "controller.modification.kind"),
])
def test_bad_modifications_are_refused_with_their_key_path(text, path, tmp_path, capsys):
    from tests.cli_input import assert_bad_input

    assert_bad_input(tmp_path, capsys, SPEC.replace("MODIFICATION", text), path)
