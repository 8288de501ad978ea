"""The MRAC simulator's experiment, re-simulated: behaviour with and without adaptation as the link, the initial
parameters, the reference model, the weighting, the gains, the amplitude and a perturbation change.

:func:`study` runs, for one pipeline result, a bounded set of re-simulations of the spec's scenario
(each a simulator of its own, :func:`~designkit.families.mrac.runs.simulate`) and returns a
:class:`Study`; it is cached per result, so the report section and the figures share it.  The budget
is at most :data:`MAX_RUNS` simulations (the gain bisection takes up to
:data:`~designkit.families.mrac.boundary.MAX_RUNS` of them); each costs what the pipeline's run costs
(a law with other gains is a new CasADi function, interpreted).
"""

from __future__ import annotations

import math
import time
import weakref
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from designkit.families.mrac.boundary import MAX_RUNS as BISECTION_RUNS
from designkit.families.mrac.boundary import (
    Boundary,
    GammaRun,
    floquet_boundary,
    frozen_signal_bound,
    gamma_boundary,
)
from designkit.families.mrac.checks import fixed_comparison
from designkit.families.mrac.data import RegressorData
from designkit.families.mrac.laws import fixed_law
from designkit.families.mrac.model import ReferenceModel, matching_parameters
from designkit.families.mrac.runs import (
    adapted,
    adaptive_variant,
    assess,
    final_link,
    matching,
    model_position,
    plant_ratio,
    rms,
    simulate,
)
from designkit.verification.suite import Context

__all__ = ["Comparison", "MAX_RUNS", "Study", "context", "study"]

MAX_RUNS = 24
"""Most simulations one study makes."""
PERTURBATION_SHARE = 0.2
"""The perturbation studied is this fraction of the run's peak command."""

_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


@dataclass(frozen=True)
class Comparison:
    """One scenario with adaptation and (when run) with the gains frozen at their initial values."""

    label: str
    rms_adaptive: float
    rms_fixed: float | None
    stable: bool
    final: tuple[float, float]
    matching: tuple[float, float]
    peak_u: float
    peak_u_fixed: float | None = None
    last_adaptive: float | None = None
    last_fixed: float | None = None
    boundary: float | None = None
    k: float | None = None
    scale: float | None = None

    @property
    def converged(self) -> bool:
        """Both parameters within 5 % of their matching values."""
        return all(math.isfinite(f) and abs(f - m) <= 0.05 * abs(m) for f, m in zip(self.final, self.matching,
                                                                                      strict=True))


@dataclass(frozen=True)
class Study:
    """Everything :func:`study` measured (module docstring)."""

    main: Comparison
    boundary: Boundary
    frozen: dict | None
    floquet: dict | None
    amplitude: tuple[float, tuple[GammaRun, ...]] | None
    plant: tuple[Comparison, ...]
    initial: tuple[Comparison, ...]
    model: tuple[Comparison, ...]
    weighting: tuple[Comparison, ...]
    gains: tuple[Comparison, ...]
    perturbation: Comparison | None
    response: dict[str, Any]
    runs: int
    seconds: float
    periodic: bool = True


def context(result: Any) -> Context:
    """The checks' context of a pipeline result."""
    return Context(result.loaded.spec, result.simulation, result.loaded.spec.numerics.solver, result.plant)


def _with_simulation(spec: Any, **changes: Any) -> Any:
    return spec.model_copy(update={"simulation": spec.simulation.model_copy(update=changes)})


def _tail(t: np.ndarray) -> np.ndarray:
    return t >= t[0] + 0.75 * (t[-1] - t[0])


