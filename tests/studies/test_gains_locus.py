"""The root locus over the gain study (:mod:`designkit.studies.gains.locus`) against python-control.

- at × 1 every gain's locus is the design's closed loop: python-control's ``pole()`` of
  ``design.closed_loop`` as a state-space system;
- at × 0.5 and × 2 it is the closed loop of the scaled design (the family's law rebuilt with the scaled gain,
  linearized at the operating point as the gain study does), its poles by python-control; the largest real
  part is the one the gain study's table reports for those runs;
- an interior scale, where the locus is interpolated, equals the exact linearization there;
- the figure is legible at 420 px (no text under 9 px) and its caption says what moves where.
"""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import numpy as np
import pytest

import designkit as dk
from designkit.families import family
from designkit.studies.gains.locus import HIGH, LOW, POINTS, root_locus
from designkit.synthesis.closed_loop import linearize

control = pytest.importorskip("control")

SPECS = Path(__file__).resolve().parents[2] / "specs"


@pytest.fixture(scope="module")
def scara():
    result = dk.run(dk.load_spec(SPECS / "scara-decentralized-pid.yaml"), simulate=False)
    return result, root_locus(result)


def _poles(sys_a: np.ndarray) -> np.ndarray:
    n = sys_a.shape[0]
    return np.sort_complex(np.asarray(control.ss(sys_a, np.zeros((n, 1)), np.zeros((1, n)), 0).poles()))


def _scaled_a(result, name: str, scale: float) -> np.ndarray:
    design, op = result.design, result.design.operating_point
    scaled = dataclasses.replace(design, gains=design.gains.replace(
        **{name: np.asarray(design.gains[name], dtype=float) * scale}))
    law = family(design.kind).law(scaled, result.loaded.spec.simulation.anti_windup)
    return np.asarray(linearize(result.plant, law, op["r"], z0=[*op["x"], *op["xc"]])[0].A, float)


def _same(a: np.ndarray, b: np.ndarray, rtol: float = 1e-7) -> None:
    a, b = np.sort_complex(np.asarray(a)), np.sort_complex(np.asarray(b))
    assert np.max(np.abs(a - b)) <= rtol * max(1.0, float(np.max(np.abs(b)))), (a, b)


def test_nominal_poles_are_the_design_s_closed_loop(scara):
    result, rl = scara
    assert rl is not None and [locus.name for locus in rl.loci] == list(result.design.gains)
    cl = result.design.closed_loop
    expected = np.sort_complex(np.asarray(control.ss(cl.A, cl.B, cl.C, cl.D).poles()))
    for locus in rl.loci:
        assert len(locus.scales) == POINTS and locus.scales[0] == pytest.approx(LOW) and \
            locus.scales[-1] == pytest.approx(HIGH)
        _same(locus.at(1.0), expected)


@pytest.mark.parametrize("name", ["K1", "K2", "K3"])
def test_the_ends_are_the_scaled_designs(scara, name):
    result, rl = scara
    locus = next(locus for locus in rl.loci if locus.name == name)
    _same(locus.poles[0], _poles(_scaled_a(result, name, LOW)))
    _same(locus.poles[-1], _poles(_scaled_a(result, name, HIGH)))
    # an interpolated interior scale is the exact linearization there
    k = POINTS // 4
    _same(locus.poles[k], _poles(_scaled_a(result, name, locus.scales[k])))


def test_the_gain_study_draws_the_locus_of_its_gain_knobs():
    from designkit.families import family
    from designkit.studies.core.study import StudyContext
    from designkit.studies.gains import STUDY

    result = dk.run(dk.load_spec(SPECS / "scara-decentralized-pid.yaml"))
    study = STUDY.run(StudyContext(result, family(result.design.kind), None, 60.0))
    (fig,) = study.figures
    assert fig.title == "Root locus over the gain study"
    text = " ".join(s for q in study.section.questions for s in q.sentences)
    assert "figure Root locus over the gain study" in text
    # the table's rows at x 0.5 and x 2 are the runs whose loops the locus ends on: a loop the locus shows unstable
    # is a variant that does not pass
    rl = root_locus(result, ["K1", "K2", "K3", "K4"])
    gains = [e for e in study.entries if e.parameter in {locus.name for locus in rl.loci}]
    assert {e.parameter for e in gains} == {"K1", "K2", "K3", "K4"}  # a spec setting's knob (poles) has no locus
    for entry in gains:
        locus = next(locus for locus in rl.loci if locus.name == entry.parameter)
        for r in entry.rows:
            if r.factor != 1.0 and float(np.max(locus.at(r.factor).real)) > 1e-9:
                assert r.outcome != "verified", (entry.parameter, r.factor)


def test_doubling_k2_destabilizes_the_scara_loop_in_the_locus(scara):
    _, rl = scara
    k2 = next(locus for locus in rl.loci if locus.name == "K2")
    unstable = [s for s, row in zip(k2.scales, k2.poles, strict=True) if row.real.max() >= 0]
    assert unstable and max(k2.poles[-1].real) > 0 and max(k2.at(1.0).real) < 0
    # the first unstable scale bracketed by its neighbours on the exact linearization (python-control)
    first = min(unstable)
    i = k2.scales.index(first)
    assert np.max(_poles(_scaled_a(scara[0], "K2", first)).real) >= 0
    assert np.max(_poles(_scaled_a(scara[0], "K2", k2.scales[i - 1])).real) < 0
    text = next(s for s in rl.sentences if s.startswith("Doubling K2"))
    assert "unstable from × " in text
    k4 = next(s for s in rl.sentences if "K4" in s)
    assert "moves no closed-loop pole" in k4  # K4 only places the zero: the reference path


def test_the_figure_is_legible_at_420_px_and_says_what_moves(scara):
    from designkit.studies.gains.locus_figure import root_locus_figure

    result, rl = scara
    fig = root_locus_figure(result, rl)
    width_pt = float(re.search(r'width="([\d.]+)pt"', fig.svg).group(1))
    sizes = [float(s) for s in re.findall(r"font-size[:=]\s*\"?([\d.]+)", fig.svg)]
    assert sizes and min(sizes) * 420.0 / width_pt >= 9.0
    assert "Doubling K1 moves the rightmost pole from" in fig.caption and "K4 moves no pole" in fig.caption
