"""``dynamic_law`` with discrete memory (:class:`~designkit.synthesis.law.Memory`) and a declared sampling period."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from designkit.models.link import LinkPlant
from designkit.synthesis.law import Law, Memory, dynamic_law

PLANT = LinkPlant(Km=2.0, tau=0.5)


def _law(**kw):
    return dynamic_law("demo", PLANT, memory=[
        Memory("y_prev", lambda s: s.q[0], 0.25, "rad"),
        Memory("count", lambda s: s.memory("count") + 1),
    ], command=lambda s: 10 * (s.qD[0] - s.memory("y_prev")) + s.memory("count"), **kw)


def test_memory_names_initial_values_units_and_update():
    law = _law(sampling_period=0.01, sampling_period_source="controller.sampling_period")
    assert law.memory_names == ("y_prev", "count") and law.initial_memory == (0.25, 0.0)
    assert law.memory_units == ("rad", "") and law.sampling_period == 0.01 and law.command_after_update
    m_next = np.asarray(law.update([0.7, 0.1], [], [0.25, 3.0], [1.0, 0, 0])).ravel()
    np.testing.assert_array_equal(m_next, [0.7, 4.0])
    # the command is a function of the memory it is given (the simulation gives it the updated one)
    assert float(law.command([0.7, 0.1], [], m_next, [1.0, 0, 0])) == pytest.approx(10 * 0.3 + 4.0)


def test_a_law_without_memory_has_no_update_to_follow_and_no_sampling_period():
    law = dynamic_law("demo", PLANT, command=lambda s: -s.q[0])
    assert law.n_memory == 0 and not law.command_after_update and law.sampling_period is None


@pytest.mark.parametrize("period", [0.0, -1.0, float("inf")])
def test_a_non_positive_or_infinite_sampling_period_is_refused(period):
    with pytest.raises(ValueError, match="sampling_period"):
        _law(sampling_period=period)


def test_memory_sizes_must_agree():
    base = _law()
    kwargs = {f: getattr(base, f) for f in ("kind", "state_names", "command", "derivative", "gate", "project",
                                            "update", "memory_names")}
    with pytest.raises(ValueError, match="initial_memory"):
        Law(**kwargs, initial_memory=(1.0, 2.0, 3.0))
    with pytest.raises(ValueError, match="memory units"):
        Law(**kwargs, memory_units=("rad",))
    assert isinstance(base.update, ca.Function)
