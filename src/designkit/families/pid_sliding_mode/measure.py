"""What a run of the PID/sliding-mode controller shows, read from the run and the design's numbers only.

* **reaching**: the first sample with ``|slm| <= band`` (``band``: the switching band ``hold sdot_max``, the
  layer ``epsilon`` with ``sat``, or ``epsilon + hold sdot_max`` with the dead zone); the **invariant** is
  ``|slm| <= band`` at every later sample;
* **precision**: ``|x1 - x1_ideal|`` after reaching, ``x1_ideal`` the plant-independent sliding motion (the
  reference through ``1/(1 + a1 s + a2 s^2)``, or the trajectory itself when tracking), against its bound
  ``||s/N||_1 max|slm|`` (``x1 - x1_ideal = (s/N(s)) slm`` from rest) and against ``||s/N||_1 band``;
* **chattering**: sign changes of ``slm`` per second after reaching, the total variation ``sum |du|`` of the
  command and of its switching part over the same time, and the switching part's peak-to-peak value over the
  last tenth of the run.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from designkit.families.pid_sliding_mode.data import LinkSlidingData
from designkit.families.pid_sliding_mode.spec import KIND
from designkit.families.pid_sliding_mode.surface import ideal_motion, surface

__all__ = ["Run", "json_summary", "measure"]


@dataclass(frozen=True)
class Run:
    """The measurements of one run (module docstring); times in s, ``slm`` in rad*s, ``u`` in N*m."""

    band: float
    hold: float
    reach: int | None
    reaching_time: float | None
    worst: float | None
    worst_at: float | None
    slm_max: float
    deviation: float | None
    deviation_bound: float
    deviation_at_band: float
    switches: int
    sliding_time: float
    switching_frequency: float | None
    total_variation: float
    relay_variation: float
    relay_ptp_tail: float
    data: dict[str, Any] = field(default_factory=dict, repr=False)


def hold_of(sim: Any) -> float:
    """How long one command is held (s): the step, or the sampling period, plus the delay."""
    st = sim.settings
    return max(float(st["dt"]), float(st.get("sampling_period") or 0.0)) + float(st.get("delay") or 0.0)


def band_of(info: LinkSlidingData, hold: float) -> float:
    """The band ``|slm| <= band`` (rad*s) this run's hold (s) leaves (module docstring)."""
    if info.epsilon is None:
        return hold * float(info.sdot_max)
    if info.layer == "saturation":
        return float(info.epsilon)
    return float(info.epsilon) + hold * float(info.sdot_max)


def measure(design: Any, sim: Any) -> Run:
    """The measurements of ``sim``, a run of ``design`` (module docstring)."""
    info: LinkSlidingData = design.data
    sf = surface(design.poles)
    t = np.asarray(sim.time, float)
    ref = np.asarray(sim.reference[:, 0, :], float)
    x1 = np.asarray(sim.state[:, sim.positions[0]], float)
    slm = np.asarray(sim.signals["slm"], float)
    relay = np.asarray(sim.signals["du"], float)
    u = np.asarray(sim.u_command[:, 0], float)
    hold = hold_of(sim)
    band = band_of(info, hold)
    x1i = ideal_motion(sf, t, ref, info.form, start=float(x1[0]))[0]
    idx = np.flatnonzero(np.abs(slm) <= band * (1 + 1e-9))
    reach = int(idx[0]) if idx.size else None
    l1 = float(info.l1)
    slm_max = float(np.max(np.abs(slm)))
    if reach is None:
        return Run(band, hold, None, None, None, None, slm_max, None, l1 * slm_max, l1 * band, 0, 0.0, None,
                   float(np.sum(np.abs(np.diff(u)))), float(np.sum(np.abs(np.diff(relay)))), 0.0,
                   {"time": t, "slm": slm, "x1": x1, "x1_ideal": x1i, "u": u, "du": relay})
    after = np.abs(slm[reach:])
    j = int(np.argmax(after))
    dev = float(np.max(np.abs(x1[reach:] - x1i[reach:])))
    nz = slm[reach:][slm[reach:] != 0]
    switches = int(np.count_nonzero(np.sign(nz[1:]) != np.sign(nz[:-1]))) if nz.size > 1 else 0
    sliding = float(t[-1] - t[reach])
    tail = max(2, (len(t) - reach) // 10)
    return Run(
        band=band, hold=hold, reach=reach, reaching_time=float(t[reach] - t[0]), worst=float(after[j]),
        worst_at=float(t[reach + j]), slm_max=slm_max, deviation=dev, deviation_bound=l1 * slm_max,
        deviation_at_band=l1 * band, switches=switches, sliding_time=sliding,
        switching_frequency=switches / sliding if sliding > 0 else None,
        total_variation=float(np.sum(np.abs(np.diff(u[reach:])))),
        relay_variation=float(np.sum(np.abs(np.diff(relay[reach:])))),
        relay_ptp_tail=float(np.ptp(relay[-tail:])),
        data={"time": t, "slm": slm, "x1": x1, "x1_ideal": x1i, "u": u, "du": relay},
    )


def _clean(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def json_summary(result: Any) -> dict[str, Any]:
    """The family's object of ``synth --json`` / ``verify --json``: the PID gains, ``M`` with the bound
    it covers, and what the run measured."""
    d = result.design
    info: LinkSlidingData = d.data
    xb = info.perturbation
    out: dict[str, Any] = {
        "form": info.form, "sliding_variable": info.sliding_variable,
        "gains": {k: float(d.gains[k]) for k in info.pid_gains},
        "a1": info.a1, "a2": info.a2, "p3": info.p3, "zero": info.p3,
        "sliding_gain_nominal": info.g_nominal,
        "M": [info.M], "M_given": info.M_given,
        "bound": {"total": info.xi_total, "parameter_change": xb.parameter,
                  "external": xb.external, "parameter_change_on_samples": xb.sampled,
                  "worst_corner": list(xb.corner), "at_time": xb.at,
                  "box": {k: list(v) for k, v in info.box.items()}, "margin": info.margin},
        "M_over_bound": info.M / info.xi_total if info.xi_total > 0 else None,
        "epsilon": info.epsilon, "layer": info.layer if info.epsilon is not None else None,
        "max_step": info.max_step, "sdot_max": info.sdot_max, "l1_deviation_per_slm": info.l1,
    }
    sim = result.simulation
    if sim is not None and "slm" in sim.signals:
        run = measure(d, sim)
        out.update({
            "band_run": run.band, "hold": run.hold, "reaching_time": run.reaching_time,
            "max_abs_slm_after_reaching": run.worst, "max_abs_slm": run.slm_max,
            "deviation_from_sliding_motion": run.deviation, "deviation_bound": run.deviation_bound,
            "deviation_bound_at_band": run.deviation_at_band,
            "switching_frequency": run.switching_frequency, "total_variation_u": run.total_variation,
            "total_variation_relay": run.relay_variation, "relay_peak_to_peak_tail": run.relay_ptp_tail,
        })
    return {KIND: {k: _clean(v) for k, v in out.items()}}
