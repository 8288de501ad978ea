"""Theorem 3's gains: l_i in closed form against the plant's own linearisation, the designed gains bracket l_i at
every vertex and inside the box, the certificate, the enclosure route."""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from designkit.families.vsc.gains import VscGains, bound_ranges, condition_sets, design_gains, rational_forms
from designkit.families.vsc.surface import sliding_surface
from designkit.models.elastic import ElasticJointPlant, elastic_state_space
from designkit.models.link import LinkPlant
from designkit.models.robots.elastic_link import DEFAULTS
from designkit.synthesis.state_space import linear_model
from designkit.verification.conditions import certify

POLES = [-8.0, -10.0, -12.0]
NAMES = ("J1", "tau1", "Km", "KR", "R1", "R2", "J2", "tau2", "mgl")


def _l_numpy(params, c):
    """l_i = -(cA)_i/(cB) from the model module's own NumPy state space (not CasADi)."""
    A, B = elastic_state_space(params)
    return -(c @ A) / (c @ B.ravel())


def _elastic_c():
    A, B = elastic_state_space(DEFAULTS)
    return sliding_surface(A, B, POLES)


def test_closed_forms_are_minus_cA_over_cB_at_random_plants():
    c = _elastic_c()
    forms = rational_forms("elastic_joint", c)
    rng = np.random.default_rng(7)
    for _ in range(50):
        values = {n: float(getattr(DEFAULTS, n)) * rng.uniform(0.5, 2.0) for n in NAMES if n != "mgl"}
        values["mgl"] = rng.uniform(0.0, 5.0)
        params = dataclasses.replace(DEFAULTS, **values)
        want = _l_numpy(params, c)
        got = [forms[f"l_{i + 1}"][0](values) / forms[f"l_{i + 1}"][1](values) for i in range(4)]
        assert got == pytest.approx(want, rel=1e-10, abs=1e-12)
        A, B = elastic_state_space(params)
        cB = forms["cB"][0](values) / forms["cB"][1](values)
        assert cB == pytest.approx(c @ B.ravel(), rel=1e-12)
        cD = c[3] * params.R2 / params.J2  # the load enters x4' with R2/J2
        assert forms["cD/cB"][0](values) / forms["cD/cB"][1](values) == pytest.approx(cD / cB, rel=1e-12)


def test_figure_5_3_l_formulas_as_printed():
    """l1 = (tau1/Km)(KR R1^2/J1 - c4 KR R2^2/J2), l2 = (tau1/Km)(1/tau1 - c1), l3 = (tau1/Km)(c4 KR R2^2/J2 -
    KR R1^2/J1), l4 = (tau1/Km)(c4/tau2 - c3) (mgl = 0): correct as printed."""
    c = _elastic_c()
    p = DEFAULTS
    k1, k2, g = p.KR * p.R1**2 / p.J1, p.KR * p.R2**2 / p.J2, p.tau1 / p.Km
    printed = [g * (k1 - c[3] * k2), g * (1 / p.tau1 - c[0]), g * (c[3] * k2 - k1), g * (c[3] / p.tau2 - c[2])]
    assert _l_numpy(p, c) == pytest.approx(printed, rel=1e-12)


def test_link_closed_forms():
    plant = LinkPlant(Km=2.0, tau=0.5)
    model = linear_model(plant)
    A, B, D = model.at()
    c = sliding_surface(A, B, [-5.0])
    forms = rational_forms("link", c)
    for Km, tau in itertools.product((1.4, 2.6), (0.35, 0.65)):
        A, B, D = model.at({"Km": Km, "tau": tau})
        want = -(c @ A) / (c @ B.ravel())
        got = [forms[k][0]({"Km": Km, "tau": tau}) / forms[k][1]({"Km": Km, "tau": tau}) for k in ("l_1", "l_2")]
        assert got == pytest.approx(want, abs=1e-12)
        assert (c @ D.ravel()) / (c @ B.ravel()) == pytest.approx(1.0)  # the link's perturbation is matched


boxes = st.fixed_dictionaries({
    "Km": st.tuples(st.floats(0.5, 2.0), st.floats(0.0, 1.0)),
    "J2": st.tuples(st.floats(0.1, 0.5), st.floats(0.0, 0.5)),
    "tau1": st.tuples(st.floats(0.02, 0.05), st.floats(0.0, 0.03)),
    "KR": st.tuples(st.floats(100.0, 200.0), st.floats(0.0, 100.0)),
}).map(lambda d: {k: (lo, lo + w) for k, (lo, w) in d.items()})