class _Runner:
    """Counts the simulations of a study against :data:`MAX_RUNS`."""

    def __init__(self, result: Any) -> None:
        self.result, self.design = result, result.design
        self.spec, self.plant = result.loaded.spec, result.plant if result.plant is not None else result.design.plant
        self.count = 0

    def ok(self, n: int = 1) -> bool:
        return self.count + n <= MAX_RUNS

    def run(self, spec: Any, law: Any) -> Any:
        self.count += 1
        return simulate(spec, self.design, self.plant, law)

    def compare(self, label: str, spec: Any, *, law: Any = None, fixed: Any = "initial",
                model: ReferenceModel | None = None) -> Comparison | None:
        """``law`` (default the design's) against the frozen law ``fixed`` (``"initial"``; None: not run);
        ``model``: the reference model ``law`` follows when not the design's (for the matching values)."""
        if not self.ok(1 + (fixed is not None)):
            return None
        d = self.design
        sim = self.run(spec, law if law is not None else d.law)
        lin = d.linearization
        ym = model_position(sim)
        e = np.asarray(sim.signals["e"], dtype=float)
        link = final_link(spec, self.plant)
        tail = _tail(np.asarray(sim.time))
        rf = pf = lf = None
        if fixed is not None:
            fl = lin.freeze(lin.initial) if fixed == "initial" else fixed
            fsim = self.run(spec, fl)
            ef = ym - np.asarray(fsim.position, dtype=float)
            rf, lf = rms(ef), rms(ef[tail])
            pf = float(np.max(np.abs(fsim.u_command)))
        final = adapted(sim)[-1]
        want = matching(d, link) if model is None else matching_parameters(model.a, d.data.nominal, link)
        return Comparison(label, rms(e), rf, assess(sim, spec).stable, (float(final[0]), float(final[1])), want,
                          float(np.max(np.abs(np.nan_to_num(sim.u_command, nan=np.inf)))), pf, rms(e[tail]), lf,
                          k=plant_ratio(d, link))


def _change_time(spec: Any, duration: float) -> float:
    change = spec.simulation.plant_change
    return float(change.time) if change is not None else round(duration / 3.0, 6)


def _plant_studies(r: _Runner, duration: float) -> tuple[Comparison, ...]:
    spec, plant = r.spec, r.plant
    Km, tau = plant.parameter("Km").value, plant.parameter("tau").value
    tc = _change_time(spec, duration)
    change = spec.simulation.plant_change
    ownKm = change is not None and "Km" in change.values
    scenarios = [("Km", Km * (2.0 if not ownKm or change.values["Km"] < Km else 0.5)), ("tau", tau * 2.0)]
    out = []
    for name, value in scenarios:
        pc = _plant_change(tc, {name: value})
        label = f"{'Km' if name == 'Km' else 'τ'} {plant.parameter(name).value:g} → {value:g} at t = {tc:g} s"
        c = r.compare(label, _with_simulation(spec, plant_change=pc))
        if c is not None:
            out.append(c)
    return tuple(out)


def _plant_change(time_s: float, values: dict[str, float]) -> Any:
    from designkit.spec.sections import PlantChange

    return PlantChange(time=time_s, values=values)


def _amplitude(r: _Runner, bd: Boundary) -> tuple[float, tuple[GammaRun, ...]] | None:
    """The bracket's ends divided by 4 with the reference amplitude doubled (predicted: bounded, then not)."""
    if bd.lo is None or bd.hi is None or not r.ok(2):
        return None
    sim_spec = r.spec.simulation
    if sim_spec.trajectory is not None:
        traj = sim_spec.trajectory
        amp = traj.amplitude
        new = [2 * a for a in amp] if isinstance(amp, list | tuple) else 2 * amp
        spec = _with_simulation(r.spec, trajectory=traj.model_copy(update={"amplitude": new}))
    else:
        step = sim_spec.step
        spec = _with_simulation(r.spec, step=[2 * s for s in step] if isinstance(step, list | tuple) else 2 * step)
    runs = []
    for scale in (bd.lo / 4.0, bd.hi / 4.0):
        sim = r.run(spec, adaptive_variant(r.design, gamma_scale=scale))
        a = assess(sim, spec)
        final = adapted(sim)[-1]
        runs.append(GammaRun(scale, a.stable, rms(sim.signals["e"]), a.growth, (float(final[0]), float(final[1])),
                             a.reason))
    return 2.0, tuple(runs)


