"""Why a check of the sliding-mode servo failed, and what would fix it: ``(cause, fix)`` from the run's numbers.

* a failed certificate (``sliding_existence``, ``sliding_reaching``, ``sliding_perturbation``): which condition,
  where on the box, by how much the gain falls short, and the value that would do (bare, and with the design's
  margin) -- read from the check's ``certificate["gains_needed"]``;
* ``sliding_band`` and the time-domain checks when the run leaves the sliding line: the failed condition behind it
  (the relay below the perturbation), a reference segment too short for the slow minimal-switching reaching, or a
  command held longer than the step the design chose;
* ``chattering`` over ``requirements.max_chatter_amplitude``: the relay's chatter predicted on the sampled (or
  held) link along ``s`` (:mod:`~designkit.families.sliding_mode.chatter`), and the boundary layer whose gain
  ``M/eps`` is half the loop's smallest critical gain over the box, declared as a change of the spec
  (``controller.boundary_layer``) that the diagnosis re-simulates;
* ``settling_time`` and ``steady_state_error`` while the run does slide: the reaching time plus the decay along
  the line at ``c``, and the error the chattering band leaves (``band/c``), with the ``c`` or band that would do.
"""

from __future__ import annotations

import math
from typing import Any

from designkit.families.sliding_mode.checks import shortfall_sentence
from designkit.families.sliding_mode.data import SlidingData
from designkit.families.sliding_mode.measure import measure
from designkit.synthesis.spec_change import SpecChange
from designkit.verification.chatter_prediction import timing_of

__all__ = ["diagnose"]

_CERTIFICATES = ("sliding_existence", "sliding_reaching", "sliding_perturbation")
_RUN = ("sliding_band", "overshoot", "settling_time", "rise_time", "steady_state_error", "sliding_pole")
_FIX = {
    "alpha": "leave alpha out of the spec so the design chooses it, or give alpha",
    "beta": "leave beta out of the spec so the design chooses it, or give beta",
    "M": "leave M out of the spec so the design chooses it, or give M",
}


def _failed(result: Any, name: str) -> Any:
    return next((c for c in result.checks if c.name == name and c.passed is False), None)


def _certificate(check: Any, margin: float) -> tuple[str, str] | None:
    needs = check.certificate.get("gains_needed", {})
    short = [(k, n) for k, n in needs.items() if n["shortfall"] >= 0]
    if not short:
        return None
    cause = "; ".join(shortfall_sentence(k, n, margin) for k, n in short).split("; ")
    causes = [p for p in cause if "margin" not in p]
    fixes = []
    for _, n in short:
        rel = ">=" if n["relation"] == ">" else "<="
        bare = "above" if n["relation"] == ">" else "below"
        unit = "N*m" if n["gain"] == "M" else "N*m/rad"
        fixes.append(f"{_FIX[n['gain']]} {rel} {n['with_margin']:.4g} {unit} (any value {bare} {n['bound']:.4g} "
                     f"{unit} meets the condition; {n['with_margin']:.4g} {unit} keeps the {100 * margin:g} % margin)")
    what = {"sliding_existence": "so the sliding mode does not exist on the whole line s = 0",
            "sliding_reaching": "so the alpha structure is not a focus and a trajectory can reach the origin inside "
                                "e s > 0 without sliding",
            "sliding_perturbation": "so near e = 0 the perturbation pushes s off the line and the loop settles "
                                    "where the structure gain balances it"}[check.name.split("[")[0]]
    return "; ".join(causes) + f", {what}.", "; ".join(fixes) + "."


