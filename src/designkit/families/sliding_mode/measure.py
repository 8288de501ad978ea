"""What a run of the sliding-mode servo shows: reaching, the band, the sliding pole, the chattering.

Only the :class:`~designkit.simulation.result.SimulationResult` (its time, reference, states, command and the
recorded ``s``) and the design's numbers are read.  The run is cut into **segments** between jumps of the
reference (one for a step; one per switch of a square wave or a PRBS), each a reaching phase and then a sliding
one; a last segment the run ends in before it reaches the band is left out (``cut``).  Per segment:

* **reaching**: the first sample with ``|s| <= band``, where ``band`` is the band this run's hold leaves:
  ``hold sdot_max`` (``hold`` the integration step, or the sampling period, plus the delay; ``sdot_max`` over the
  box for ``|e|`` up to the larger of the design's ``e_max`` and the largest ``|e|`` seen while sliding), or the
  boundary layer ``epsilon``.  Once entered the band is invariant (package docstring), so the **invariant** is
  ``|s| <= band`` at every later sample of the segment;
* **sliding pole**: on the sliding samples (from the first sign change of ``s`` after reaching until ``s`` leaves
  the band, if it does) where ``|e|`` is above ``POLE_FLOOR band/c`` (the chattering's share of ``e' = -c e + s``
  is then below ``c/POLE_FLOOR``), the least-squares ``p = sum(e e')/sum(e^2)`` with ``e' = x2``; the line
  predicts ``p = -c``;
* **chattering**: sign changes of ``s`` per second after reaching (at most ``1/hold``: the held sign can flip
  every step), the total variation ``sum |du|`` of the command after reaching, the largest ``|s|`` after the
  first sign change (the chattering amplitude; the error it leaves is at most that over ``c``) and the
  peak-to-peak command over the last tenth of the sliding time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from designkit.families.sliding_mode.conditions import SlidingGains, sdot_bound
from designkit.families.sliding_mode.data import SlidingData

__all__ = ["POLE_FLOOR", "POLE_TOLERANCE", "SlidingRun", "json_summary", "measure"]

POLE_FLOOR = 50.0
"""The pole is fitted where ``|e| >= POLE_FLOOR band / c``: the fit is then within ``c / POLE_FLOOR`` of ``-c``."""
POLE_TOLERANCE = 0.05
"""The measured pole agrees with ``-c`` when within this fraction of ``c`` (2.5 times the fit's own bound)."""
MIN_FIT_SAMPLES = 20


@dataclass(frozen=True)
class SlidingRun:
    """The measurements of one run (module docstring); times in s, ``s`` in rad/s, ``u`` in N*m."""

    band: float
    hold: float
    design_band: float
    segments: tuple[tuple[int, int], ...]
    reach: tuple[int | None, ...]
    reaching_times: tuple[float | None, ...]
    worst_excursion: float | None
    worst_at: float | None
    pole: float | None
    fit_samples: int
    switches: int
    sliding_time: float
    switching_frequency: float | None
    total_variation: float
    amplitude: float | None
    u_ptp_tail: float | None
    e_seen: float
    cut: bool = False
    data: dict[str, Any] = field(default_factory=dict, repr=False)

    @property
    def reached(self) -> bool:
        """Every segment reached the band."""
        return all(r is not None for r in self.reach)

    @property
    def reaching_time(self) -> float | None:
        """The longest reaching time over the segments (None when one never reached)."""
        return max(self.reaching_times) if self.reached and self.reaching_times else None


def hold_of(sim: Any) -> float:
    """How long one command is held (s): the step, or the sampling period, plus the delay."""
    st = sim.settings
    hold = max(float(st["dt"]), float(st.get("sampling_period") or 0.0))
    return hold + float(st.get("delay") or 0.0)


def _segments(xd: np.ndarray) -> tuple[tuple[int, int], ...]:
    cuts = [0, *(np.flatnonzero(np.diff(xd) != 0) + 1).tolist(), xd.size]
    return tuple((a, b) for a, b in zip(cuts[:-1], cuts[1:], strict=True) if b > a)


def _first(mask: np.ndarray) -> int | None:
    idx = np.flatnonzero(mask)
    return int(idx[0]) if idx.size else None


def _sign_changes(s: np.ndarray) -> tuple[int, int | None]:
    """Number of sign changes of ``s`` (zeros skipped) and the index of the first."""
    nz = np.flatnonzero(s != 0)
    if nz.size < 2:
        return 0, None
    flips = np.flatnonzero(np.sign(s[nz[1:]]) != np.sign(s[nz[:-1]]))
    return int(flips.size), (int(nz[flips[0] + 1]) if flips.size else None)


def _band(design: Any, info: SlidingData, hold: float, e_bar: float) -> float:
    if info.boundary_layer is not None:
        return float(info.boundary_layer)
    g = SlidingGains(*(float(design.gains[k]) for k in ("alpha", "beta", "M", "c")))
    return hold * sdot_bound(g, info.xi_bar, info.box, e_bar, info.band)


def measure(design: Any, sim: Any) -> SlidingRun:
    """The measurements of ``sim``, a run of the sliding-mode ``design`` (module docstring)."""
    info = design.data
    c = float(info.c)
    t = np.asarray(sim.time, float)
    x1 = np.asarray(sim.state[:, sim.positions[0]], float)
    x2 = np.asarray(sim.state[:, sim.velocities[0]], float)
    xd = np.asarray(sim.reference[:, 0, 0], float)
    e, s, u = x1 - xd, np.asarray(sim.signals["s"], float), np.asarray(sim.u_command[:, 0], float)
    hold = hold_of(sim)
    segs = _segments(xd)
    e_bar = float(info.e_max)
    for _ in range(2):  # the band for |e| up to what the sliding phases meet
        band = _band(design, info, hold, e_bar)
        reach = [_first(np.abs(s[a:b]) <= band * (1 + 1e-9)) for a, b in segs]
        seen = max([float(np.max(np.abs(e[a + r:b]))) for (a, b), r in zip(segs, reach, strict=True)
                    if r is not None] or [0.0])
        if seen <= e_bar:
            break
        e_bar = seen
    cut = len(segs) > 1 and reach[-1] is None  # the run ended during the last segment's reaching phase
    if cut:
        segs, reach = segs[:-1], reach[:-1]
    worst, worst_at, switches, sliding, tv = None, None, 0, 0.0, 0.0
    amp, fit, tail = None, [], []
    for (a, b), r in zip(segs, reach, strict=True):
        if r is None:
            continue
        k0 = a + r
        after = np.abs(s[k0:b])
        j = int(np.argmax(after))
        if worst is None or after[j] > worst:
            worst, worst_at = float(after[j]), float(t[k0 + j])
        n_flip, first = _sign_changes(s[k0:b])
        switches += n_flip
        sliding += (b - k0) * float(sim.settings["dt"])
        tv += float(np.sum(np.abs(np.diff(u[k0:b]))))
        if first is not None:
            k1 = k0 + first
            amp = max(amp or 0.0, float(np.max(np.abs(s[k1:b]))))
            out = _first(np.abs(s[k1:b]) > band * (1 + 1e-9))  # the sliding samples: until s leaves the band
            stop = b if out is None else k1 + out
            keep = np.arange(k1, stop)[np.abs(e[k1:stop]) >= POLE_FLOOR * band / c]
            fit.extend(keep.tolist())
            n_tail = max(2, (b - k1) // 10)
            tail.append(float(np.ptp(u[b - n_tail:b])))
    fit_idx = np.array(fit, dtype=int)
    pole = (float(np.sum(e[fit_idx] * x2[fit_idx]) / np.sum(e[fit_idx] ** 2)) if fit_idx.size >= MIN_FIT_SAMPLES
            else None)
    times = tuple(None if r is None else float(t[a + r] - t[a]) for (a, _), r in zip(segs, reach, strict=True))
    return SlidingRun(
        band=band, hold=hold, design_band=float(info.band), segments=segs, reach=tuple(reach),
        reaching_times=times, worst_excursion=worst, worst_at=worst_at, pole=pole, fit_samples=int(fit_idx.size),
        switches=switches, sliding_time=sliding, switching_frequency=switches / sliding if sliding > 0 else None,
        total_variation=tv, amplitude=amp, u_ptp_tail=max(tail) if tail else None, e_seen=e_bar, cut=cut,
        data={"time": t, "e": e, "x2": x2, "s": s, "u": u, "fit": fit_idx},
    )


def _clean(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def json_summary(result: Any) -> dict[str, Any]:
    """The ``sliding_mode`` object of ``verify --json``: the law's numbers and what the run measured."""
    d = result.design
    info = d.data
    out: dict[str, Any] = {
        "sliding_function": "s = x2 + c (x1 - xD)", "c": info.c, "sliding_pole": -info.c,
        "perturbation_bound": info.xi_bar, "margin": info.margin, "box": info.box,
        "lp_objective": info.objective, "lp_weights": info.lp["weights"], "torque_rows": info.torque_rows,
        "band_target": info.band, "band_source": info.band_source, "boundary_layer": info.boundary_layer,
        "max_step": info.max_step, "sdot_max": info.sdot_max, "strip": info.strip,
        "reaching_rate": info.reaching_rate,
    }
    sim = result.simulation
    if sim is not None:
        run = measure(d, sim)
        out.update({
            "dt": float(sim.settings["dt"]), "hold": run.hold, "band_run": run.band,
            "reaching_time": run.reaching_time, "reaching_times": list(run.reaching_times),
            "max_abs_s_after_reaching": run.worst_excursion,
            "measured_pole": run.pole, "pole_relative_error": (None if run.pole is None else
                                                               abs(run.pole + info.c) / info.c),
            "switching_frequency": run.switching_frequency, "step_rate": 1.0 / run.hold,
            "chattering_amplitude": run.amplitude,
            "chattering_error_band": None if run.amplitude is None else run.amplitude / info.c,
            "total_variation_u": run.total_variation, "u_peak_to_peak_tail": run.u_ptp_tail,
        })
    return {"sliding": {k: _clean(v) for k, v in out.items()}}
