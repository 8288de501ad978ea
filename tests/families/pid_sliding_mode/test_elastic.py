"""PID/sliding mode on the elastic joint (families/pid_sliding_mode/elastic.py): the sliding motion against the
closed-form transfer function (scipy), the equivalent control against the plant's own equation (finite
differences of the motion), and a run that slides with the motor on slm = 0."""

from __future__ import annotations

import numpy as np
import pytest

from designkit.families.pid_sliding_mode.elastic import sliding_motion
from designkit.families.pid_sliding_mode.surface import surface
from designkit.models.elastic import elastic_state_space
from designkit.models.robots.elastic_link import elastic_link

GAINS = {"K1": 37.0, "K2": 3.2, "K3": 120.0, "K4": -0.225}

SPEC = """\
name: pid-sm-elastic
plant: {kind: elastic_joint, uncertainty: {J2: [0.45, 0.55], Km: [1.8, 2.2]}}
controller: {kind: pid_sliding_mode, poles: [-3, -4, -12]}
requirements: {overshoot: 15, settling_time: 2.5, steady_state_error: 0.02}
simulation: {duration: 3.0, step: 1.0, perturbation: {value: 0.2, time: 2.0}}
"""


@pytest.mark.parametrize("overrides", [{}, {"J2": 0.3, "tau2": 0.7, "KR": 120.0}])
def test_load_sliding_motion_is_the_closed_form_transfer(overrides):
    from scipy import signal

    params = elastic_link(**overrides)
    sf = surface([-8, -10, -12])
    t = np.linspace(0, 3, 6001)
    m = sliding_motion(params, sf.a1, sf.a2, GAINS, t, np.ones_like(t), np.zeros_like(t), 0.0)
    k2 = params.KR * params.R2**2 / params.J2
    num = [k2]
    den = np.polymul([sf.a2, sf.a1, 1.0], [1.0, 1.0 / params.tau2, k2])
    _, y = signal.step((num, den), T=t)
    assert m["x"][:, 2] == pytest.approx(y, abs=2e-6)


def test_equivalent_control_drives_the_plant_along_the_motion():
    params = elastic_link(Km=2.2, J2=0.45)
    sf = surface([-8, -10, -12])
    t = np.linspace(0, 1, 200001)
    w = np.where(t >= 0.5, 0.2, 0.0)
    m = sliding_motion(params, sf.a1, sf.a2, GAINS, t, np.ones_like(t), w, 0.0)
    A, B = elastic_state_space(params)
    x = m["x"]
    xdot = np.gradient(x, t, axis=0)
    rhs = x @ A.T + np.outer(m["u_eq"], B[:, 0])
    rhs[:, 3] += params.R2 / params.J2 * w
    inner = (t > 0.01) & (np.abs(t - 0.5) > 0.01)
    assert np.max(np.abs(xdot[inner] - rhs[inner])) < 1e-3 * np.max(np.abs(xdot[inner]))
    # on the motion slm = a1 x1 + a2 x2 + z with z' = x1 - xD vanishes: z = -a1 x1 - a2 x2 integrates x1 - xD
    z = -sf.a1 * x[:, 0] - sf.a2 * x[:, 1]
    assert np.gradient(z, t)[inner] == pytest.approx((x[:, 0] - 1.0)[inner], abs=1e-3)


@pytest.fixture(scope="module")
def result():
    from designkit.pipeline import run
    from designkit.schema.loader import parse_spec

    return run(parse_spec(SPEC))


def test_the_motor_slides_and_the_load_follows_its_motion(result):
    checks = {c.name: c for c in result.checks}
    assert checks["pid_sm_elastic_relay"].passed and checks["pid_sm_elastic_band"].passed
    sim = result.simulation
    x1 = np.asarray(sim.state[:, 0])
    # the motor follows xD/N(s) whatever the plant (computed here with scipy from the poles -3, -4)
    from scipy import signal

    _, ideal = signal.step(([1.0], [1 / 12, 7 / 12, 1.0]), T=np.asarray(sim.time))
    assert np.max(np.abs(x1 - ideal)) < 5e-3
    info = result.design.data
    assert info.load_mode.zeta == pytest.approx(1 / (2 * 2.0 * 20.0))
    # no load offset of the motor: the integral holds x1 at xD; the spring carries the 0.2 N*m: x3 = xD + w/KR
    assert np.mean(np.asarray(sim.state[-200:, 0])) == pytest.approx(1.0, abs=2e-3)


def test_fast_sliding_poles_ring_the_load():
    from designkit.pipeline import run
    from designkit.schema.loader import parse_spec

    res = run(parse_spec(SPEC.replace("[-3, -4, -12]", "[-8, -10, -12]")))
    checks = {c.name: c for c in res.checks}
    assert checks["pid_sm_elastic_band"].passed  # the motor still slides ...
    assert checks["settling_time"].passed is False  # ... but the lightly damped load does not settle


def test_uncontrollable_elastic_joint_is_refused_at_the_parameter(tmp_path, capsys):
    from tests.cli_input import assert_bad_input

    text = SPEC.replace("kind: elastic_joint,", "kind: elastic_joint, KR: 1.0e-6,")
    assert_bad_input(tmp_path, capsys, text, "plant.KR: makes the plant uncontrollable")
    bad_pole = SPEC.replace("[-3, -4, -12]", "[-3, -4, 0.5]")
    assert_bad_input(tmp_path, capsys, bad_pole, "controller.poles[2]")


def test_figures_draw_the_motor_and_the_link(result):
    from designkit.families import family
    from designkit.families.pid_sliding_mode.elastic import motion_figure, sliding_variable_figure

    assert {sliding_variable_figure, motion_figure} <= set(family("pid_sliding_mode").figures)
    slm, motion = sliding_variable_figure(result), motion_figure(result)
    assert slm is not None and "<svg" in slm.svg and "the band (green)" in slm.caption
    assert motion is not None and "the simulated link (purple)" in motion.caption
    assert "20 rad/s, damping 0.0125" in motion.caption


def test_relay_covers_interior_plants_of_the_box(result):
    # M is sized on the corners; at random interior plants the sliding motion's equivalent control stays below it
    info = result.design.data
    gains = {k: float(result.design.gains[k]) for k in ("K1", "K2", "K3", "K4")}
    t = np.linspace(0.0, 3.0, 12001)
    r = np.ones_like(t)
    w = np.where(t >= 2.0, 0.2, 0.0)
    rng = np.random.default_rng(17)
    worst = 0.0
    for _ in range(20):
        params = elastic_link(J2=rng.uniform(0.45, 0.55), Km=rng.uniform(1.8, 2.2))
        m = sliding_motion(params, info.a1, info.a2, gains, t, r, w, 0.0)
        worst = max(worst, float(np.max(np.abs(m["du_eq"]))))
    assert worst <= info.sup_du_eq * (1 + 1e-9) < info.M
