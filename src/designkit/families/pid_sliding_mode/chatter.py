"""The PID/sliding-mode link's chatter: predicted from the sliding variable's transfer function, measured on the
run.

**The loop the relay sees** (package docstring): ``slm' = p3 slm + g (du + xi)`` with ``g = a2 Km/tau`` (the
nominal ``g``, ``LinkSlidingData.g_nominal``), so from the relay's output ``du`` (N*m) to ``slm`` (rad*s) the
loop is ``g/(p - p3)``, closed by ``du = -M sign(slm)``; the perturbation is a bias of the relay (the equivalent
control).  The prediction is :mod:`designkit.verification.chatter_prediction`'s, as the run holds the command.

**Measured** on the last tenth of the run after reaching (the settled chatter), on the whole command
``u = u0 + du``.
"""

from __future__ import annotations

from typing import Any

from designkit.verification.chatter_prediction import measure as measure_chatter
from designkit.verification.chatter_prediction import predict, timing_of, words
from designkit.verification.limit_cycle import Loop

__all__ = ["chatter", "loop_of"]

TAIL = 10
"""The settled window is the last ``1/TAIL`` of the run after reaching (at least two samples)."""


def loop_of(p3: float, g: float) -> Loop:
    """``slm = g/(p - p3) du`` (``p3`` in 1/s, ``g`` in rad*s per s per N*m)."""
    return Loop.of([[p3]], [g], [1.0])


def chatter(design: Any, sim: Any, spec: Any, run: Any) -> tuple[str, dict[str, Any]]:
    """The words and the certificate entry of the chatter predicted against measured (``run``: the family's
    :func:`~designkit.families.pid_sliding_mode.measure.measure` of ``sim``)."""
    info = design.data
    m = float(info.M)
    timing = timing_of(spec, sim)
    pred = predict(loop_of(float(info.p3), float(info.g_nominal)), m, timing, "rad·s", "N·m", "slm")
    meas = None
    if run.reach is not None:
        d = run.data
        n = max(2, (len(d["time"]) - run.reach) // TAIL)
        meas = measure_chatter(d["time"][-n:], d["slm"][-n:], d["u"][-n:])
    compared = timing.bandwidth is None or timing.lag_in_run
    sentence = words(pred, meas, m, "rad·s", "N·m", compared, "slm")
    if info.epsilon is not None:
        sentence += (f"; with the boundary layer ε = {info.epsilon:.4g} rad·s the relay is not the ideal one inside "
                     "it, which the prediction (of the relay) does not describe")
    return sentence, {"predicted": pred.to_dict(), "measured": None if meas is None else meas.to_dict(),
                      "sampling_period_s": timing.period, "delay_s": timing.delay,
                      "actuator_bandwidth_rad_s": timing.bandwidth, "compared": compared}
