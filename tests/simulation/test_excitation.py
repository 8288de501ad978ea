"""Square-wave and PRBS references, which references a family follows, and a plant change during the run."""

from __future__ import annotations

import numpy as np
import pytest

from designkit.errors import SpecError
from designkit.families import synthesize
from designkit.schema.loader import parse_spec
from designkit.simulation.reference import PRBS_TAPS, prbs, prbs_bits, square
from designkit.simulation.run import simulate

LINK = "plant: {kind: link, Km: 2.0, tau: 0.5}\n"
SERVO = "controller: {kind: pid_servo, poles: [-4, -5, -20], zero: -3}\n"


@pytest.mark.parametrize("order", sorted(PRBS_TAPS))
def test_every_shift_register_is_maximal_length(order):
    """Period 2^n - 1 (the register visits every non-zero state), and 2^(n-1) ones per period."""
    n = 2**order - 1
    bits = prbs_bits(order, 2 * n, seed=12345)
    assert np.array_equal(bits[:n], bits[n:])
    assert int(bits[:n].sum()) == 2 ** (order - 1)
    windows = {tuple(np.roll(bits[:n], -k)[:order]) for k in range(n)}
    assert len(windows) == n  # every non-zero order-bit pattern once


def test_prbs_levels_switch_on_the_bit_grid_and_the_seed_shifts_the_sequence():
    ref = prbs(0.5, 0.2, order=5, seed=3, start=1.0, n=1)
    t = np.arange(0, 31 * 0.2, 0.05)
    x = ref.evaluate(t)[:, 0, 0]
    assert set(np.round(x, 12)) == {0.5, 1.5}
    assert np.all(ref.evaluate(t)[:, 0, 1:] == 0.0)
    changes = t[1:][np.diff(x) != 0]
    assert np.allclose(np.round(changes / 0.2), changes / 0.2, atol=1e-9)
    other = prbs(0.5, 0.2, order=5, seed=4, start=1.0, n=1).evaluate(t)[:, 0, 0]
    assert not np.array_equal(x, other)


def test_square_wave_alternates_about_the_start():
    ref = square([0.2, -0.1], 2.0, start=[0.0, 1.0], n=2)
    x = ref.evaluate(np.array([0.0, 0.5, 0.99, 1.0, 1.5, 2.0]))[:, :, 0]
    assert np.allclose(x[:, 0], [0.2, 0.2, 0.2, -0.2, -0.2, 0.2])
    assert np.allclose(x[:, 1], [0.9, 0.9, 0.9, 1.1, 1.1, 0.9])


def test_a_servo_follows_a_square_wave_and_a_tracker_refuses_it():
    loaded = parse_spec(f"name: sq\n{LINK}{SERVO}simulation: {{duration: 4, trajectory: "
                        "{kind: square, amplitude: 0.3, period: 2.0}}\n")
    res = simulate(loaded.spec, synthesize(loaded.spec))
    assert res.settings["reference"]["kind"] == "square"
    # 1 s after each edge (t = 0 and t = 1 s) the servo is within 2.5 % of the 0.6 rad swing of the new level
    assert res.position[1000] == pytest.approx(0.3, abs=0.015) and res.position[1999] == pytest.approx(-0.3, abs=0.015)
    assert res.reference[999, 0, 0] == 0.3 and res.reference[1000, 0, 0] == -0.3
    with pytest.raises(SpecError) as info:
        parse_spec(f"name: sq\n{LINK}controller: {{kind: pid_tracking, poles: [-10, -12, -15]}}\nsimulation: "
                   "{trajectory: {kind: square, amplitude: 0.3, period: 2.0}}\n")
    assert info.value.path == "simulation.trajectory.kind" and "follows" in info.value.message
    with pytest.raises(SpecError) as info:
        parse_spec(f"name: q\n{LINK}{SERVO}simulation: {{trajectory: {{kind: quintic, amplitude: 1, duration: 1}}}}\n")
    assert info.value.path == "simulation.trajectory.kind"


def test_a_plant_change_acts_from_its_time_and_is_validated():
    """Km doubled at t = 2 s: before, the run equals the unchanged one; after, it differs; a bad name is refused."""
    base = f"name: pc\n{LINK}{SERVO}simulation: {{duration: 4.0, step: 1.0, perturbation: {{value: 0.5, time: 2.5}}"
    same = parse_spec(base + "}\n").spec
    changed = parse_spec(base + ", plant_change: {time: 2.0, values: {Km: 4.0}}}\n").spec
    a, b = simulate(same, synthesize(same)), simulate(changed, synthesize(changed))
    k = int(np.searchsorted(a.time, 2.0))
    # the changed run's adaptive steps end on t = 2 s (a breakpoint), the unchanged run's cross it, so the grid
    # points of the last step before it are interpolated from different steps: equal within the error control
    # (rtol 1e-10, atol 1e-12; RK4 on the grid gave bit-equal runs)
    np.testing.assert_allclose(a.state[: k + 1], b.state[: k + 1], rtol=0, atol=1e-9)
    assert np.max(np.abs(a.state[k + 600:] - b.state[k + 600:])) > 1e-3
    assert b.settings["plant_change"]["time_applied"] == pytest.approx(2.0)
    bad = parse_spec(base + ", plant_change: {time: 2.0, values: {Kx: 4.0}}}\n").spec
    with pytest.raises(SpecError) as info:
        simulate(bad, synthesize(bad))
    assert info.value.path == "simulation.plant_change.values.Kx"
