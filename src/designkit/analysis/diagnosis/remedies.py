"""The fixes a diagnosis proposes, written as changed specs: :class:`Remedy` values (key path -> new value).

The owners of a failing check (an element's module, a family, a check's rule) state their fixes as
sentences with their numbers (``"Reduce the relay hysteresis to 4.394 N·m or less"``, ``"Raise K1 by a
factor 5.21 or more"``).  An owner may declare, with its sentence, the changes of the spec that realize it
(:class:`~designkit.synthesis.spec_change.SpecChange`): those are that sentence's remedies
(:func:`declared_remedies`), and the sentence is not read.  Otherwise :func:`propose` turns each sentence it
recognizes (:data:`RECOGNIZERS`, one regular expression and one builder per kind of fix) into one or more
:class:`Remedy` values, each a concrete change of the spec that :mod:`~designkit.analysis.diagnosis.resimulate`
runs again.  A number read from a sentence is taken at the end of the interval its printed digits round from,
on the side the sentence asks for (:func:`printed_bound`: "at least 8.619" is 8.6195, "4.394 or less" is
4.3935), so that the changed spec honours the sentence whatever the digits left out.  A sentence no
recognizer reads is left as it is and is not numbered as a fix.

The "slower poles" fix is computed here: every closed-loop pole (and the zero) of the design scaled by
the one factor ``c < 1`` at which the ideal linear loop's peak command is just under :data:`HEADROOM` times
the actuator limit (:func:`slower_poles`) (the loop then does not saturate, so the simulation is the
linear one).
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from designkit.display.numbers import fmt_number, quantity, unit
from designkit.spec.fields import parse_pole

__all__ = ["HEADROOM", "RECOGNIZERS", "Remedy", "declared_remedies", "printed_bound", "propose", "round_down",
           "round_up", "snippet"]

HEADROOM = 0.9
"""The slower-poles fix aims the ideal linear loop's peak command at this fraction of the actuator limit."""
ACCEPT = 0.97
"""The slower-poles search stops once the peak command is within this fraction of its target (and below it)."""
SIZING = 1.1
"""The actuator-sizing fix gives the actuator this times the ideal linear loop's peak command."""

CANCELLATION = 1e-3
"""A zero the design placed on a pole is written this much (relatively) beyond it in a fix: the spec refuses
a given zero equal to a pole; the residue of the nearly cancelled pole is of this order."""

_NUM = r"(\d+(?:\.\d+)?(?:e[-+]?\d+)?)"


@dataclass(frozen=True)
class Remedy:
    """A fix as a change of the spec.

    Parameters
    ----------
    title : str
        The fix in words, with its numbers and units.
    changes : tuple of (str, object)
        Spec key paths (``"simulation.nonlinearity.hysteresis"``) and their new values; ``None`` removes the key.
    source : str
        The diagnosis' sentence this remedy realizes.
    requirement : bool
        The remedy changes a requirement (or the actuator) rather than the controller: said in the report.
    kind : str
        Which recognizer built it (its builder's name, e.g. ``"_raise_k1"``).
    """

    title: str
    changes: tuple[tuple[str, Any], ...]
    source: str
    requirement: bool = False
    kind: str = ""


def _digits(x: float, digits: int, up: bool) -> float:
    if x == 0 or not math.isfinite(x):
        return x
    e = math.floor(math.log10(abs(x))) - digits + 1
    q = 10.0 ** e
    v = (math.ceil if up else math.floor)(x / q - (1e-9 if up else -1e-9)) * q
    return float(f"{v:.{digits}g}")


def round_up(x: float, digits: int = 4) -> float:
    """``x`` rounded up to ``digits`` significant digits (``round_up(8.6187) == 8.619``)."""
    return _digits(x, digits, True)


def round_down(x: float, digits: int = 4) -> float:
    """``x`` rounded down to ``digits`` significant digits (``round_down(4.3948) == 4.394``)."""
    return _digits(x, digits, False)


