"""Strategies and builders shared by the verification tests."""

from __future__ import annotations

import itertools

import numpy as np
from hypothesis import strategies as st

from designkit.models.link import LinkPlant
from designkit.simulation.result import SimulationResult
from designkit.verification.tolerances import POLE_REL

real_pole = st.floats(min_value=-50.0, max_value=-0.1, allow_nan=False)
plants = st.builds(
    LinkPlant,
    Km=st.floats(min_value=0.1, max_value=10.0, allow_nan=False),
    tau=st.floats(min_value=0.05, max_value=5.0, allow_nan=False),
)


@st.composite
def pole_sets(draw) -> tuple[complex, complex, complex]:
    """Three stable poles: a real triple, or a conjugate pair plus a real pole (1/s)."""
    if draw(st.booleans()):
        return tuple(complex(draw(real_pole)) for _ in range(3))
    re = draw(st.floats(min_value=-30.0, max_value=-0.1))
    im = draw(st.floats(min_value=0.1, max_value=30.0))
    return (complex(re, im), complex(re, -im), complex(draw(real_pole)))


def well_separated(poles, rel: float = 1e-2) -> bool:
    """Poles pairwise farther apart than ``rel`` times the largest magnitude (simple roots)."""
    p = np.asarray(poles, complex)
    R = np.max(np.abs(p))
    return all(abs(a - b) > rel * R for a, b in itertools.combinations(p, 2))


def same_multiset(actual, expected, rel: float = POLE_REL) -> bool:
    """Best matching over permutations (independent of the module's assignment), errors scaled by max |expected|."""
    a, e = np.asarray(actual, complex), np.asarray(expected, complex)
    if a.shape != e.shape:
        return False
    R = max(1e-300, float(np.max(np.abs(e))))
    best = min(np.max(np.abs(a[list(perm)] - e)) for perm in itertools.permutations(range(len(a))))
    return bool(best / R <= rel)


def step_result(time, x1, u, *, amplitude: float = 1.0, u_applied=None, kind: str = "step",
                reference=None) -> SimulationResult:
    """A SimulationResult built directly from sampled signals (no simulation engine)."""
    time = np.asarray(time, float)
    n = len(time)
    if reference is None:
        reference = np.zeros((n, 3))
        reference[:, 0] = amplitude
    x1 = np.asarray(x1, float)
    state = np.column_stack([x1, np.gradient(x1, time)])
    u = np.asarray(u, float)
    return SimulationResult(
        time=time, reference=np.asarray(reference, float), state=state, controller_state=np.zeros((n, 1)),
        u_command=u, u_applied=u if u_applied is None else np.asarray(u_applied, float),
        perturbation=np.zeros(n), measured=state.copy(), kind=kind,
    )


def rk4_relay_lag(a: float, b: float, c: float, m: float, bandwidth: float, dt: float, delay: float,
                  span: float) -> tuple[float, float, float]:
    """Our own RK4 run of the link along ``s = c e + x2`` (``e' = x2``, ``x2' = -a x2 + b u_a``) behind the lag
    ``u_a' = bandwidth (v - u_a)``, the relay ``v = -m sign(s)`` read at the start of every step ``dt`` (s) and
    applied ``delay`` (s) later, from ``e = 0.01``, for ``span`` (s): the frequency (Hz, the mean period between
    the upward sign changes of ``s`` over the last half), half the peak-to-peak of ``s`` and of ``u_a`` there."""

    def f(x: np.ndarray, v: float) -> np.ndarray:
        return np.array([x[1], -a * x[1] + b * x[2], bandwidth * (v - x[2])])

    n, late = int(round(span / dt)), int(round(delay / dt))
    x, line = np.array([0.01, 0.0, 0.0]), [0.0] * late
    s_out, ua = np.empty(n), np.empty(n)
    for i in range(n):
        s = c * x[0] + x[1]
        line.append(-m * np.sign(s))
        v = line.pop(0)
        k1 = f(x, v)
        k2 = f(x + dt / 2 * k1, v)
        k3 = f(x + dt / 2 * k2, v)
        k4 = f(x + dt * k3, v)
        x = x + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        s_out[i], ua[i] = s, x[2]
    w = slice(n // 2, n)
    up = np.flatnonzero((s_out[w][:-1] < 0) & (s_out[w][1:] >= 0))
    return (len(up) - 1) / ((up[-1] - up[0]) * dt), float(np.ptp(s_out[w])) / 2, float(np.ptp(ua[w])) / 2