def _lost_sliding(result: Any, run: Any) -> tuple[str, str] | None:
    """Why the run left the sliding line, when a reason is visible."""
    pert = _failed(result, "sliding_perturbation")
    info = result.design.data
    if pert is not None:
        need = pert.certificate["gains_needed"]["M_perturbation"]
        alpha = float(result.design.gains["alpha"])
        e_star = need["shortfall"] / alpha if alpha > 0 else math.nan
        return (f"The relay M = {need['value']:.4g} N*m is below the perturbation sup|xi| = {need['bound']:.4g} N*m "
                f"(sliding_perturbation failed): the run leaves the sliding line (largest |s| "
                f"{run.worst_excursion or math.nan:.4g} rad/s against the band {run.band:.4g} rad/s) and settles "
                f"near e = (sup|xi| - M)/alpha = {e_star:.3g} rad, where the structure gain balances the shortfall.",
                f"M >= {need['with_margin']:.4g} N*m (sup|xi| with the {100 * info.margin:g} % margin); any M above "
                f"{need['bound']:.4g} N*m restores the sliding mode.")
    if not run.reached:
        k = run.reach.index(None)
        a, b = run.segments[k]
        t = run.data["time"]
        box = info.box
        alpha = float(result.design.gains["alpha"])
        slow = math.sqrt(max(box["Km"][0] / box["tau"][1] * alpha, 0.0))
        c = float(info.c)
        return (f"Segment {k + 1} (from t = {float(t[a]):.4g} s, {float(t[b - 1] - t[a]):.3g} s long) never reached "
                "the band: the alpha structure turns the trajectory onto the line slowly (natural frequency "
                f"sqrt(b alpha) = {slow:.3g} rad/s at the slowest corner, alpha = {alpha:.4g} N*m/rad, the "
                "minimal-switching choice), slower still when the perturbation opposes the move.",
                f"controller.reaching_frequency (rad/s), e.g. {c:g} (the sliding pole), which raises alpha to "
                f"omega_r^2 tau/Km on the box ({c * c * box['tau'][1] / box['Km'][0]:.4g} N*m/rad), or a longer "
                "reference segment.")
    max_step = float(info.max_step)
    if run.hold > max_step * (1 + 1e-9):
        return (f"The command is held for {run.hold:.4g} s (the sampling period and the delay), longer than the "
                f"{max_step:.4g} s step the design chose for the band {info.band:.4g} rad/s: the chattering "
                f"grows with the hold to about {run.band:.4g} rad/s.",
                f"A sampling period plus delay of at most {max_step:.4g} s, or a wider controller.chattering_band "
                f"(about {info.sdot_max * run.hold:.4g} rad/s for this hold).")
    return None


def _while_sliding(result: Any, check: Any, run: Any) -> tuple[str, str] | None:
    c = float(result.design.data.c)
    req = result.loaded.spec.requirements
    if check.name == "steady_state_error" and run.amplitude is not None and req is not None:
        need = req.steady_state_error
        return (f"While sliding the error is left by the chattering: |s| up to {run.amplitude:.4g} rad/s leaves "
                f"|e| up to {run.amplitude / c:.4g} rad on the line e' = -c e + s.",
                f"controller.chattering_band <= {c * need / 2:.4g} rad/s (half of c x the required error), which "
                "halves the step; or a boundary_layer of that size.")
    if check.name == "settling_time" and run.reaching_time is not None and req is not None:
        t_r = run.reaching_time
        k0 = run.segments[0][0] + run.reach[0]
        e_r = abs(float(run.data["e"][k0]))
        band = req.settling_band * float(result.design.data.amplitude)
        decay = math.log(max(e_r / band, 1.0)) / c
        left = req.settling_time - t_r
        fix = (f"a faster sliding pole, c >= {math.log(max(e_r / band, 1.0)) / left:.4g} 1/s, if the reaching time "
               f"stays {t_r:.3g} s" if left > 0 else
               f"a faster reaching phase: the reaching time {t_r:.3g} s alone exceeds the required settling time; a "
               "larger alpha (controller.alpha) turns the alpha structure faster")
        return (f"The settling time is the reaching time {t_r:.3g} s plus the decay along the line from |e| = "
                f"{e_r:.3g} rad to the {100 * req.settling_band:g} % band at c = {c:g} 1/s, ln(|e|/band)/c = "
                f"{decay:.3g} s.", fix + ".")
    return None


def _continuous_layer(result: Any, check: Any, limit: float) -> tuple[str, str, tuple[SpecChange, ...]]:
    """A continuous switch: no finite limit cycle; the layer whose own step is the run's."""
    from designkit.display.numbers import quantity
    from designkit.families.sliding_mode import LAYER_STEPS

    info, m = result.design.data, float(result.design.gains["M"])
    dt = float(result.simulation.settings["dt"])
    eps = LAYER_STEPS * float(info.sdot_max) * dt
    cap = ""
    if info.strip is not None and eps > info.strip / 2:
        eps = info.strip / 2
        cap = f" (capped at half the strip where s s' < 0 holds, {eps:.4g} rad/s)"
    req = result.loaded.spec.requirements
    need = None if req is None else req.steady_state_error
    if need is not None and info.xi_bar > 0:
        # inside the layer |s| -> eps xi/M and |e| -> eps xi/(M c): half the required error at most
        most = 0.5 * float(info.c) * m * float(need) / float(info.xi_bar)
        if eps > most:
            eps = most
            cap = (f" (narrowed so that the error the layer leaves, ε sup|ξ|/(M c), is half the required "
                   f"{float(need):g} rad; its step is then ε/(10 ṡ_max) = {eps / (LAYER_STEPS * info.sdot_max):.3g} s)")
    cause = (f"The continuous-time relay M = {quantity(m, 'N*m')} has no finite limit cycle: held over the integration "
             f"step {dt:.3g} s, it switches the command by ±{quantity(check.achieved, 'N*m')} against "
             f"{quantity(limit, 'N*m')}, a chatter the step sets.")
    fix = (f"A boundary layer ε = {eps:.4g} rad/s (controller.boundary_layer){cap}: at most the layer whose own step "
           f"ε/(10 ṡ_max) is the run's {dt:.3g} s (ṡ_max = {float(info.sdot_max):.4g} rad/s²), which resolves its "
           f"linear gain M/ε = {m / eps:.4g} N·m/(rad/s), so the command settles to the equivalent control.")
    change = SpecChange(f"a boundary layer ε = {eps:.4g} rad/s",
                        (("controller.boundary_layer", float(f"{eps:.4g}")), ("controller.chattering_band", None)))
    return cause, fix, (change,)