def printed_bound(text: str, up: bool) -> float:
    """The end of the interval a printed number rounds from: ``"5.21"`` stands for [5.205, 5.215), so a sentence
    asking for "5.21 or more" is honoured by 5.215 (``up``) and one asking for "4.394 or less" by 4.3935.

    Examples
    --------
    >>> printed_bound("5.21", True), printed_bound("4.394", False), printed_bound("1.6e+05", True)
    (5.215, 4.3935, 165000.0)
    """
    mantissa = text.lower().split("e")[0]
    exponent = int(text.lower().split("e")[1]) if "e" in text.lower() else 0
    decimals = len(mantissa.split(".")[1]) if "." in mantissa else 0
    half = 0.5 * 10.0 ** (exponent - decimals)
    return float(f"{float(text) + (half if up else -half):.12g}")


def _spec_dict(result: Any) -> dict[str, Any]:
    import yaml

    data = yaml.safe_load(result.loaded.text)
    return data if isinstance(data, dict) else {}


def _get(data: dict[str, Any], path: str) -> Any:
    node: Any = data
    for key in path.split("."):
        if not isinstance(node, dict) or key not in node:
            return None
        node = node[key]
    return node


def _limit_changes(data: dict[str, Any], value: float) -> tuple[tuple[str, Any], ...]:
    """The actuator limit, and the ``max_control`` requirement when it is below it."""
    changes: list[tuple[str, Any]] = []
    if _get(data, "simulation.nonlinearity.kind") == "saturation":
        changes.append(("simulation.nonlinearity.limit", value))
    cap = _get(data, "requirements.max_control")
    if isinstance(cap, int | float) and cap < value:
        changes.append(("requirements.max_control", value))
    return tuple(changes)


def _actuator_limit(m: re.Match[str], result: Any, data: dict[str, Any], text: str) -> list[Remedy]:
    value = printed_bound(m.group(1), True)
    changes = _limit_changes(data, value)
    return [Remedy(f"an actuator limit of {quantity(value, 'N*m')}, the design unchanged", changes, text, True)] \
        if changes else []


def _settling(m: re.Match[str], result: Any, data: dict[str, Any], text: str) -> list[Remedy]:
    value = printed_bound(m.group(1), True)
    return [Remedy(f"a settling-time requirement of {quantity(value, 's')}",
                   (("requirements.settling_time", value),), text, True)]


def _pole_text(p: complex) -> Any:
    re_, im = float(f"{p.real:.4g}"), float(f"{abs(p.imag):.4g}") if p.imag else 0.0
    if not im:
        return re_
    # the spec's complex-pole syntax (spec.fields.parse_pole reads i as j); j would read as a Python literal
    return f"{re_:g}{'+' if p.imag > 0 else '-'}{im:g}i"


def _scaled_poles(result: Any, c: float) -> tuple[tuple[str, Any], ...]:
    """``controller.poles`` (and ``controller.zero`` when the design has one) scaled by ``c``."""
    design = result.design
    changes: list[tuple[str, Any]] = [("controller.poles", [_pole_text(c * complex(p)) for p in design.poles])]
    fields = getattr(type(result.loaded.spec.controller), "model_fields", {})
    if "zero" in fields and design.zeros:
        zero = float(f"{c * complex(design.zeros[0]).real:.4g}")
        if any(abs(parse_pole(q) - zero) <= 1e-9 * (1 + abs(zero)) for q in changes[0][1]):
            zero = float(f"{zero * (1 + CANCELLATION):.4g}")  # the spec refuses a zero on a pole: just beyond it
        changes.append(("controller.zero", zero))
    return tuple(changes)


def _linear_peak(result: Any, changes: Sequence[tuple[str, Any]]) -> float | None:
    """Peak |u| of the ideal linear response of the spec changed by ``changes`` (None: not available)."""
    from types import SimpleNamespace

    from designkit.analysis.diagnosis.comparison import _linear_run
    from designkit.families import synthesize
    from designkit.runner.variants import changed_spec

    try:
        loaded = changed_spec(result.loaded, changes)
        design = synthesize(loaded.spec, result.plant)
    except Exception:  # noqa: BLE001 -- a scale the design refuses: not a candidate
        return None
    run = _linear_run(SimpleNamespace(simulation=result.simulation, design=design, plant=result.plant))
    if run is None:
        return None
    u = np.asarray(run.u_command, float)
    return float(np.max(np.abs(u))) if u.size and np.all(np.isfinite(u)) else None


