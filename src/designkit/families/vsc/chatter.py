"""The variable structure regulator's chatter: predicted from the plant along ``sigma``, measured on the run.

**The loop the relay sees.**  The law is one switch (package docstring): ``u = sum m_i x~_i + v`` with
``m_i = (alpha_i + beta_i)/2`` and the relay ``v = (sum h_i |x~_i| - delta) sign(sigma)``, whose amplitude is
``delta + sum |h_i| |x~_i|``, ``delta`` once the error has settled; the prediction takes it with the mean
``|x~_i|`` over the measured window (the loop is linear: the orbit scales with the amplitude).  With the
nominal ``(A, B)`` (``VscData.nominal_model``) the relay sees the linear loop ``x~' = (A + B m) x~ + B v``,
``sigma = c x~`` (sigma in rad/s: ``c`` is normalised on the driven velocity), closed by ``v = -delta sign(sigma)``: the
prediction of :mod:`designkit.verification.chatter_prediction` as the run holds the command.

**Measured** on the last tenth of the run after reaching (the settled chatter).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from designkit.verification.chatter_prediction import measure as measure_chatter
from designkit.verification.chatter_prediction import predict, timing_of, words
from designkit.verification.limit_cycle import Loop

__all__ = ["box_loops", "chatter", "loop_of", "relay_amplitude"]

TAIL = 10
"""The settled window is the last ``1/TAIL`` of the run after reaching (at least two samples)."""


def loop_of(design: Any, model: tuple[Any, Any] | None = None) -> Loop:
    """The plant ``model = (A, B)`` (default: the nominal one) along ``sigma`` with the structure's mean gains fed
    back (module docstring)."""
    info = design.data
    a, b = (np.asarray(x, float) for x in (model or info.nominal_model[:2]))
    b = b.reshape(-1)
    m = (np.asarray(info.alpha, float) + np.asarray(info.beta, float)) / 2
    return Loop.of(a + np.outer(b, m), b, np.asarray(info.c, float))


def box_loops(design: Any) -> list[Loop]:
    """:func:`loop_of` at the nominal plant and at every corner of the design's parameter box (the plant linearised
    at rest there)."""
    import itertools

    from designkit.synthesis.state_space import linear_model

    box = design.data.box
    model = linear_model(design.plant)
    names = list(box)
    corners = [dict(zip(names, v, strict=True)) for v in itertools.product(*(box[k] for k in names))]
    return [loop_of(design)] + [loop_of(design, model.at(c)[:2]) for c in corners]


def relay_amplitude(design: Any, run: Any) -> tuple[float, float, int]:
    """``(delta + structure, structure, n)``: the relay's amplitude (the input's unit) with the structure's share
    ``sum |h_i| mean|x~_i|`` over the settled window, the last ``n`` samples (module docstring); ``delta`` and 0
    without a reaching."""
    info = design.data
    delta = float(info.delta)
    if run.reach is None:
        return delta, 0.0, 0
    d = run.data
    n = max(2, (len(d["time"]) - run.reach) // TAIL)
    h = np.abs(np.asarray(info.alpha, float) - np.asarray(info.beta, float)) / 2
    structure = float(np.mean(np.abs(d["xt"][-n:]) @ h))
    return delta + structure, structure, n


def chatter(design: Any, sim: Any, spec: Any, run: Any) -> tuple[str, dict[str, Any]]:
    """The words and the certificate entry of the chatter predicted against measured (``run``: the family's
    :func:`~designkit.families.vsc.measure.measure` of ``sim``)."""
    from designkit.verification.switching import input_unit

    info = design.data
    unit = input_unit(design, 0).replace("N*m", "N·m") or "N·m"
    delta = float(info.delta)
    timing = timing_of(spec, sim)
    meas = None
    amplitude, structure, n = relay_amplitude(design, run)
    if n:
        d = run.data
        meas = measure_chatter(d["time"][-n:], d["sigma"][-n:], d["u"][-n:])
    pred = predict(loop_of(design), amplitude, timing, "rad/s", unit, "σ")
    compared = timing.bandwidth is None or timing.lag_in_run
    sentence = (f"the relay's amplitude on the window δ + Σ|h_i| mean|x̃_i| = {delta:.3g} + {structure:.3g} {unit}; "
                + words(pred, meas, amplitude, "rad/s", unit, compared, "σ"))
    if design.data.boundary_layer is not None:
        sentence += (f"; with the boundary layer ε = {design.data.boundary_layer:.4g} rad/s the relay is linear "
                     "inside it, which the prediction (of the relay) does not describe")
    return sentence, {"predicted": pred.to_dict(), "measured": None if meas is None else meas.to_dict(),
                      "sampling_period_s": timing.period, "delay_s": timing.delay,
                      "actuator_bandwidth_rad_s": timing.bandwidth, "compared": compared}
