"""Why a check of the variable structure regulator failed, and what would fix it: ``(cause, fix)``.

* ``vsc_gains`` / ``vsc_gains_enclosed``: which gain does not bracket its ``l_i``, at which corner of the box, by
  how much, and the value that would do (bare, and with the design's margin);
* ``vsc_relay``: the relay below the perturbation's share of ``sigma'`` and the ``delta`` that would do;
* ``vsc_band``: the failed condition behind it, or a command held longer than the step the design chose.
"""

from __future__ import annotations

from typing import Any

from designkit.families.vsc.checks import gain_shortfalls, shortfall_sentence
from designkit.families.vsc.data import VscData
from designkit.families.vsc.measure import hold_of

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


def diagnose(result: Any, check: Any) -> tuple[str, str] | None:
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
    return None