def _response(result: Any, cmp: dict[str, Any]) -> dict[str, Any]:
    """Response time and control level after the last change: the last rising edge of the reference."""
    sim = result.simulation
    t = np.asarray(sim.time, dtype=float)
    r = np.asarray(sim.reference, dtype=float)[:, 0, 0]
    ups, downs = np.flatnonzero(np.diff(r) > 0) + 1, np.flatnonzero(np.diff(r) < 0) + 1
    edges = [(int(u), int(downs[downs > u][0])) for u in ups if np.any(downs > u)]
    out: dict[str, Any] = {}
    if edges:
        k0, k1 = edges[-1]
        seg = slice(k0 - 1, k1)
        for name, y in (("model", model_position(sim)), ("adaptive", np.asarray(sim.position, dtype=float)),
                        ("fixed", cmp["position"])):
            out[f"rise_{name}"] = _rise(t[seg], y[seg], float(r[k0]))
        out["edge_at"] = float(t[k0])
    change = result.loaded.spec.simulation.plant_change
    before = t < change.time if change is not None else np.zeros(t.size, dtype=bool)
    u, uf = np.abs(np.asarray(sim.u_command, dtype=float)[:, 0]), np.abs(cmp["u"])
    out["peak_u_adaptive"] = float(np.max(np.nan_to_num(u, nan=np.inf)))
    out["peak_u_fixed"] = float(np.max(uf))
    out["peak_u_before"] = float(np.max(uf[before])) if before.any() else None
    return out


def _rise(t: np.ndarray, y: np.ndarray, target: float) -> float | None:
    """10-90 % rise time (s) of ``y`` from ``y[0]`` to ``target``, linear interpolation; None when not reached."""
    amp = target - y[0]
    if amp == 0 or not np.all(np.isfinite(y)):
        return None
    yn = (y - y[0]) / amp
    times = []
    for level in (0.1, 0.9):
        k = np.flatnonzero(yn >= level)
        if k.size == 0 or k[0] == 0:
            return None
        i = int(k[0])
        times.append(t[i - 1] + (level - yn[i - 1]) / (yn[i] - yn[i - 1]) * (t[i] - t[i - 1]))
    return float(times[1] - times[0])


def _kept(*items: Comparison | None) -> tuple[Comparison, ...]:
    return tuple(c for c in items if c is not None)


def _main_fixed(result: Any, r: _Runner) -> dict[str, np.ndarray]:
    """The fixed-gain run of the spec's scenario: from the ``adaptation_error`` check's data, else simulated."""
    check = next((c for c in result.checks if c.name == "adaptation_error" and "fixed_error" in c.data), None)
    if check is not None:
        return {"e_fixed": np.asarray(check.data["fixed_error"]), "position": np.asarray(check.data["fixed_position"]),
                "u": np.asarray(check.data["fixed_u"])}
    r.count += 1
    cmp = fixed_comparison(result.design, context(result))
    return {"e_fixed": cmp["e_fixed"], "position": np.asarray(cmp["fixed"].position, dtype=float),
            "u": np.asarray(cmp["fixed"].u_command, dtype=float)[:, 0]}


