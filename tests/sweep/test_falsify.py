"""The falsification search finds a failing corner planted in a box whose samples all pass.

The box ``Km in [0.1, 1]``, ``tau in [0.5, 0.95]`` of the link PID (tests/sweep/test_pass_fraction.py) is
stable except in a triangle at the corner (Km, tau) = (0.1, 0.95), about 0.5 % of its area (the closed-form
boundary ``tau < K1 (1 + Km K2) / K3``); 30 samples of seed 0 all fall outside it.
"""

from __future__ import annotations

import numpy as np

from designkit.families import synthesize
from designkit.schema.loader import parse_spec
from designkit.sweep.api import sweep
from tests.sweep.specs import link, write


def test_the_search_breaks_the_requirement_at_the_planted_corner(tmp_path):
    text = link(km=(0.1, 1.0), tau=(0.5, 0.95))
    g = synthesize(parse_spec(text).spec).gains
    K1, K2, K3 = float(g["K1"]), float(g["K2"]), float(g["K3"])
    assert K1 * (1 + 0.1 * K2) / K3 < 0.95  # the corner is unstable (Routh-Hurwitz) ...
    assert K1 * (1 + 0.14 * K2) / K3 > 0.95  # ... and the unstable region is a sliver near it
    res = sweep(write(tmp_path, text), 30, seed=0, engine="process")
    assert res.n_passed == 30
    f = res.falsification
    assert f.broken and f.requirement == "steady_state_error"
    assert f.values[1] > K1 * (1 + f.values[0] * K2) / K3  # the point it found is unstable in closed form
    assert not res.verified
    assert res.to_json()["falsification"]["breaks_a_requirement"] is True


def test_a_box_that_holds_everywhere_is_not_falsified(tmp_path):
    res = sweep(write(tmp_path, link(km=(0.5, 1.0), tau=(0.5, 0.7))), 10, seed=0, engine="process")
    assert res.n_passed == 10 and not res.falsification.broken and res.verified
    assert np.all(res.falsification.values >= [0.5, 0.5]) and np.all(res.falsification.values <= [1.0, 0.7])