@settings(max_examples=8, deadline=None)
@given(boxes, st.floats(0.05, 1.0), st.integers(0, 2**32 - 1))
def test_designed_gains_bracket_l_at_every_vertex_and_inside(box, margin, seed):
    plant = ElasticJointPlant(DEFAULTS)
    model = linear_model(plant)
    box = {k: (min(lo, float(getattr(DEFAULTS, k))), max(hi, float(getattr(DEFAULTS, k)))) for k, (lo, hi) in
           box.items()}
    c = _elastic_c()
    forms = rational_forms("elastic_joint", c)
    bounds = bound_ranges(forms, model, box)
    al, be, S = design_gains(bounds, c, 12.0, 40.0, margin, None, None)
    names = list(box)
    points = [dict(zip(names, v, strict=True)) for v in itertools.product(*[box[n] for n in names])]
    rng = np.random.default_rng(seed)
    points += [{n: rng.uniform(*box[n]) for n in names} for _ in range(30)]
    for pt in points:
        l = _l_numpy(dataclasses.replace(DEFAULTS, **pt), c)
        for i in range(4):
            assert al[i] + margin * S[i] * (1 - 1e-9) <= l[i] + 1e-12 * S[i]
            assert l[i] <= be[i] - margin * S[i] * (1 - 1e-9) + 1e-12 * S[i]
    r = bounds["cD/cB"]
    delta = (1 + margin) * 1.0 * max(abs(r.lower), abs(r.upper))  # the design's relay for d_bar = 1
    g = VscGains(al, be, delta, tuple(c))
    sets = condition_sets(g, forms, model, box, bounds, 1.0)
    assert certify("gains", sets["gains"], box).passed is True
    assert certify("relay", sets["relay"], box).passed is True


def test_narrow_gains_fail_at_the_corner_the_dense_grid_finds():
    plant = ElasticJointPlant(DEFAULTS)
    model = linear_model(plant)
    box = {"J2": (0.45, 0.55), "Km": (1.8, 2.2)}
    c = _elastic_c()
    forms = rational_forms("elastic_joint", c)
    bounds = bound_ranges(forms, model, box)
    grid = [_l_numpy(dataclasses.replace(DEFAULTS, J2=j, Km=k), c)[0] for j in np.linspace(*box["J2"], 41)
            for k in np.linspace(*box["Km"], 41)]
    assert bounds["l_1"].lower == pytest.approx(min(grid), rel=1e-12)
    assert bounds["l_1"].upper == pytest.approx(max(grid), rel=1e-12)
    g = VscGains((40.0, -0.3, -45.0, 0.6), (45.0, -0.2, -40.0, 0.8), 0.01, tuple(c))
    check = certify("gains", condition_sets(g, forms, model, box, bounds, 0.2)["gains"], box)
    assert check.passed is False
    ev = check.certificate["evidence"]
    assert set(ev["theta"]) == set(box) and all(v in box[k] for k, v in ev["theta"].items())


def test_uncertain_ratio_falls_back_to_a_proven_enclosure():
    """With R1 uncertain, l_1 has R1^2: not multi-affine; its range is the proven enclosure, which contains every
    value of a dense sample and is within the tolerance of it."""
    plant = ElasticJointPlant(DEFAULTS)
    model = linear_model(plant)
    box = {"Km": (1.8, 2.2), "R1": (0.018, 0.022)}
    c = _elastic_c()
    bounds = bound_ranges(rational_forms("elastic_joint", c), model, box)
    b = bounds["l_1"]
    assert b.method == "enclosure" and b.form == "general"
    assert bounds["l_2"].method == "vertices"
    vals = [_l_numpy(dataclasses.replace(DEFAULTS, Km=k, R1=r), c)[0] for k in np.linspace(*box["Km"], 31)
            for r in np.linspace(*box["R1"], 31)]
    assert b.lower <= min(vals) and max(vals) <= b.upper
    assert min(vals) - b.lower <= 1e-5 * abs(min(vals)) and b.upper - max(vals) <= 1e-5 * abs(max(vals))
