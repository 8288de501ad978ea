"""What the vsc family says of a run when a study asks, and what it predicts: figure 5.3's c4 as printed against the
designed surface, and the static offset of a constant load against the reduced system solved by hand."""

from __future__ import annotations

import numpy as np
import pytest

from designkit.families import family
from designkit.families.vsc.answers import printed_c4
from designkit.models.robots.elastic_link import elastic_link
from designkit.pipeline import run
from designkit.schema.loader import parse_spec

ROBEL_VSC = """\
name: robel-vsc
plant: {kind: elastic_joint, uncertainty: {J2: [0.45, 0.55], Km: [1.8, 2.2], KR: [180, 220]}}
controller: {kind: vsc, sliding_poles: [-8, -10, -12]}
requirements: {overshoot: 15, settling_time: 2.5, steady_state_error: 0.02}
simulation: {duration: 4.0, step: 1.0, perturbation: {value: 0.2, time: 2.5}}
"""


@pytest.fixture(scope="module")
def result():
    return run(parse_spec(ROBEL_VSC))


def test_printed_c4_is_figure_5_3_as_printed(result):
    p = elastic_link()
    p1, p2, p3 = -8.0, -10.0, -12.0
    c1 = -(p1 + p2 + p3) - 1.0 / p.tau2
    c2 = 1.0
    # figure 5.3 as printed: c4 = (J2/(KR R2^2))(p3 p1 + p3 p2 + p1 p2) - 1 - c1 J2/(c2 KR R2^2)
    printed = (p.J2 / (p.KR * p.R2**2)) * (p3 * p1 + p3 * p2 + p1 * p2) - 1 - c1 * p.J2 / (c2 * p.KR * p.R2**2)
    c = result.design.data.c
    assert printed_c4(c, p.tau2, p.KR * p.R2**2 / p.J2) == pytest.approx(printed, rel=1e-12)
    # ... and the designed c4 is the derivation's (tau2 in the last term), which places -8, -10, -12
    assert c[3] == pytest.approx(printed + c1 / (c2 * 400.0) - c1 / (p.tau2 * 400.0), rel=1e-12)
    words = " ".join(family("vsc").answer("strategy", result))
    assert "printed c4 = -0.33375" in words


def test_the_load_offset_prediction_is_the_reduced_system_at_rest(result):
    p = elastic_link()
    c = np.asarray(result.design.data.c)
    k2 = p.KR * p.R2**2 / p.J2
    _, x3 = np.linalg.solve(np.array([[c[0], c[2]], [k2, -k2]]), [0.0, -p.R2 / p.J2 * 0.2])  # x2 = x4 = 0, c x = 0
    assert family("vsc").prediction("load_offset").value(result) == pytest.approx(abs(x3), rel=1e-9)


def test_how_it_slid_names_its_own_checks(result):
    words = " ".join(family("vsc").answer("how", result))
    gains = next(c for c in result.checks if c.name == "vsc_gains")
    assert f"theorem 3, certified: {gains.status}" in words
    assert "reached the surface in" in words and "the sliding motion predicts" in words
