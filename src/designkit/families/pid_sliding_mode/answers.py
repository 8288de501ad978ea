"""What the PID/sliding-mode family says of one of its runs when a study asks
(:attr:`designkit.synthesis.family.Family.answers`) and what it predicts in closed form
(:attr:`~designkit.synthesis.family.Family.predictions`), on the link and on the elastic joint
(:mod:`~designkit.families.pid_sliding_mode.elastic`, its own data type).

* ``how``: how the relay held the sliding variable in its band in the run, and what that leaves free (on the
  elastic joint: the link hanging on the spring with its own lightly damped mode);
* ``strategy``: the law, what it measures and what its design needs;
* ``load_offset``: the static offset ``|x - xD|`` (rad) a constant load of the spec's ``simulation.perturbation``
  leaves: 0 on the link (on ``slm = 0`` the integral of the position error is held), ``w/(KR R2)`` on the elastic
  joint (the motor held at ``xD``, the spring carrying the load).
"""

from __future__ import annotations

from typing import Any

from designkit.display.numbers import fmt_number, fmt_poles
from designkit.families.pid_sliding_mode.data import ElasticSlidingData, LinkSlidingData
from designkit.families.pid_sliding_mode.spec import IN_BAND
from designkit.synthesis.knobs import Metric

__all__ = ["ANSWERS", "PREDICTIONS", "how", "load_offset", "strategy"]

def _elastic_band() -> str:
    """The elastic joint's in-band check name (:mod:`~designkit.families.pid_sliding_mode.elastic`, imported when
    asked: it extends this package's family)."""
    from designkit.families.pid_sliding_mode.elastic import BAND

    return BAND


def _check(run: Any, name: str) -> Any:
    return next((c for c in run.checks if c.name == name), None)


def how(result: Any) -> tuple[str, ...]:
    """How far the sliding variable stayed from 0 against its band (rad*s), and what the surface leaves free."""
    d = result.design
    if result.simulation is None:
        return ()
    info = d.data
    if isinstance(info, ElasticSlidingData):
        band = _check(result, _elastic_band())
        if band is None:
            return ()
        mode = info.load_mode
        return (f"It slides on the motor: |slm| stays at most {fmt_number(band.achieved, 3)} rad·s against the band "
                f"{fmt_number(info.band, 3)} rad·s ({band.status}), so the motor follows its model 1/(1 + a1 s + "
                f"a2 s²) exactly; the link hangs on the spring with its own mode ({fmt_number(mode.omega, 3)} "
                f"rad/s, damping {fmt_number(mode.zeta, 3)}), which the motor-side surface cannot damp.",)
    band = _check(result, IN_BAND)
    if not isinstance(info, LinkSlidingData) or band is None:
        return ()
    return (f"The relay holds slm = a1 x1 + a2 x2 + x3 within {fmt_number(band.achieved, 3)} rad·s of 0 "
            f"({band.status} against its band), where the response is 1/(1 + a1 s + a2 s²) whatever Km, τ and a "
            "bounded perturbation.",)


def strategy(result: Any) -> tuple[str, ...]:
    """The law, what it measures and what its design needs, with the design's poles (1/s) and relay amplitude."""
    d = result.design
    unit = d.plant.inputs[0].unit
    poles = fmt_poles(d.poles)
    info = d.data
    if isinstance(info, ElasticSlidingData):
        return (f"slm = a1 x1 + a2 x2 + z on the motor, z' = x1 − xD, u = u0 − M sign(slm) with u0 the PID on the "
                f"motor: its design needs the PID matching on the rigid approximation (poles {poles} 1/s, zero on "
                f"p3), a1 and a2 from the sliding poles, and M = {fmt_number(info.M, 4)} {unit} above the "
                "equivalent control along the sliding motions of the box's corners.",)
    if not isinstance(info, LinkSlidingData):
        return ()
    return (f"u = u0 − M sign(slm), slm = a1 x1 + a2 x2 + x3, u0 the one-link PID (poles {poles} 1/s, zero on p3): its "
            "design needs the PID matching, a1 and a2 from the sliding poles, and M above the input-equivalent "
            "perturbation of the parameter box (§5.4), certified on the box.",)


def load_offset(result: Any) -> float | None:
    """The static offset of the controlled position under the spec's constant load (module docstring), rad."""
    pert = result.loaded.spec.simulation.perturbation
    d = result.design
    if pert is None or d.plant.kind == "robot":
        return None
    if not isinstance(d.data, ElasticSlidingData):
        return 0.0
    values = pert.value if isinstance(pert.value, list | tuple) else [pert.value]
    p = d.plant.params
    return abs(max((float(v) for v in values), key=abs)) / (p.KR * p.R2)


ANSWERS = (("how", how), ("strategy", strategy))
"""The topics the family answers (:data:`designkit.synthesis.family.ANSWER_TOPICS`)."""

PREDICTIONS = (Metric("load_offset", "static offset a constant load leaves (closed form)", "rad", load_offset,
                      "0 on the link; w/(KR R2) on the elastic joint, the motor held at xD"),)
"""What the family predicts in closed form for a run."""