def slower_poles(result: Any, limit: float, iterations: int = 12) -> tuple[float, tuple[tuple[str, Any], ...]] | None:
    """The pole scale ``c`` (0 < c < 1) at which the ideal linear loop commands between :data:`ACCEPT` and 1 times
    :data:`HEADROOM` ``limit``, and the spec changes; None without poles in the design or a linear response.

    ``ln peak`` is nearly affine in ``ln c`` (the peak command of a step grows as a power of the loop's speed), so
    the root of ``ln peak(c) - ln target`` is bracketed from a power-law guess and refined by regula falsi with
    the Illinois modification (a bracket always kept, at most ``iterations`` designs).
    """
    design = result.design
    if not design.poles or not hasattr(result.loaded.spec.controller, "poles") or \
            any(isinstance(p, list | tuple) for p in design.poles):
        return None
    target = math.log(HEADROOM * limit)

    def f(x: float) -> float:
        peak = _linear_peak(result, _scaled_poles(result, math.exp(x)))
        return math.inf if peak is None or peak <= 0 else math.log(peak) - target

    hi, f_hi = 0.0, f(0.0)
    if not math.isfinite(f_hi) or f_hi <= 0:
        return None
    x = -f_hi / 2.0  # a peak growing as c^2 (the step's acceleration)
    lo, f_lo = x, f(x)
    while f_lo > 0 or not math.isfinite(f_lo):
        if lo < math.log(1e-4):
            return None
        hi, f_hi = (lo, f_lo) if math.isfinite(f_lo) else (hi, f_hi)
        lo, f_lo = lo - 2.0, f(lo - 2.0)
    side = 0
    for _ in range(iterations):
        if math.log(ACCEPT) <= f_lo <= 0.0:
            break
        x = lo - f_lo * (hi - lo) / (f_hi - f_lo)
        fx = f(x)
        if not math.isfinite(fx) or fx > 0:
            hi, f_hi = x, fx if math.isfinite(fx) else f_hi
            f_lo = f_lo / 2.0 if side == -1 else f_lo
            side = -1
        else:
            lo, f_lo = x, fx
            f_hi = f_hi / 2.0 if side == 1 else f_hi
            side = 1
    c = math.exp(lo)
    return c, _scaled_poles(result, c)


def _demand(m: re.Match[str], result: Any, data: dict[str, Any], text: str) -> list[Remedy]:
    peak, limit = float(m.group(1)), float(m.group(3))
    out = []
    found = slower_poles(result, limit)
    if found is not None:
        c, changes = found
        out.append(Remedy(f"every closed-loop pole and the zero scaled by {fmt_number(c, 3)}, so that the ideal "
                          f"linear loop commands {fmt_number(100 * HEADROOM, 2)} % of the "
                          f"{quantity(limit, 'N*m')} limit", changes, text))
    sized = round_up(SIZING * peak, 2)
    changes = _limit_changes(data, sized)
    if changes:
        out.append(Remedy(f"an actuator limit of {quantity(sized, 'N*m')} ({fmt_number(SIZING, 2)} times the "
                          f"{quantity(peak, 'N*m')} the linear loop commands), the design unchanged", changes, text,
                          True))
    return out


def _hysteresis(m: re.Match[str], result: Any, data: dict[str, Any], text: str) -> list[Remedy]:
    value = printed_bound(m.group(1), False)
    return [Remedy(f"a relay hysteresis of {quantity(value, 'N*m')}", (("simulation.nonlinearity.hysteresis", value),),
                   text, True)]


