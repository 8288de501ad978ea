"""Where the gradient rule loses stability: the simulated bracket on re-simulation, the frozen-signal bound against
the eigenvalues of the frozen loop, and the 1/amplitude^2 law."""

from __future__ import annotations

import numpy as np
import pytest

from designkit.families.mrac.boundary import floquet_boundary, frozen_signal_bound
from designkit.families.mrac.runs import adaptive_variant, assess, matching, sensitivities, simulate
from designkit.schema.loader import parse_spec
from tests.families.mrac.conftest import SPECS


def _rerun(result, scale):
    spec, d = result.loaded.spec, result.design
    sim = simulate(spec, d, result.plant, adaptive_variant(d, gamma_scale=scale))
    return sim, assess(sim, spec)


@pytest.mark.slow
def test_the_gamma_bracket_is_monotone_on_resimulation(unstable_result):
    check = next(c for c in unstable_result.checks if c.name == "adaptive_stability")
    assert check.passed is False
    lo, hi = check.certificate["bracket"]
    assert lo < hi <= 1.0 and hi / lo <= 1.25 ** 2  # the spec's gains (scale 1) diverge; bracket bisected below them
    want = matching(unstable_result.design, (1.0, 0.5))
    for scale in (lo / 2, lo):
        sim, a = _rerun(unstable_result, scale)
        assert a.stable, (scale, a.reason)
    sim, a = _rerun(unstable_result, lo / 2)
    assert np.allclose(sim.controller_state[-1, -2:], want, rtol=0.05)  # well inside: the parameters converge
    for scale in (hi, 2 * hi):
        _, a = _rerun(unstable_result, scale)
        assert not a.stable, (scale, a.reason)
    floquet = check.certificate["floquet_scale"]
    assert lo / 2 < floquet < hi  # the linearized loop loses stability inside what the simulation brackets


def test_the_frozen_signal_bound_is_where_the_frozen_loop_crosses_the_imaginary_axis(link_result):
    sim, d, spec = link_result.simulation, link_result.design, link_result.loaded.spec
    bound = frozen_signal_bound(sim, d, spec, link_result.plant)
    k = bound["k"]
    assert k == pytest.approx(1.0 * 0.5 / (2.0 * 0.5))  # Km tau_n / (Km_n tau) after the change
    i = int(np.argmin(np.abs(sim.time - bound["at"])))
    names = list(sim.controller_state_names)
    ym = sim.controller_state[:, [names.index("ym1"), names.index("ym2")]][i]
    S = sensitivities(sim)[i]
    r = sim.reference[i, 0, 0]
    Gamma, Q = np.diag(d.data.gamma), np.array(d.data.Q)
    # the frozen linearization about the matched trajectory, assembled here: dx' = A_m dx + k b phi' alpha~,
    # alpha~' = -s Gamma S' Q dx (b = (0, 1), phi = (r - ym1, -ym2))
    A = np.zeros((4, 4))
    A[:2, :2] = [[0.0, 1.0], [-20.0, -9.0]]
    A[1, 2:] = k * np.array([r - ym[0], -ym[1]])

    def worst(s):
        A[2:, :2] = -s * Gamma @ S.T @ Q
        eig = np.linalg.eigvals(A)
        return max(e.real for e in eig if abs(e) > 1e-9)  # one eigenvalue is 0 (rank-one coupling)

    s0 = bound["scale"]
    assert worst(0.999 * s0) < 0 < worst(1.001 * s0)


def test_the_boundary_estimates_scale_as_one_over_amplitude_squared(link_result):
    text = (SPECS / "mrac-link.yaml").read_text().replace("amplitude: 0.5", "amplitude: 1.0")
    loaded = parse_spec(text)
    d = link_result.design
    spec2 = loaded.spec
    sim2 = simulate(spec2, d, link_result.plant, d.law)
    sim1, spec1 = link_result.simulation, link_result.loaded.spec
    f1 = frozen_signal_bound(sim1, d, spec1, link_result.plant)
    f2 = frozen_signal_bound(sim2, d, spec2, link_result.plant)
    assert f1["scale"] / f2["scale"] == pytest.approx(4.0, rel=1e-6)
    q1 = floquet_boundary(sim1, d, spec1, link_result.plant, around=f1["scale"])
    q2 = floquet_boundary(sim2, d, spec2, link_result.plant, around=f2["scale"])
    assert q1["scale"] / q2["scale"] == pytest.approx(4.0, rel=0.02)  # each refined to 1 %
