"""The PID/sliding-mode family's design data: one type per form, and the integral states its laws declare."""

from __future__ import annotations

from pathlib import Path

import pytest

from designkit.families.pid_sliding_mode.data import ElasticSlidingData, LinkSlidingData, RobotSlidingData
from designkit.pipeline import design
from designkit.schema.loader import load_spec, parse_spec
from tests.families.pid_sliding_mode.test_elastic import SPEC as ELASTIC_SPEC

ROOT = Path(__file__).resolve().parents[3]


@pytest.mark.parametrize(("source", "kind", "integrals"), [
    ("specs/pid-sm-link.yaml", LinkSlidingData, ("x3",)),
    ("specs/hierarchy-simnog.yaml", RobotSlidingData, ("x3_1", "x3_2")),
    (ELASTIC_SPEC, ElasticSlidingData, ()),
])
def test_each_form_carries_its_data_and_declares_the_integrals_of_a_position_error(source, kind, integrals):
    """The link's ``x3`` and the robot's ``x3_i`` integrate the controlled position's error (``x3' = q - qD``);
    the elastic joint's ``z`` integrates the motor's, not the link's (a load leaves ``w/(KR R2)`` on the link), so
    it is no integral action on the controlled position."""
    loaded = parse_spec(source) if "\n" in source else load_spec(ROOT / source)
    d = design(loaded)
    assert isinstance(d.data, kind)
    assert d.law.integral_states == integrals
    assert d.data.a1 == pytest.approx(float(d.gains["a1"])) and d.data.a2 == pytest.approx(float(d.gains["a2"]))
