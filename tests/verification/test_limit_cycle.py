"""The relay's limit cycle predicted by :mod:`designkit.verification.limit_cycle`, against closed forms and
brute-force simulations of our own (NumPy and scipy's ``cont2discrete``, not the module's exponentials)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.signal import cont2discrete

from designkit.verification.limit_cycle import (
    Loop,
    continuous_orbit,
    critical_gain,
    describing_function,
    layer_for_gain,
    sampled_orbit,
    sampled_orbits,
)

K, T, M = 2.0, 0.5, 1.0


def first_order() -> Loop:
    """``s = K/(T p + 1) v``."""
    return Loop.of([[-1 / T]], [K / T], [1.0])


def test_hysteresis_on_first_order_lag_closed_form():
    # the classic result: y swings between -h and h; from h under -M: y = -KM + (KM + h) exp(-t/T) reaches -h at
    # T ln((KM + h)/(KM - h)), so the period is twice that
    h = 0.3
    orbit = continuous_orbit(first_order(), M, hysteresis=h)
    assert orbit is not None
    assert 2 * orbit.half_period == pytest.approx(2 * T * math.log((K * M + h) / (K * M - h)), rel=1e-9)
    assert orbit.amplitude == pytest.approx(h, rel=1e-6)


def test_delay_on_first_order_lag_closed_form():
    # derived here: the input turns to -M at the peak y_p; y = -KM + (y_p + KM) exp(-t/T) crosses 0 at
    # t1 = T ln((y_p + KM)/KM); the input turns L later, where y = -y_p by symmetry: y_p = KM (1 - exp(-L/T)),
    # and the half period is t1 + L = L + T ln(2 - exp(-L/T))
    L = 0.1
    orbit = continuous_orbit(first_order(), M, delay=L)
    assert orbit is not None
    y_p = K * M * (1 - math.exp(-L / T))
    assert orbit.amplitude == pytest.approx(y_p, rel=1e-6)
    assert orbit.half_period == pytest.approx(L + T * math.log(2 - math.exp(-L / T)), rel=1e-9)


def test_no_continuous_orbit_without_hysteresis_or_delay():
    assert continuous_orbit(first_order(), M) is None


def _simulate_relay(a, b, c, m, dt, duration):
    """RK4 of ``x' = A x + B v``, ``v = -M sign(C x)`` evaluated at every step and held over it."""
    x = np.array([0.3, 0.0, 0.0])
    n = int(duration / dt)
    s = np.empty(n)
    for i in range(n):
        v = -m * np.sign(c @ x)
        f = lambda z, v=v: a @ z + b * v  # noqa: E731
        k1 = f(x)
        k2 = f(x + dt / 2 * k1)
        k3 = f(x + dt / 2 * k2)
        k4 = f(x + dt * k3)
        x = x + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        s[i] = c @ x
    return s


