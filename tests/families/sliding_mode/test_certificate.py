"""The certificate of the conditions on the box: against a dense grid, and failing gain sets with their shortfall."""

from __future__ import annotations

import numpy as np
import pytest

from designkit.families.sliding_mode.checks import CERTIFICATE_RULE, gains_of
from designkit.families.sliding_mode.diagnoses import diagnose
from designkit.verification.suite import Context
from tests.families.sliding_mode.common import BOX, check

NAMES = ("sliding_existence", "sliding_reaching", "sliding_perturbation")


def _grid_values(g, xi_bar: float, n: int = 201) -> dict[str, np.ndarray]:
    """Every condition on an n x n grid of the box, written here from the derivation (not the family's code)."""
    Km, tau = np.meshgrid(np.linspace(*BOX["Km"], n), np.linspace(*BOX["tau"], n))
    c = g.c
    return {
        "sliding_existence": np.minimum(g.alpha * Km - c + c * c * tau, c - c * c * tau - g.beta * Km),
        "sliding_reaching": 4 * g.alpha * Km * tau - 1,
        "sliding_perturbation": np.full(Km.shape, g.M - xi_bar),
    }


def _certify(design, spec):
    return {c.name: c for c in CERTIFICATE_RULE.run(design, Context(spec))}


def test_designed_gains_are_certified_with_labelled_conditions(link_result):
    checks = {c.name: c for c in link_result.checks if c.name in NAMES}
    assert set(checks) == set(NAMES) and all(c.passed is True and c.required for c in checks.values())
    assert checks["sliding_existence"].certificate["forms"] == ["affine"]
    assert checks["sliding_reaching"].certificate["forms"] == ["multiaffine"]
    assert "existence conditions" in checks["sliding_existence"].detail
    assert "reaching conditions" in checks["sliding_reaching"].detail
    from designkit.families.sliding_mode.linear_checks import CERTIFICATE_LABELS

    # the link's three conditions and the linear plants' own, each labelled once
    assert CERTIFICATE_RULE.labels.keys() == set(NAMES) | CERTIFICATE_LABELS.keys()
    assert not set(NAMES) & CERTIFICATE_LABELS.keys()


def test_vertex_minimum_is_the_minimum_over_a_dense_grid(link_result):
    d = link_result.design
    g, xi_bar = gains_of(d), d.data.xi_bar
    grid = _grid_values(g, xi_bar)
    for name in NAMES:
        entries = check(link_result, name).certificate["conditions"]
        certified = min(e["minimum"] for e in entries)
        assert grid[name].min() >= certified - 1e-9 * (1 + abs(certified))
        assert grid[name].min() == pytest.approx(certified, rel=1e-9, abs=1e-12)  # the corners are grid points
    # the reaching minimum sits at the corner (Km_lo, tau_lo), where 1/(4 Km tau) is largest
    at = check(link_result, "sliding_reaching").certificate["conditions"][0]["at"]
    assert at == {"Km": 1.4, "tau": 0.35}


def test_multiaffine_vertex_theorem_on_random_gains():
    """Random gains: the vertex verdict of the focus condition is the dense grid's verdict."""
    from designkit.families.sliding_mode.conditions import SlidingGains, condition_sets
    from designkit.verification.conditions import certify

    rng = np.random.default_rng(11)
    for _ in range(12):
        g = SlidingGains(alpha=rng.uniform(0.3, 1.0), beta=-5.0, M=1.0, c=5.0)
        verdict = certify("r", condition_sets(g, 0.5)["reaching"], BOX).passed
        grid_ok = bool(_grid_values(g, 0.5, 101)["sliding_reaching"].min() > 0)
        assert verdict is grid_ok


def test_relay_below_the_perturbation_fails_with_the_shortfall(weak_result):
    c = check(weak_result, "sliding_perturbation")
    assert c.passed is False and c.required
    assert c.detail.startswith("M = 0.8 N*m is below sup|xi| = 1 N*m by 0.2 N*m; M >= 1.2 N*m with the 20 % margin")
    assert c.certificate["shortfall"] == {"M_perturbation": pytest.approx(0.2)}
    assert c.certificate["evidence"]["value"] == pytest.approx(-0.2)
    assert check(weak_result, "sliding_existence").passed is True
    cause, fix = diagnose(weak_result, c)
    assert "M = 0.8 N*m is below sup|xi| = 1 N*m by 0.2 N*m" in cause
    assert "M >= 1.2 N*m" in fix and "above 1 N*m" in fix


def test_beta_and_alpha_failures_name_the_corner_and_the_gain_that_would_do(link_result):
    import dataclasses

    d = link_result.design
    spec = link_result.loaded.spec
    # beta above k at the corner (Km_lo, tau_hi), where k = 5 (1 - 3.25)/1.4 = -8.036 is smallest
    bad = dataclasses.replace(d, gains=d.gains.replace(beta=-8.0, alpha=0.45))
    out = _certify(bad, spec)
    ex = out["sliding_existence"]
    assert ex.passed is False
    assert ex.certificate["evidence"]["theta"] == {"Km": 1.4, "tau": 0.65}
    assert ex.certificate["shortfall"]["beta_existence"] == pytest.approx(-8.0 - 5 * (1 - 5 * 0.65) / 1.4)
    assert "beta = -8 N*m/rad is above c (1 - c tau)/Km = -8.036 N*m/rad at Km = 1.4, tau = 0.65" in ex.detail
    re = out["sliding_reaching"]
    assert re.passed is False  # 0.45 < 1/(4 1.4 0.35) = 0.5102
    assert ("alpha = 0.45 N*m/rad is below 1/(4 Km tau) = a^2/(4 b) = 0.5102 N*m/rad at Km = 1.4, tau = 0.35"
            in re.detail)
    assert "alpha >= 0.6122 N*m/rad with the 20 % margin" in re.detail
    cause, fix = diagnose(link_result, re)
    assert "not a focus" in cause and "alpha >= 0.6122 N*m/rad" in fix
