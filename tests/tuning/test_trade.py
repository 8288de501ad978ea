"""The trade-off along the final direction: its ends are the initial and tuned candidates, an interior point is the
geometric mean of the two pole sets (the log coordinates' midpoint), whose margins the runner's own checks give at
the nominal plant and at the box's corners; the report draws it with its caption and the JSON carries the points."""

from __future__ import annotations

import numpy as np
import pytest

import designkit as dk
from tests.tuning.specs import LINK, write

BOX = LINK.replace("tau: 0.5}", "tau: 0.5, uncertainty: {Km: [1.6, 2.4]}}")
"""The link PID over a +-20 % Km box (the nominal and two corners)."""


@pytest.fixture(scope="module")
def tuned(tmp_path_factory):
    folder = tmp_path_factory.mktemp("trade")
    return dk.tune(write(folder, BOX), out=folder / "out", budget=1.0, sweep_samples=0)


def test_the_ends_are_the_initial_and_tuned_candidates(tuned):
    t = tuned.trade
    assert list(t.steps) == [-0.25, 0.0, 0.25, 0.5, 0.75, 1.0, 1.25]
    for k in tuned.best.margins:
        assert t.margins[k][1] == pytest.approx(tuned.initial.margins[k], abs=1e-9)
        assert t.margins[k][5] == pytest.approx(tuned.best.margins[k], abs=1e-9)
    assert not any(t.failed)


def test_the_midpoint_is_the_geometric_mean_run_by_the_runner(tuned):
    """Step 0.5: each pole the geometric mean of its initial and tuned magnitudes; every requirement's margin over
    its limit (capped at 1), the smallest over the nominal plant and the corners Km = 1.6, 2.4, from the runner's
    checks on the nominal design."""
    from designkit.runner.run import run_spec
    from designkit.runner.variants import changed_spec
    from designkit.spec.plant_builder import plant_from_spec

    p0 = np.array([-4.0, -5.0, -20.0])
    p1 = np.real(np.asarray(tuned.best.values["poles"], dtype=complex))
    mid = -np.sqrt(p0 * p1)
    loaded = changed_spec(tuned.loaded, [("controller.poles", [float(p) for p in mid])])
    plant = plant_from_spec(loaded.spec.plant, None)
    limits = {"overshoot": 5.0, "settling_time": 1.5, "max_control": 40.0}
    worst = dict.fromkeys(limits, np.inf)
    for actual in (None, plant.with_params(Km=1.6), plant.with_params(Km=2.4)):
        checks = {c.name: c for c in run_spec(loaded, plant=plant, actual=actual, box=False).checks}
        for k, limit in limits.items():
            worst[k] = min(worst[k], min(1.0, checks[k].margin / limit))
    for k in limits:
        assert tuned.trade.margins[k][3] == pytest.approx(worst[k], abs=1e-6), k


def test_the_report_draws_it_and_the_json_carries_it(tuned):
    html = tuned.files["html"].read_text(encoding="utf-8")
    assert "Trade-off along the final direction" in html and html.count("<svg") == 2
    assert "(step 0) to the tuned values (step 1), extended a quarter beyond each end" in html
    data = tuned.to_json()["trade_off"]
    assert len(data["steps"]) == 7 and set(data["margins"]) == set(tuned.best.margins)
    assert data["scores"][5] == pytest.approx(min(tuned.best.margins.values()), abs=1e-9)


def test_no_direction_no_curve_and_a_refused_point_is_not_measured(tmp_path):
    from designkit.schema.loader import load_spec
    from designkit.tuning.api import prepare
    from designkit.tuning.trade import trade_off

    problem, space = prepare(load_spec(write(tmp_path, LINK)))
    assert trade_off(problem, space, space.x0, space.x0.copy()) is None
    # poles [-4, -5, -20] towards [-3, -3, -3] (the zero's modulus, fixed at -3): step 1 puts the poles on the zero
    target = np.log(np.full_like(space.x0, 3.0))
    t = trade_off(problem, space, space.x0, target, steps=(0.0, 1.0))
    assert not t.failed[0] and np.isfinite(t.scores[0])
    assert t.failed[1] and np.isnan(t.scores[1]) and all(np.isnan(m[1]) for m in t.margins.values())


def test_the_pdf_report_carries_the_same_content(tuned):
    """``<name>-tuning.pdf`` beside the HTML: its text (read back from the PDF) holds the verdict, every margin before
    and after, the tuned coordinates, the search, each point of the trade-off table, and the figures' own text."""
    from tests.report.pdf_text import pdf_text

    pdf = tuned.files["pdf"]
    assert pdf == tuned.files["html"].with_suffix(".pdf") and pdf.read_bytes().startswith(b"%PDF")
    text = " ".join(pdf_text(pdf).split())
    assert "link-tune: tuning" in text and "TUNED AND VERIFIED" in text
    for k in tuned.best.margins:
        assert f"{tuned.initial.margins[k]:.3g}" in text and f"{tuned.best.margins[k]:.3g}" in text, k
    for c, x in zip(tuned.space.coordinates, tuned.best.x, strict=True):
        assert f"{c.label} 1/s [{c.low:.4g}, {c.high:.4g}] {c.initial:.4g} {np.exp(x):.4g}" in text
    s = tuned.search
    assert f"{len(s.evaluations)} candidates, {s.simulations} simulations" in text and "Why this search" in text
    t = tuned.trade
    for i, step in enumerate(t.steps):
        assert f"{step:+.2f} " + " ".join(f"{t.margins[k][i]:.3g}" for k in t.margins) in text, step
    # no date in the PDF: the same result compiles to the same bytes
    from designkit.tuning.report import pdf_bytes

    assert pdf_bytes(tuned) == pdf.read_bytes() and b"CreationDate" not in pdf.read_bytes()
    # the figures' text is text in the PDF: the convergence figure's legend and the trade-off's axis
    for said in ("best so far", "every requirement met", "step along the line from the initial to the tuned values"):
        assert said in text, said
