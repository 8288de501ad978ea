"""Why a check of the variable structure regulator failed, and what would fix it: ``(cause, fix)``.

* ``vsc_gains`` / ``vsc_gains_enclosed``: which gain does not bracket its ``l_i``, at which corner of the box, by
  how much, and the value that would do (bare, and with the design's margin);
* ``vsc_relay``: the relay below the perturbation's share of ``sigma'`` and the ``delta`` that would do;
* ``vsc_band``: the failed condition behind it, or a command held longer than the step the design chose;
* ``vsc_chattering`` over ``requirements.max_chatter_amplitude``: the relay switches the command by its whole
  amplitude whatever the equivalent control; the boundary layer whose gain ``(delta + structure)/eps`` is half the
  smallest critical gain of the loop along ``sigma`` (nominal plant and the box's corners, held as the run holds
  the command: :func:`~designkit.verification.chatter_prediction.layer_fix`), declared as a change of the spec
  (``controller.boundary_layer``) that the diagnosis re-simulates.
"""

from __future__ import annotations

from typing import Any

from designkit.families.vsc.checks import gain_shortfalls, shortfall_sentence
from designkit.families.vsc.data import VscData
from designkit.families.vsc.measure import hold_of
from designkit.synthesis.spec_change import SpecChange

__all__ = ["diagnose"]


def _gains(result: Any) -> tuple[str, str] | None:
    info: VscData = result.design.data
    short = gain_shortfalls(result.design)
    if not short:
        return None
    cause = "; ".join(shortfall_sentence(f, info.margin) for f in short)
    fixes = []
    for f in short:
        rel, side = ("<=", "below") if f["relation"] == "<" else (">=", "above")
        fixes.append(f"{f['gain']} {rel} {f['with_margin']:.4g} (any value {side} {f['bound']:.4g} meets the "
                     f"condition)")
    return (cause + ": at those corners of the box the switching does not turn sigma' against sigma, so the "
            "sliding mode is not guaranteed for every plant of the box.",
            "Leave alpha and beta out of the spec so the design chooses them, or give " + "; ".join(fixes) + ".")


def _relay(result: Any) -> tuple[str, str]:
    info: VscData = result.design.data
    r = info.bounds["cD/cB"]
    need = info.d_bar * max(abs(r.lower), abs(r.upper))
    return (f"delta = {info.delta:.4g} is below the perturbation's share of sigma', sup|cD/cB| d_bar = "
            f"{need:.4g}: the perturbation can push sigma off the surface.",
            f"controller.relay_amplitude above {need:.4g} ({(1 + info.margin) * need:.4g} with the "
            f"{100 * info.margin:g} % margin), or leave it out so the design sizes it.")


def _band(result: Any) -> tuple[str, str] | None:
    failed = {c.name for c in result.checks if c.passed is False}
    if "vsc_gains" in failed or "vsc_gains_enclosed" in failed:
        return _gains(result)
    if "vsc_relay" in failed:
        return _relay(result)
    info: VscData = result.design.data
    hold = hold_of(result.simulation)
    if hold > info.max_step * (1 + 1e-9):
        return (f"The command is held for {hold:.4g} s (sampling period and delay), longer than the "
                f"{info.max_step:.4g} s step the design chose: one held step can move sigma beyond the band.",
                f"A sampling period plus delay of at most {info.max_step:.4g} s, or a wider "
                "controller.chattering_band.")
    return None


def _chattering(result: Any, check: Any) -> tuple[str, str, tuple[SpecChange, ...]] | None:
    """The boundary layer that removes the chatter the requirement refuses."""
    from designkit.families.vsc.chatter import box_loops, relay_amplitude
    from designkit.families.vsc.measure import measure
    from designkit.verification.chatter_prediction import layer_fix, layer_words, timing_of

    sim, limit = result.simulation, check.certificate.get("limit")
    if sim is None or limit is None or check.achieved is None:
        return None
    design = result.design
    amplitude, structure, _ = relay_amplitude(design, measure(design, sim))
    timing = timing_of(result.loaded.spec, sim)
    fix = layer_fix(box_loops(design), amplitude, timing)
    if fix is None:
        return None
    eps, k_c = fix
    unit = check.unit.replace("N*m", "N·m")
    cause = (f"The relay switches the command by its amplitude δ + Σ|h_i| mean|x̃_i| = {amplitude:.4g} {unit} "
             f"(δ = {float(design.data.delta):.4g}, the structure's share {structure:.3g}) whatever the equivalent "
             f"control: measured ±{check.achieved:.4g} {unit} against the limit {float(limit):.4g} {unit}; a "
             "sign(σ) relay cannot chatter less.")
    fix_words = (f"A boundary layer ε = {eps:.4g} rad/s (controller.boundary_layer): "
                 + layer_words(amplitude, eps, k_c, timing, "rad/s", unit,
                               "the loop along σ at the nominal plant and the box's corners") + ".")
    change = SpecChange(f"a boundary layer ε = {eps:.4g} rad/s",
                        (("controller.boundary_layer", float(f"{eps:.4g}")), ("controller.chattering_band", None)))
    return cause, fix_words, (change,)


def diagnose(result: Any, check: Any) -> tuple[str, str] | tuple[str, str, tuple[SpecChange, ...]] | None:
    """``(cause, fix)`` for a failed check of a ``vsc`` run (module docstring), or None."""
    if not isinstance(result.design.data, VscData) or check.passed is not False:
        return None
    name = check.name.split("[")[0]
    if name in ("vsc_gains", "vsc_gains_enclosed"):
        return _gains(result)
    if name == "vsc_relay":
        return _relay(result)
    if name == "vsc_band" and result.simulation is not None:
        return _band(result)
    if name == "vsc_chattering":
        return _chattering(result, check)
    return None