def test_describing_function_third_order_against_simulation():
    # K/(p (p + 1)(p + 2)): the phase crosses -180 deg at w = sqrt(2) (Im of the denominator at jw vanishes), where
    # |G| = K/6, so the harmonic balance gives A = 4 M K/(6 pi)
    gain = 3.0
    loop = Loop.transfer([gain], [1, 3, 2, 0])
    cycle = describing_function(loop, M)
    assert cycle is not None
    assert cycle.frequency == pytest.approx(math.sqrt(2), rel=1e-9)
    assert cycle.amplitude == pytest.approx(4 * M * gain / (6 * math.pi), rel=1e-9)
    dt = 1e-3
    s = _simulate_relay(loop.a, loop.b, loop.c, M, dt, 60.0)
    tail = s[len(s) // 2:]
    ups = np.flatnonzero((tail[:-1] < 0) & (tail[1:] >= 0))
    period = float(np.mean(np.diff(ups))) * dt
    assert 2 * math.pi / period == pytest.approx(cycle.frequency, rel=0.05)
    assert float(np.max(np.abs(tail))) == pytest.approx(cycle.amplitude, rel=0.25)


def _brute(a, b, c, m, ts, sub, delay_steps, samples):
    """The sampled relay loop stepped at ``ts/sub`` by scipy's ``cont2discrete``: the command ``-M sign(s_j)``
    computed at each sample, reaching the plant ``delay_steps`` sub-steps later and held until the next one."""
    ad, bd, *_ = cont2discrete((a, b.reshape(-1, 1), c.reshape(1, -1), np.zeros((1, 1))), ts / sub)
    x = np.zeros(a.shape[0])
    x[0] = 0.01
    pending: list[tuple[int, float]] = []
    applied = 0.0
    out = []
    for i in range(samples * sub):
        if i % sub == 0:
            s = float(c @ x)
            out.append(s)
            pending.append((i + delay_steps, -m * float(np.sign(s))))
        while pending and pending[0][0] <= i:
            applied = pending.pop(0)[1]
        x = ad @ x + bd[:, 0] * applied
    return np.array(out)


def _steady_period(s: np.ndarray) -> tuple[int, np.ndarray]:
    """The brute force's steady period ``n`` (samples; the smallest after which its tail repeats to 1e-10) and
    its last period, rotated to start at the first of a run of positive samples."""
    tail = s[-2000:]
    n = next(n for n in range(1, 500) if np.max(np.abs(tail[n:] - tail[:-n])) < 1e-10)
    starts = [i for i in range(1, 2 * n + 1) if tail[-3 * n + i] > 0 >= tail[-3 * n + i - 1]]
    i = len(tail) - 3 * n + starts[0]
    return n, tail[i:i + n]


STABLE = ([3.0], [1, 3.5, 3.5, 1])
"""``3/((p + 0.5)(p + 1)(p + 2))``: no integrator, so its orbits are isolated."""


@pytest.mark.parametrize("case", ["stable third order", "stable third order, delayed", "sliding line"])
def test_sampled_orbit_against_brute_force(case):
    integrator = case == "sliding line"
    if integrator:  # the link along s = x2 + c e: b (p + c)/(p (p + a))
        loop = Loop.of([[0, 1], [0, -2.0]], [0, 4.0], [5.0, 1])
        ts, sub, lag, samples = 1e-3, 4, 0, 20000
    else:
        loop = Loop.transfer(*STABLE)
        ts, sub, lag, samples = 0.1, 5, (2 if "delayed" in case else 0), 3000
    s = _brute(loop.a, loop.b, loop.c, M, ts, sub, lag, samples)
    n, last = _steady_period(s)
    orbits = {2 * o.half_period: o for o in sampled_orbits(loop, M, ts, delay=lag * ts / sub)}
    # the run settles on one of the predicted orbits, sample for sample
    assert n in orbits, (n, sorted(orbits))
    expected = orbits[n].samples
    if integrator:  # a member of the family shifted along the integrator: the same orbit about its mean
        last, expected = last - np.mean(last), expected - np.mean(expected)
    assert np.allclose(last, expected, atol=1e-9, rtol=0)
    assert orbits[n].frequency == pytest.approx(1 / (n * ts))
    smallest = sampled_orbit(loop, M, ts, delay=lag * ts / sub)
    assert smallest.half_period == min(orbits) // 2 and smallest.tried == smallest.half_period - 1


def test_sampled_first_order_k1_closed_form():
    # s_{j+1} = p s_j - K (1 - p) M sign(s_j), p = exp(-Ts/T): the 2-periodic orbit s = +-K M (1 - p)/(1 + p)
    ts = 0.05
    orbit = sampled_orbit(first_order(), M, ts)
    p = math.exp(-ts / T)
    assert orbit is not None and orbit.half_period == 1
    assert orbit.sampled_amplitude == pytest.approx(K * M * (1 - p) / (1 + p), rel=1e-12)


def test_lag_adds_the_actuator_output():
    loop = Loop.transfer([3.0], [1, 3, 2, 0]).with_lag(20.0)
    # the lag's phase moves the crossing below sqrt(2): -180 deg where atan(w) + atan(w/2) + atan(w/20) = pi/2
    cycle = describing_function(loop, M)
    w = cycle.frequency
    assert math.atan(w) + math.atan(w / 2) + math.atan(w / 20) == pytest.approx(math.pi / 2, rel=1e-9)
    orbit = sampled_orbit(loop, M, 0.05)
    assert orbit is not None and orbit.peak("actuator") <= M


def test_critical_gain_sampled_integrator():
    # s' = b v, v = -K s held over Ts: s_{j+1} = (1 - K b Ts) s_j, unstable from K = 2/(b Ts)
    b_, ts = 4.0, 1e-3
    loop = Loop.of([[0.0]], [b_], [1.0])
    assert critical_gain(loop, ts) == pytest.approx(2 / (b_ * ts), rel=1e-9)
    # with a one-sample delay: z^2 - z + K b Ts = 0 reaches |z| = 1 at K b Ts = 1
    assert critical_gain(loop, ts, delay=ts) == pytest.approx(1 / (b_ * ts), rel=1e-9)
    assert critical_gain(loop) == math.inf
    assert layer_for_gain(1.2, 500.0, 0.5) == pytest.approx(1.2 / 250.0)


def test_critical_gain_continuous_third_order():
    # Routh on p^3 + 3 p^2 + 2 p + K g: stable for K g < 6
    loop = Loop.transfer([3.0], [1, 3, 2, 0])
    assert critical_gain(loop) == pytest.approx(2.0, rel=1e-9)


def test_bad_arguments_are_named():
    from designkit.errors import SpecError

    with pytest.raises(SpecError, match="^period: "):
        sampled_orbit(first_order(), M, 0.0)
    with pytest.raises(SpecError, match="^amplitude: "):
        sampled_orbits(first_order(), -1.0, 0.1)
    with pytest.raises(SpecError, match="^num: "):
        Loop.transfer([1.0, 0.0], [1.0, 1.0])


def test_critical_gain_with_an_integrator_among_fast_modes():
    """A loop with a pole at 0 among lightly damped ones (s (s + 5)(s^2 + 24 s + 369) against (s + 1)(s^2 + 20 s +
    300), relative degree one): the integrator's pole sits on the unit circle at zero gain, where round-off must
    not read the loop as unstable; the critical gain against our own scan of the closed loop's spectral radius
    (scipy's cont2discrete, ZOH)."""
    from scipy.signal import cont2discrete

    from designkit.verification.limit_cycle import critical_gain

    den = np.polymul([1, 0], np.polymul([1, 5], [1, 24, 369]))
    num = np.polymul([1, 1], [1, 20, 300])
    a = np.zeros((4, 4))
    a[:3, 1:] = np.eye(3)
    a[3] = -den[:0:-1]
    b = np.array([0, 0, 0, 1.0])
    c = num[::-1].astype(float)
    loop = Loop.of(a, b, c)
    h = 7.2e-5
    ad, bd, *_ = cont2discrete((a, b.reshape(-1, 1), c.reshape(1, -1), np.zeros((1, 1))), h)

    def radius(k: float) -> float:
        return float(np.max(np.abs(np.linalg.eigvals(ad - k * bd @ c.reshape(1, -1)))))

    grid = np.geomspace(1.0, 1e6, 4001)
    first = next(k for k in grid if radius(k) >= 1)
    got = critical_gain(loop, h)
    assert 0 < got < math.inf
    assert got == pytest.approx(first, rel=grid[1] / grid[0] - 1)
