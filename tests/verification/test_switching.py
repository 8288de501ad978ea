"""How a command switches, measured on synthetic records against counts and sums of our own: a square wave of known
frequency on a smooth part, a sine with noise, a command alternating every step."""

from __future__ import annotations

import numpy as np
import pytest

from designkit.verification.switching import measure, moving_average, reversals, warning

DT = 1e-4
T = np.arange(0.0, 2.0 + DT / 2, DT)


def _square(f: float, amplitude: float) -> np.ndarray:
    return amplitude * np.sign(np.sin(2 * np.pi * f * T + 0.1))


@pytest.mark.parametrize("f, amplitude", [(50.0, 2.0), (120.0, 5.0)])
def test_square_wave_on_a_smooth_part(f, amplitude):
    smooth = 3.0 + np.sin(np.pi * T)
    square = _square(f, amplitude)
    m = measure("u", T, smooth + square, window=10 / f)
    edges = int(np.count_nonzero(np.diff(square)))  # own count of the square's edges
    assert m.reversals == edges - 1  # the first edge sets the direction
    assert m.rate == pytest.approx(2 * f, rel=0.01)
    assert m.switching_rms == pytest.approx(amplitude, rel=0.05)
    assert m.averaged_rms == pytest.approx(np.sqrt(np.mean(smooth ** 2)), rel=0.02)
    assert m.dominates == bool(amplitude > np.sqrt(np.mean(smooth ** 2)))
    # total variation: 2 A per edge plus the smooth part's 0 -> 1 -> -1 -> 0 (4)
    assert m.variation == pytest.approx(2 * amplitude * edges + 4.0, rel=0.01)
    assert m.variation_rate == pytest.approx(m.variation / 2.0)
    assert not m.step_set and not m.sampling_set
    assert (warning(m) is not None) == m.dominates


def test_sine_with_small_noise_reverses_at_its_extrema():
    rng = np.random.default_rng(3)
    clean = 2.0 * np.sin(2 * np.pi * 5.0 * T)
    u = clean + 0.01 * rng.standard_normal(T.size)
    extrema = int(np.count_nonzero(np.diff(np.sign(np.diff(clean)))))  # own count: turns of the clean sine
    m = measure("u", T, u, window=1.0)
    assert m.reversals == extrema
    assert not m.step_set


def test_noise_faster_than_the_window_is_switching_at_the_step():
    rng = np.random.default_rng(4)
    sigma = 0.01
    u = 2.0 * np.sin(2 * np.pi * 5.0 * T) + sigma * rng.standard_normal(T.size)
    m = measure("u", T, u, window=20 * DT)
    # the moving average keeps the sine and a 1/21 share of the noise's power (21 samples)
    assert m.switching_rms == pytest.approx(sigma * np.sqrt(1 - 1 / 21), rel=0.05)
    assert m.ratio == pytest.approx(sigma / np.sqrt(2.0), rel=0.1)
    assert not m.dominates
    assert m.step_set  # white noise turns about every other sample
    text = warning(m)
    assert text is not None and "numerical choice" in text and "dominates" not in text


def test_alternating_every_step_is_set_by_the_step_and_dominates():
    u = 0.2 + 1.5 * (-1.0) ** np.arange(T.size)
    m = measure("tau1", T, u, window=0.05, sampling_period=0.0)
    assert m.reversals == T.size - 2
    assert m.rate == pytest.approx(1 / DT, rel=0.01)
    assert m.step_set and m.dominates
    text = warning(m, "N*m")
    assert "tau1" in text and "dominates" in text and "integration step" in text


def test_sampled_command_rate_against_the_sampling_period():
    ts = 1e-3
    held = np.sign(np.sin(2 * np.pi * 200.0 * np.floor(T / ts) * ts + 0.1))  # 400 reversals/s, held per sample
    m = measure("u", T, held, window=0.05, sampling_period=ts)
    assert m.rate == pytest.approx(400.0, rel=0.02)
    assert m.sampling_set and not m.step_set
    assert "sampling period" in warning(m)


def test_smooth_command_does_not_switch():
    u = 4.0 * np.exp(-3 * T)
    m = measure("u", T, u, window=0.05)
    assert m.reversals == 0
    assert warning(m) is None
    assert m.variation == pytest.approx(4.0 * (1 - np.exp(-6.0)), rel=1e-9)


def test_moving_average_against_a_convolution():
    rng = np.random.default_rng(5)
    u = rng.standard_normal(T.size)
    k = 101  # window = 100 steps
    avg = moving_average(T, u, window=100 * DT)
    # trapezoid rule over the window: the two end samples weigh half
    kernel = np.ones(k)
    kernel[[0, -1]] = 0.5
    expected = np.convolve(u, kernel / 100.0, mode="same")
    assert np.allclose(avg[k:-k], expected[k:-k], atol=1e-12)


def test_reversals_hysteresis():
    assert reversals(np.array([0.0, 1.0, 0.95, 1.1, 0.0, 0.5]), 0.2) == 2
    assert reversals(np.array([0.0, 1.0, 0.95, 1.1, 0.0, 0.5]), 0.01) == 4


def test_a_diverged_record_is_measured_up_to_the_divergence():
    u = _square(50.0, 1.0)
    u[T.size // 2:] = np.nan
    m = measure("u", T, u, window=0.2)
    assert m.duration == pytest.approx(1.0, abs=2 * DT)
    assert m.rate == pytest.approx(100.0, rel=0.02)


def test_loop_window_from_the_design_poles_then_the_spec_then_the_run():
    from types import SimpleNamespace as Ns

    from designkit.verification.switching import loop_window

    spec = Ns(controller=Ns(poles=[-4.0, -20.0]), simulation=Ns(sampling_period=0.0))
    assert loop_window(Ns(poles=(complex(-5, 3),)), spec, 3.0) == pytest.approx(0.2)  # the sliding pole -c
    assert loop_window(Ns(poles=()), spec, 3.0) == pytest.approx(0.05)
    assert loop_window(None, Ns(controller=Ns(), simulation=Ns(sampling_period=0.0)), 3.0) == pytest.approx(0.03)
    sampled = Ns(controller=Ns(poles=[-400.0]), simulation=Ns(sampling_period=0.01))
    assert loop_window(None, sampled, 3.0) == pytest.approx(0.02)  # at least two sampling periods