def study(result: Any) -> Study | None:
    """The re-simulated experiment of ``result`` (module docstring), cached; None without a simulation."""
    if result.simulation is None or result.design.linearization.kind != "frozen":
        return None
    if isinstance(result.design.data, RegressorData):  # the study varies the coefficient form's settings
        return None
    if result in _CACHE:
        return _CACHE[result]
    start = time.perf_counter()
    r = _Runner(result)
    d, spec, sim = r.design, r.spec, result.simulation
    duration = float(np.asarray(sim.time)[-1])
    cmp = _main_fixed(result, r)
    ea, ef = np.asarray(sim.signals["e"], dtype=float), cmp["e_fixed"]
    tail = _tail(np.asarray(sim.time))
    a0 = assess(sim, spec)
    final = adapted(sim)[-1]
    main = Comparison("the spec's scenario", rms(ea), rms(ef), a0.stable, (float(final[0]), float(final[1])),
                      matching(d, final_link(spec, r.plant)),
                      float(np.max(np.abs(np.nan_to_num(sim.u_command, nan=np.inf)))),
                      float(np.max(np.abs(cmp["u"]))), rms(ea[tail]), rms(ef[tail]))
    stab = next((c for c in result.checks if c.name == "adaptive_stability"), None)
    known = GammaRun(1.0, a0.stable, main.rms_adaptive, a0.growth, main.final, a0.reason)
    if stab is not None and "boundary" in stab.data and stab.data["boundary"].hi is not None:
        bd = stab.data["boundary"]
    else:
        bd = gamma_boundary(spec, d, r.plant, known=known, max_runs=BISECTION_RUNS)
    r.count += len(bd.runs) - 1
    frozen = frozen_signal_bound(sim, d, spec, r.plant)
    floquet = floquet_boundary(sim, d, spec, r.plant, around=frozen["scale"] if frozen else None)
    f_main = floquet["scale"] if floquet else None
    k_main = plant_ratio(d, final_link(spec, r.plant))
    main = replace(main, boundary=f_main, k=k_main)
    amplitude = _amplitude(r, bd)

    def moved(c: Comparison | None) -> Comparison | None:  # the boundary scales as 1/k (module boundary)
        return None if c is None else replace(c, boundary=f_main * k_main / c.k if f_main and c.k else None)

    plant = tuple(moved(c) for c in _plant_studies(r, duration))
    x = d.data
    half = [0.5 * v for v in x.initial]
    initial = _kept(moved(r.compare("initial parameters × 0.5", spec, law=adaptive_variant(d, initial=half),
                                    fixed=fixed_law(d.plant, half))))
    model_now = ReferenceModel(x.reference_model.a)
    faster = ReferenceModel.from_frequency(1.5 * model_now.natural_frequency, model_now.damping)
    model = _kept(r.compare(f"reference model ωn × 1.5 ({faster.natural_frequency:.3g} rad/s)", spec,
                            law=adaptive_variant(d, model=faster), model=faster))
    weighting = []
    for factor in (0.1, 10.0):
        D = np.diag([1.0, math.sqrt(factor)])
        Q = (D @ np.asarray(x.Q, dtype=float) @ D).tolist()
        c = r.compare(f"velocity weight × {factor:g}", spec, law=adaptive_variant(d, Q=Q), fixed=None)
        if c is not None:
            fq = floquet_boundary(sim, d, spec, r.plant, Q=Q, around=f_main)
            weighting.append(replace(c, boundary=fq["scale"] if fq else None))
    small = moved(r.compare("γ × 0.1", spec, law=adaptive_variant(d, gamma_scale=0.1), fixed=None))
    gains = _kept(replace(small, scale=0.1) if small is not None else None)
    perturbation = None
    if spec.simulation.perturbation is None:
        from designkit.spec.sections import Perturbation

        value = PERTURBATION_SHARE * main.peak_u_fixed
        tp = _change_time(spec, duration)
        pspec = _with_simulation(spec, plant_change=None, perturbation=Perturbation(value=value, time=tp))
        perturbation = moved(r.compare(f"perturbation ξ = {value:.3g} N·m from t = {tp:g} s (no plant change)",
                                       pspec))
    out = Study(main, bd, frozen, floquet, amplitude, _kept(*plant), initial, model, tuple(weighting), gains,
                perturbation, _response(result, cmp), r.count, time.perf_counter() - start,
                periodic=spec.simulation.trajectory is not None)
    _CACHE[result] = out
    return out