def _proportional(m: re.Match[str], result: Any, data: dict[str, Any], text: str) -> list[Remedy]:
    return [Remedy("a proportional actuator (no relay)", (("simulation.nonlinearity", None),), text, True)]


def _gain_factor(factor: float, data: dict[str, Any]) -> tuple[tuple[str, Any], ...] | None:
    """K1 times ``factor`` at the same damping: the natural frequency (or the error poles) times its square root."""
    root = math.sqrt(factor)
    wn = _get(data, "controller.natural_frequency")
    if isinstance(wn, int | float):
        return (("controller.natural_frequency", round_up(wn * root)),)
    if isinstance(wn, list):
        return (("controller.natural_frequency", [round_up(float(w) * root) for w in wn]),)
    return None


def _raise_k1(m: re.Match[str], result: Any, data: dict[str, Any], text: str) -> list[Remedy]:
    factor = printed_bound(m.group(1), True)
    changes = _gain_factor(factor, data)
    if changes is None:
        return []
    return [Remedy(f"K1 times {fmt_number(factor, 4)} and K2 times its square root (the natural frequency times "
                   f"{fmt_number(math.sqrt(factor), 4)}, the damping unchanged)", changes, text)]


def _flow(text: str) -> Any:
    import yaml

    return yaml.safe_load(text)


def _model_payload(m: re.Match[str], result: Any, data: dict[str, Any], text: str) -> list[Remedy]:
    payload = _flow(m.group(1))
    out = [Remedy(f"the controller's model given the plant's payload ({unit(m.group(1))})",
                  (("controller.model.payload", payload),), text)]
    more = re.search(r"K1 must then still grow by a factor " + _NUM, text)
    extra = _gain_factor(printed_bound(more.group(1), True), data) if more else None
    if more and extra:
        out.append(Remedy(f"the controller's model given the plant's payload and K1 times "
                          f"{fmt_number(printed_bound(more.group(1), True), 4)} "
                          "(the natural frequency times its square root)",
                          (("controller.model.payload", payload), *extra), text))
    return out


def _damped(m: re.Match[str], result: Any, data: dict[str, Any], text: str) -> list[Remedy]:
    value = _flow(m.group(1))
    return [Remedy(f"damped least squares ({unit(m.group(1))})", (("controller.damped_least_squares", value),), text)]


def _alpha(m: re.Match[str], result: Any, data: dict[str, Any], text: str) -> list[Remedy]:
    value = float(m.group(1))
    return [Remedy(f"a learning gain α = {fmt_number(value)} 1/s⁴", (("controller.learning.alpha", value),), text)]


def _switching(m: re.Match[str], result: Any, data: dict[str, Any], text: str) -> list[Remedy]:
    value = printed_bound(m.group(1), True)
    return [Remedy(f"a switching gain M = {quantity(value, 'N*m')}", (("controller.M", value),), text)]


def _gamma(m: re.Match[str], result: Any, data: dict[str, Any], text: str) -> list[Remedy]:
    value = printed_bound(m.group(1), False)
    return [Remedy(f"an adaptation gain γ = {fmt_number(value)}", (("controller.gamma", value),), text)]


def _forgetting(m: re.Match[str], result: Any, data: dict[str, Any], text: str) -> list[Remedy]:
    value = float(m.group(1))
    return [Remedy(f"a forgetting factor λ = {fmt_number(value)}", (("controller.forgetting", value),), text)]


def _left_out(m: re.Match[str], result: Any, data: dict[str, Any], text: str) -> list[Remedy]:
    names = [n for n in (m.group(1), m.group(2)) if n]
    present = [n for n in names if isinstance(data.get("controller"), dict) and n in data["controller"]]
    if not present:
        return []
    return [Remedy(f"{' and '.join(present)} left out of the spec, for the design to choose",
                   tuple((f"controller.{n}", None) for n in present), text)]


Builder = Callable[[re.Match[str], Any, dict[str, Any], str], list[Remedy]]

