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
