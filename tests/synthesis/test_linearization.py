"""The linearization contract: what a design's closed loop means, and which checks may read it."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from designkit.families import check_rules, synthesize
from designkit.families.pid_servo import law as servo_law
from designkit.models.link import LinkPlant
from designkit.schema.loader import parse_spec
from designkit.synthesis.closed_loop import with_closed_loop, with_law
from designkit.synthesis.design import Design
from designkit.synthesis.linearization import Linearization
from designkit.verification.suite import applicable
from tests.problems import POSSPEED_YAML

PLANT = LinkPlant(Km=2.0, tau=0.5)


def test_a_switching_contract_has_no_loop_and_is_offered_no_linear_check():
    spec = parse_spec(POSSPEED_YAML).spec
    d = synthesize(spec)
    none = Linearization("none", reason="the law switches")
    bare = with_law(dataclasses.replace(d, closed_loop=None, input_loop=None, characteristic=None), d.law, none)
    assert bare.linear_law is None
    offered = applicable(bare, spec, rules=check_rules(d.kind))
    assert offered == ()  # every check of the servo reads the linear loop, none applies
    with pytest.raises(ValueError, match="no closed_loop"):
        dataclasses.replace(d, linearization=none)


def test_a_frozen_contract_linearizes_the_frozen_law():
    """freeze(values) gives the fixed-gain law: here the servo with K1 scaled by the frozen value."""
    spec = parse_spec(POSSPEED_YAML).spec
    base = synthesize(spec)

    def freeze(values):
        return servo_law(dataclasses.replace(base, gains=base.gains.replace(K1=float(base.gains["K1"]) * values[0])))

    frozen = Linearization("frozen", parameters=("k",), initial=(1.5,), freeze=freeze, reason="test")
    d = with_closed_loop(Design(kind=base.kind, plant=PLANT, gains=base.gains), base.law, [0.0, 0.0, 0.0],
                         linearization=frozen)
    # the characteristic polynomial with K1 -> 1.5 K1: tau s^3 + (1 + Km K2) s^2 + 1.5 Km K1 s + Km K3
    K1, K2, K3 = (float(base.gains[k]) for k in ("K1", "K2", "K3"))
    expected = np.roots([0.5, 1 + 2 * K2, 1.5 * 2 * K1, 2 * K3])
    assert np.allclose(np.sort_complex(d.closed_loop.poles), np.sort_complex(expected), rtol=1e-9)
    assert d.law is base.law and d.linear_law is not base.law
    assert "frozen at k = 1.5" in frozen.describe()
    with pytest.raises(ValueError, match="frozen linearization needs"):
        Linearization("frozen", parameters=("k",), initial=())