RECOGNIZERS: tuple[tuple[re.Pattern[str], Builder], ...] = (
    (re.compile(r"actuator limit of at least " + _NUM + " N·m"), _actuator_limit),
    (re.compile(r"or a settling time of " + _NUM + " s or more"), _settling),
    (re.compile(r"commands " + _NUM + r" N·m for this \w+, " + _NUM + " times the " + _NUM + r" N·m limit: slower"),
     _demand),
    (re.compile(r"[Rr]educe the relay hysteresis to " + _NUM + " N·m or less"), _hysteresis),
    (re.compile(r"drive the link with a proportional actuator"), _proportional),
    (re.compile(r"Raise K1 by a factor " + _NUM + " or more"), _raise_k1),
    (re.compile(r"\(controller\.model\.payload: (\{[^}]*\})\)"), _model_payload),
    (re.compile(r"\(controller\.damped_least_squares: (\{[^}]*\})\)"), _damped),
    (re.compile(r"controller\.learning\.alpha in \(0, [^)]*\)[^,]*, e\.g\. " + _NUM), _alpha),
    (re.compile(r"\bM >= " + _NUM + " N·m"), _switching),
    (re.compile(r"Use γ = " + _NUM + r"(?:, " + _NUM + r")? or less"), _gamma),
    (re.compile(r"controller\.forgetting \(e\.g\. " + _NUM + r"\)"), _forgetting),
    (re.compile(r"with λ = " + _NUM + r" \(re-simulated\)"), _forgetting),
    (re.compile(r"Leave (\w+)(?: and (\w+))? out of the spec"), _left_out),
)
"""One regular expression per kind of fix sentence (read on the typeset text: ``N·m``) and the builder of its
remedies."""


def declared_remedies(sentence: str, changes: Sequence[Any]) -> tuple[Remedy, ...]:
    """The changes of the spec an owner declared for its fix ``sentence``
    (:class:`~designkit.synthesis.spec_change.SpecChange`) as remedies; each its own kind (``"declared: "`` and its
    title), so that every one is re-run."""
    return tuple(Remedy(c.title, tuple(c.changes), sentence, c.requirement, kind=f"declared: {c.title}")
                 for c in changes)


def propose(result: Any, sentences: Sequence[str], declared: Mapping[str, Sequence[Any]] | None = None
            ) -> tuple[tuple[str, tuple[Remedy, ...]], ...]:
    """Every fix sentence with the remedies it reads as (an empty tuple: not recognized), in order.

    Parameters
    ----------
    result : designkit.pipeline.PipelineResult
        The run the sentences diagnose (its spec text, design, plant and simulation).
    sentences : sequence of str
        The distinct fix sentences of the findings.
    declared : mapping of str to sequence of SpecChange, optional
        Sentences whose owner declared their changes of the spec: those changes are the remedies
        (:func:`declared_remedies`), and :data:`RECOGNIZERS` do not read the sentence.
    """
    data = _spec_dict(result)
    owned = {unit(k): v for k, v in (declared or {}).items()}
    out = []
    for sentence in sentences:
        text = unit(sentence)
        if owned.get(text):
            out.append((sentence, declared_remedies(sentence, owned[text])))
            continue
        remedies: list[Remedy] = []
        for pattern, build in RECOGNIZERS:
            m = pattern.search(text)
            if m is not None:
                try:
                    remedies += [replace(r, kind=build.__name__) for r in build(m, result, data, sentence)]
                except Exception:  # noqa: BLE001, S112 -- a remedy that cannot be built is simply not offered
                    continue
        out.append((sentence, tuple(remedies)))
    return tuple(out)


def snippet(changes: Sequence[tuple[str, Any]]) -> str:
    """The changed fields as one line of YAML (flow style): ``{simulation: {nonlinearity: {hysteresis: 4.39}}}``."""
    import yaml

    nested: dict[str, Any] = {}
    for path, value in changes:
        node = nested
        keys = path.split(".")
        for key in keys[:-1]:
            node = node.setdefault(key, {})
        node[keys[-1]] = value
    return yaml.safe_dump(nested, default_flow_style=True, sort_keys=False, width=10_000, allow_unicode=True).strip()
