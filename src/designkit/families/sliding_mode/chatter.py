"""The sliding-mode servo's chatter: predicted from the link along ``s``, measured on the run, and the boundary
layer that brings it under ``requirements.max_chatter_amplitude``.

**The loop the relay sees.**  With ``u = -psi e + v``, ``v = -M sign(s)``, the link ``x1' = x2``,
``x2' = -a x2 + b u`` (``a = 1/tau``, ``b = Km/tau``) gives, from the relay's output ``v`` (N*m) to
``s = x2 + c e`` (rad/s)::

    s = b (p + c) / (p (p + a)) v,    state (e, x2),  A = [[0, 1], [0, -a]],  B = [0, b],  C = [c, 1],

its output the error ``e`` (rad).  The structure term splits into a smooth part and a switch:
``psi e = (alpha + beta)/2 e + (alpha - beta)/2 |e| sign(s)``.  ``e`` moves at the sliding line's rate ``c``, far
slower than the chatter, so the smooth part is a slowly varying bias of the relay, like the perturbation;
together they are the equivalent control ``u_eq``, which makes the orbit asymmetric
(:mod:`designkit.verification.chatter_prediction`).  The switch adds ``(alpha - beta)|e|/2`` to the relay's
amplitude, which vanishes as ``e`` settles: the prediction takes the relay's amplitude on the measured window,
``M + (alpha - beta)/2 mean|e|`` (the loop is linear: the orbit scales with the amplitude), and the boundary layer
must also hold the structure switch's orbit as sliding starts (:func:`layer`).  The prediction is on the design's
nominal ``(Km, tau)``; the boundary layer that removes the chatter is sized on the box's corners (the smallest
critical gain).

**Measured** on the last tenth of the sliding time of the last reference segment that slides (the settled
chatter; the reaching phase and the perturbation's step are left out).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.verification.chatter_prediction import (
    ChatterMeasured,
    ChatterPredicted,
    Timing,
    layer_fix,
    predict,
    timing_of,
    words,
)
from designkit.verification.limit_cycle import Loop

__all__ = ["Chatter", "chatter", "layer", "loop_of", "structure_amplitude"]

TAIL = 10
"""The settled window is the last ``1/TAIL`` of the sliding time (at least two samples)."""


def loop_of(Km: float, tau: float, c: float) -> Loop:
    """The link along ``s`` (module docstring): ``Km`` ((rad/s)/(N*m)), ``tau`` (s), ``c`` (1/s)."""
    return Loop.of([[0.0, 1.0], [0.0, -1.0 / tau]], [0.0, Km / tau], [c, 1.0], {"output": [1.0, 0.0]})


@dataclass(frozen=True)
class Chatter:
    """The chatter of one run: the prediction, the measurement (None without a sliding window), the run's timing,
    whether the two are compared (a lag the spec states must be in the run), and the words."""

    predicted: ChatterPredicted
    measured: ChatterMeasured | None
    timing: Timing
    compared: bool
    sentence: str

    def to_dict(self) -> dict[str, Any]:
        """JSON form (Hz, rad/s, N*m)."""
        return {"predicted": self.predicted.to_dict(),
                "measured": None if self.measured is None else self.measured.to_dict(),
                "sampling_period_s": self.timing.period, "delay_s": self.timing.delay,
                "actuator_bandwidth_rad_s": self.timing.bandwidth, "compared": self.compared}


def _window(run: Any) -> tuple[int, int] | None:
    for (a, b), r in zip(reversed(run.segments), reversed(run.reach), strict=True):
        if r is not None and b - (a + r) >= 2:
            n = max(2, (b - a - r) // TAIL)
            return b - n, b
    return None


def chatter(design: Any, sim: Any, spec: Any, run: Any) -> Chatter:
    """Predicted against measured for the run ``sim`` of ``design`` (``run``: its
    :func:`~designkit.families.sliding_mode.measure.measure`)."""
    from designkit.verification.chatter_prediction import measure as measure_chatter

    km, tau = (float(design.plant.parameter(n).value) for n in ("Km", "tau"))
    c, m = float(design.gains["c"]), float(design.gains["M"])
    timing = timing_of(spec, sim)
    win = _window(run)
    meas, structure = None, 0.0
    if win is not None:
        d = run.data
        a, b = win
        meas = measure_chatter(d["time"][a:b], d["s"][a:b], d["u"][a:b])
        half = (float(design.gains["alpha"]) - float(design.gains["beta"])) / 2
        structure = half * float(np.mean(np.abs(d["e"][a:b])))
    pred = predict(loop_of(km, tau, c), m + structure, timing, "rad/s", "N·m")
    compared = timing.bandwidth is None or timing.lag_in_run
    layer_words = "" if design.data.boundary_layer is None else (
        f"; with the boundary layer ε = {design.data.boundary_layer:.4g} rad/s the relay is the gain "
        f"M/ε = {m / design.data.boundary_layer:.4g} N·m/(rad/s) inside it, which the prediction (of the relay) "
        "does not describe")
    said = (f"the relay's amplitude on the window M + (α − β)/2 mean|e| = {m:.3g} + {structure:.3g} N·m; "
            + words(pred, meas, m + structure, "rad/s", "N·m", compared))
    return Chatter(pred, meas, timing, compared, said + layer_words)


STRUCTURE_MARGIN = 1.25
"""The boundary layer is at least this many times the ``|s|`` the structure switch's orbit reaches."""


def structure_amplitude(design: Any, run: Any) -> float:
    """``(alpha - beta) |e_r| / 2`` (N*m): the relay the structure switch adds on ``s`` as the loop starts to
    slide (``|e_r|`` the largest error at reaching over the segments): ``psi e = (alpha + beta)/2 e +
    (alpha - beta)/2 |e| sign(s)``."""
    e = run.data["e"]
    reached = [abs(float(e[a + r])) for (a, _), r in zip(run.segments, run.reach, strict=True) if r is not None]
    return (float(design.gains["alpha"]) - float(design.gains["beta"])) / 2 * max(reached, default=0.0)


def layer(design: Any, sim: Any, spec: Any, run: Any) -> tuple[float, float, float] | None:
    """``(eps, K_c, s_psi)``: the boundary layer (rad/s) that removes the chatter, the smallest critical gain
    (N*m per rad/s) over the corners of the design's box, and the ``|s|`` (rad/s) the structure switch's relay
    (:func:`structure_amplitude`) reaches on its sampled orbit at the worst corner.  ``eps`` is the larger of
    the layer whose gain ``M/eps`` is half ``K_c``
    (:func:`~designkit.verification.chatter_prediction.layer_fix`: the relay's oscillation vanishes) and
    ``STRUCTURE_MARGIN s_psi`` (the structure switch, still a relay inside the layer, stays inside it)."""
    from designkit.verification.limit_cycle import sampled_orbit

    box = design.data.box
    c = float(design.gains["c"])
    loops = [loop_of(km, tau, c) for km, tau in itertools.product(box["Km"], box["tau"])]
    timing = timing_of(spec, sim)
    fix = layer_fix(loops, float(design.gains["M"]), timing)
    if fix is None:
        return None
    eps, k_c = fix
    a_psi = structure_amplitude(design, run)
    hold = timing.period if timing.period > 0 else timing.step
    s_psi = 0.0
    if a_psi > 0:
        for loop in loops:
            orbit = sampled_orbit(loop.with_lag(timing.bandwidth) if timing.bandwidth else loop, a_psi, hold,
                                  timing.delay)
            s_psi = max(s_psi, orbit.amplitude if orbit is not None else 0.0)
    return max(eps, STRUCTURE_MARGIN * s_psi), k_c, s_psi
