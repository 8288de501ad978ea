"""A discontinuous law is held over each step: RK4 and CVODES carry it, the step respects its bound."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from designkit.errors import SpecError
from designkit.models.link import LinkPlant
from designkit.schema.loader import parse_spec
from designkit.simulation.run import build
from designkit.synthesis.closed_loop import with_law
from designkit.synthesis.design import Design, Gain, Gains
from designkit.synthesis.law import dynamic_law
from designkit.synthesis.linearization import Linearization

PLANT = LinkPlant(Km=2.0, tau=0.5)
C, M = 5.0, 4.0


def _relay_design(max_step: float = 1e-4) -> Design:
    """u = -M sign(x2 + c (x1 - xD)): a pure sliding-mode law on the link (no perturbation)."""
    law = dynamic_law("relay_test", PLANT, command=lambda s: -M * ca.sign(s.qd[0] + C * (s.q[0] - s.qD[0])),
                      signals={"s": lambda s: s.qd[0] + C * (s.q[0] - s.qD[0])}, discontinuous=True,
                      max_step=max_step, max_step_reason="the chattering band of the test")
    d = Design(kind="pid_servo", plant=PLANT, gains=Gains.of([Gain("c", C)]), poles=(-C,))
    return with_law(d, law, Linearization("none", reason="the law switches on s = 0"))


@pytest.mark.parametrize("integrator", ["rk4", "cvodes"])
def test_both_integrators_carry_the_switching_law_to_the_sliding_line(integrator):
    spec = parse_spec("name: sw\nplant: {kind: link, Km: 2, tau: 0.5}\ncontroller: {kind: pid_servo, poles: "
                      "[-4, -5, -20]}\nsimulation: {duration: 1.5, step: 0.2}\n"
                      f"numerics: {{integrator: {integrator}}}\n").spec
    res = build(spec, _relay_design()).run()
    assert res.settings["dt"] <= 1e-4 and "discontinuous law" in res.settings["evaluation"]
    assert "integrator_failure" not in res.settings and np.all(np.isfinite(res.state))
    s = np.asarray(res.signals["s"])
    # on the line s = 0 the error decays as exp(-c t): after 1.5 s, e ~ 0.2 exp(-c (1.5 - t_reach)) -> tiny
    assert abs(res.tracking_error[-1]) < 1e-3
    # held over a step of h, |ds| per step <= h (b M + |c - a| |x2|): the band after reaching
    reached = np.flatnonzero(np.abs(s) < 1e-2)[0]
    assert np.max(np.abs(s[reached + 10:])) < 1e-4 * (4.0 * M + abs(C - 2.0) * 0.2 * C) * 1.5


def test_a_user_step_above_the_laws_bound_is_refused():
    spec = parse_spec("name: sw\nplant: {kind: link, Km: 2, tau: 0.5}\ncontroller: {kind: pid_servo, poles: "
                      "[-4, -5, -20]}\nsimulation: {duration: 1.0, dt: 0.001}\n").spec
    with pytest.raises(SpecError) as info:
        build(spec, _relay_design(1e-4))
    assert info.value.path == "simulation.dt" and "the chattering band of the test" in info.value.message
