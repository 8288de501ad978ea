"""The reaching condition sigma sigma' < 0 with the law as built, at random states and random plants of the box;
the sign convention (the notes' theorem 3 labelling fails it); the boundary layer's law."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from designkit.models.elastic import elastic_state_space
from designkit.models.robots.elastic_link import DEFAULTS
from tests.families.vsc.common import ELASTIC_BOX, ELASTIC_SPEC, run_text

REST = np.array([1.0, 0.0, 1.0, 0.0])


def _command(law, x, xd=0.3):
    y = x + xd * REST
    return float(law.command(y, [], [], [xd, 0.0, 0.0]))


def _sigma_sigmadot(design, law, params, x, d):
    A, B = elastic_state_space(params)
    D = np.array([0.0, 0.0, 0.0, params.R2 / params.J2])
    c = np.asarray(design.data.c)
    u = _command(law, x)
    xdot = A @ x + B.ravel() * u + D * d
    return float(c @ x), float(c @ xdot)


def test_reaching_condition_at_random_states_and_plants(elastic_result):
    d, law = elastic_result.design, elastic_result.design.law
    info = d.data
    rng = np.random.default_rng(3)
    worst = -np.inf
    for _ in range(400):
        p = dataclasses.replace(DEFAULTS, **{k: rng.uniform(*v) for k, v in ELASTIC_BOX.items()})
        x = rng.normal(size=4) * np.array([0.5, 5.0, 0.5, 5.0])
        dist = rng.uniform(-1, 1) * info.d_bar
        s, sdot = _sigma_sigmadot(d, law, p, x, dist)
        cB = p.Km / p.tau1
        cD = info.c[3] * p.R2 / p.J2
        bound = -(cB * info.delta - abs(cD) * info.d_bar) * abs(s)  # derived in gains.py's docstring
        assert s * sdot <= bound + 1e-9 * (1 + abs(s * sdot))
        worst = max(worst, s * sdot)
    assert worst < 0


def test_the_printed_theorem_3_labelling_fails_the_reaching_condition(elastic_result):
    """alpha_i where x_i sigma < 0 (the notes' theorem 3) with alpha_i < l_i < beta_i: sigma sigma' > 0 at some
    states (here, at most of them) -- with that labelling the inequalities must read alpha_i > l_i > beta_i."""
    d = elastic_result.design
    info = d.data
    swapped = dataclasses.replace(d, data=dataclasses.replace(info, alpha=info.beta, beta=info.alpha))
    from designkit.families.vsc import law as build_law

    law = build_law(swapped)
    rng = np.random.default_rng(4)
    positive = 0
    for _ in range(200):
        x = rng.normal(size=4) * np.array([0.5, 5.0, 0.5, 5.0])
        s, sdot = _sigma_sigmadot(d, law, DEFAULTS, x, 0.0)
        positive += s * sdot > 0
    assert positive > 100


def test_boundary_layer_law_is_continuous_and_the_switching_law_outside_the_layer(elastic_result):
    eps = 0.05
    layered = run_text(ELASTIC_SPEC.read_text().replace("  margin: 0.2\n", f"  margin: 0.2\n  boundary_layer: {eps}\n"))
    law_sw, law_bl = elastic_result.design.law, layered.design.law
    assert law_sw.discontinuous and not law_bl.discontinuous
    c = np.asarray(elastic_result.design.data.c)
    rng = np.random.default_rng(8)
    for _ in range(100):
        x = rng.normal(size=4) * np.array([0.5, 5.0, 0.5, 5.0])
        if abs(c @ x) > eps:
            assert _command(law_bl, x) == pytest.approx(_command(law_sw, x), rel=1e-12, abs=1e-12)
        # across sigma = 0: move x along c by +-1e-9 around the surface, the layered command moves by O(1e-9/eps)
        x0 = x - (c @ x) / (c @ c) * c
        up, down = x0 + 1e-9 * c / (c @ c), x0 - 1e-9 * c / (c @ c)
        assert abs(_command(law_bl, up) - _command(law_bl, down)) < 1e-5