def _chattering(result: Any, check: Any) -> tuple[str, str, tuple[SpecChange, ...]] | None:
    """The boundary layer that removes the chatter the requirement refuses."""
    from designkit.display.numbers import quantity
    from designkit.families.sliding_mode.chatter import STRUCTURE_MARGIN, layer

    design, sim, spec = result.design, result.simulation, result.loaded.spec
    limit = check.certificate.get("limit")
    if limit is None or sim is None:
        return None
    timing = timing_of(spec, sim)
    if timing.period == 0 and timing.delay == 0 and timing.bandwidth is None:
        return _continuous_layer(result, check, float(limit))
    found = layer(design, sim, spec, measure(design, sim))
    if found is None:
        return None
    eps, k_c, s_psi = found
    m = float(design.gains["M"])
    strip = design.data.strip
    held = sim.settings.get("sampling_period") or sim.settings["dt"]
    cap = ""
    if strip is not None and eps > strip / 2:
        cap = (f" That layer is wider than half the strip where s s' < 0 holds ({strip / 2:.4g} rad/s), which the "
               "design refuses; the widest allowed is proposed instead.")
        eps = strip / 2
    req = spec.requirements
    need = None if req is None else req.steady_state_error
    info = design.data
    if need is not None and info.xi_bar > 0 and eps * info.xi_bar / (m * info.c) > float(need):
        cap += (f" That layer leaves an error ε sup|ξ|/(M c) = {eps * info.xi_bar / (m * info.c):.3g} rad, above the "
                f"required {float(need):g} rad: with this hold no layer meets both; a shorter sampling period lowers "
                "the critical gain's bound on ε.")
    measured = check.achieved
    cause = (f"The relay M = {quantity(m, 'N*m')} switches the command by ±{quantity(m, 'N*m')} whatever the "
             f"equivalent control (measured ±{quantity(measured, 'N*m') if measured is not None else 'n/a'}, "
             f"against {quantity(limit, 'N*m')}): a sign(s) relay cannot chatter less than M, held over "
             f"{held:.3g} s.")
    fix = (f"A boundary layer ε = {eps:.4g} rad/s (controller.boundary_layer): inside the layer the relay is the "
           f"linear gain M/ε = {m / eps:.4g} N·m/(rad/s), half the smallest critical gain {k_c:.4g} N·m/(rad/s) "
           f"of the held loop over the box's corners, so the predicted oscillation vanishes and the command settles "
           f"to the equivalent control; and at least {STRUCTURE_MARGIN:g} times the |s| = {s_psi:.4g} rad/s that the "
           f"structure switch (a relay of (α − β)|e|/2 on s as sliding starts) reaches on its held orbit, so that "
           f"it stays inside the layer.{cap}")
    change = SpecChange(f"a boundary layer ε = {eps:.4g} rad/s",
                        (("controller.boundary_layer", float(f"{eps:.4g}")), ("controller.chattering_band", None)))
    return cause, fix, (change,)


def diagnose(result: Any, check: Any) -> tuple[str, str] | tuple[str, str, tuple[SpecChange, ...]] | None:
    """``(cause, fix)`` for a failed check of a sliding-mode run (module docstring), or None."""
    if not isinstance(result.design.data, SlidingData) or check.passed is not False:
        return None
    base = check.name.split("[")[0]
    if base in _CERTIFICATES:
        return _certificate(check, float(result.design.data.margin))
    if base == "chattering":
        return _chattering(result, check)
    if base not in _RUN or result.simulation is None:
        return None
    run = measure(result.design, result.simulation)
    band = _failed(result, "sliding_band")
    if band is not None or base == "sliding_band":
        return _lost_sliding(result, run)
    return _while_sliding(result, check, run)
