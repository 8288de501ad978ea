"""Why a decentralized PID failed, from its own joint loops (``Family.diagnoses``).

Each joint ``i`` is a PID servo designed on its simplified link ``Km_i/(s (tau_i s + 1))``; its position follows
its reference through::

    T_i(s) = Km (K1 + K3 K4) s + Km K3) / (tau s^3 + (1 + Km K2) s^2 + Km K1 s + Km K3)
           = (1 - s/z) T0(s),      z = -K3/(K1 + K3 K4),    T0(0) = 1,

``T0`` having the three designed poles and no zero.  So the step response is ``y = y0 + c y0'`` with ``y0`` the
poles' own step, ``y0'`` its derivative and ``c = -1/z`` (s): a zero at ``z < 0`` adds ``1/|z|`` times the
derivative of the poles' step.  A zero to the right of the poles (``|z|`` small) makes that derivative action
large, and with it the overshoot, even when the poles alone do not overshoot.

**Overshoot** (:func:`overshoot`): ``100 (max_t y - 1)`` %, ``y0`` and ``y0'`` computed on a fine grid by the exact
discretization of a realization of ``T0`` (:func:`designkit.simulation.linear.forced_response`).
``c -> max_t (y0 + c y0')`` is a maximum of functions affine in ``c``, hence convex: when the poles alone meet a
limit ``R`` (``c = 0``) and the design's zero does not, the zeros that meet it are exactly those left of one
``z* = -1/c*`` (:func:`zero_for`, bisection on ``c``), the zero on a real pole (which cancels it) among them when
what the other poles leave meets ``R``.  Moving the zero changes ``K4`` only, the reference feed-forward: the
closed-loop poles, the loop seen at the plant input (margins) and the rejection of the intercoupling are unchanged.

**A negative rate gain.**  ``1 + Km K2 = tau |p1 + p2 + p3|`` (the ``s^2`` coefficient), so ``K2 < 0`` when the
poles' sum is smaller than the link's own ``1/tau``: the design cancels part of the link's damping.  With the loop
gain multiplied by ``g`` the Routh conditions read ``1 + g Km K2 > 0`` and ``K1 (1 + g Km K2) > tau K3``, so the
joint loop stays stable only for ``g < (K1 - tau K3)/(-Km K2 K1)`` (:func:`upper_gain_margin`): that is what limits
such a joint's gain margin, not its overshoot.

A failing ``overshoot`` check is explained joint by joint (the loop's prediction against the simulation's
overshoot of that joint); the fix moves the zeros of the joints that overshoot, declared as changes of the spec
(:class:`~designkit.synthesis.spec_change.SpecChange`): with the family's ``design_margin`` below the limit, and on
the third pole.

**The workspace certificate** (the family's own rule): a joint's loop is stable only while ``tau < tau_crit =
K1 (1 + Km K2)/K3 = tau* S1 S2/S3`` (``S1, S2, S3`` the symmetric functions of its poles' magnitudes, ``tau*`` the
design's, :func:`pole_ratio`), so when the box holds a larger ``D_ii`` the fix asks for poles whose ``S1 S2/S3``
exceeds ``tau_hi/tau*`` (declared: the complex pair's real part moved left until the ratio has the family's
``design_margin`` above it), or for the design at the configuration where ``D_ii`` is largest (declared too: then
``tau_crit = tau_hi S1 S2/S3``, though the coupled arm is linearized there), or a box that keeps ``D_ii`` below the
critical inertia.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.display.numbers import fmt_number, quantity
from designkit.families.decentralized_pid.data import DecentralizedPidData
from designkit.synthesis.spec_change import SpecChange

__all__ = ["JointLoop", "diagnose", "joint_loops", "overshoot", "pole_ratio", "poles_step", "upper_gain_margin",
           "zero_for"]

SAMPLES = 30001
"""Grid points of the poles' step over :data:`SETTLE` time constants of the slowest pole."""
SETTLE = 15.0
"""The grid spans this many time constants ``1/min |Re p|`` (the step is within ``e^-15`` of its end)."""
BISECTIONS = 60
"""Bisection steps on ``c = -1/z`` (the bracket shrinks by ``2^-60``)."""


@dataclass(frozen=True)
class JointLoop:
    """Joint ``joint``'s loop on its simplified link, as designed.

    Parameters
    ----------
    joint : int
        1-based.
    Km : float
        Link gain, (rad/s)/(N*m) (or (m/s)/N).
    tau : float
        Link time constant (s).
    K1, K2, K3, K4 : float
        Its PID gains (N*m/rad, N*m*s/rad, N*m/(rad*s), s; N and m for a prismatic joint).
    poles : tuple of complex
        Its closed-loop poles (1/s).
    zero : float or None
        The zero of ``q_i/qD_i``, ``-K3/(K1 + K3 K4)`` (1/s); None when ``K1 + K3 K4 = 0`` (no finite zero).
    position_unit, input_unit : str
        ``rad`` or ``m``; ``N*m`` or ``N``.
    """

    joint: int
    Km: float
    tau: float
    K1: float
    K2: float
    K3: float
    K4: float
    poles: tuple[complex, ...]
    zero: float | None
    position_unit: str = "rad"
    input_unit: str = "N*m"

    @property
    def c(self) -> float:
        """``-1/z`` (s): the weight of the derivative of the poles' step (0 without a finite zero)."""
        return 0.0 if self.zero is None else -1.0 / self.zero

    @property
    def rate_unit(self) -> str:
        """The unit of ``K2``."""
        return f"{self.input_unit}*s/{self.position_unit}"


def joint_loops(design: Any) -> tuple[JointLoop, ...]:
    """The joint loops of a decentralized PID design, from its gains and simplified links."""
    plant = design.plant
    gains = {k: np.atleast_1d(np.asarray(design.gains[k], dtype=float)) for k in ("K1", "K2", "K3", "K4")}
    out = []
    for i, (link, loop) in enumerate(zip(design.data.links, design.loops, strict=True)):
        K1, K2, K3, K4 = (float(gains[k][i]) for k in ("K1", "K2", "K3", "K4"))
        lead = K1 + K3 * K4
        zero = -K3 / lead if abs(lead) > 1e-12 * (abs(K1) + abs(K3 * K4)) else None
        poles = tuple(sorted((complex(p) for p in loop.closed_loop.poles), key=lambda p: (-p.real, p.imag)))
        out.append(JointLoop(i + 1, float(link.Km), float(link.tau), K1, K2, K3, K4, poles, zero,
                             plant.states[plant.positions[i]].unit, plant.inputs[i].unit))
    return tuple(out)


def poles_step(poles: Sequence[complex], samples: int = SAMPLES) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(t, y0, y0')``: the unit step of ``T0(s) = prod(-p)/prod(s - p)`` and its derivative (1/s) on a grid of
    ``samples`` points over :data:`SETTLE` time constants of the slowest pole (exact discretization of its
    controllable realization; at least two poles, so that ``y0' = C A x``)."""
    from designkit.simulation.linear import forced_response

    p = np.asarray(poles, dtype=complex)
    den = np.real(np.poly(p))
    n = p.size
    A = np.zeros((n, n))
    A[:-1, 1:] = np.eye(n - 1)
    A[-1, :] = -den[:0:-1]
    B = np.zeros((n, 1))
    B[-1, 0] = 1.0
    C = np.zeros((1, n))
    C[0, 0] = den[-1]
    t = np.linspace(0.0, SETTLE / float(np.min(np.abs(p.real))), int(samples))
    y = forced_response(A, B, np.vstack([C, C @ A]), np.zeros((2, 1)), t, np.ones((1, t.size)))
    return t, y[0], y[1]


def overshoot(poles: Sequence[complex], zero: float | None, step: Any = None) -> float:
    """The overshoot (%) of ``(1 - s/zero) T0(s)`` (module docstring); ``step`` is :func:`poles_step` of ``poles``
    when already computed."""
    _, y0, dy0 = poles_step(poles) if step is None else step
    c = 0.0 if zero is None else -1.0 / zero
    return max(0.0, 100.0 * (float(np.max(y0 + c * dy0)) - 1.0))


def zero_for(poles: Sequence[complex], limit: float, step: Any = None) -> float | None:
    """The zero ``z*`` (1/s) right of which ``(1 - s/z) T0`` overshoots more than ``limit`` (%): every zero at or
    left of it meets the limit; ``-inf`` (no zero) is the most the poles allow, and None when even that
    overshoots more than ``limit``."""
    step = poles_step(poles) if step is None else step
    _, y0, dy0 = step

    def over(c: float) -> float:
        return 100.0 * (float(np.max(y0 + c * dy0)) - 1.0) - limit

    if over(0.0) > 0:
        return None
    lo, hi = 0.0, 1.0 / float(np.min(np.abs(np.asarray(poles, dtype=complex))))
    while over(hi) <= 0:
        lo, hi = hi, 2.0 * hi
        if hi > 1e12:  # unreachable for a step that rises (y0' > 0 somewhere): every zero meets the limit
            return 0.0
    for _ in range(BISECTIONS):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if over(mid) <= 0 else (lo, mid)
    return -1.0 / lo if lo > 0 else -math.inf


def upper_gain_margin(loop: JointLoop) -> float | None:
    """The factor ``g`` on the joint's loop gain up to which its loop stays stable (module docstring); None when
    ``K2 >= 0`` (then only ``K1 > tau K3`` bounds it from below, and no factor above 1 destabilizes it)."""
    if loop.K2 >= 0 or loop.K1 <= 0:
        return None
    return (loop.K1 - loop.tau * loop.K3) / (-loop.Km * loop.K2 * loop.K1)


def _and(words: Sequence[str]) -> str:
    return ", ".join(words[:-1]) + f" and {words[-1]}" if len(words) > 1 else words[0]


def _joints(numbers: Sequence[int]) -> str:
    return ("joint " if len(numbers) == 1 else "joints ") + _and([str(j) for j in numbers])


def _overshoots(percent: float) -> str:
    return f"overshoots {fmt_number(percent)} %" if percent > 0 else "does not overshoot"


def _poles(poles: Sequence[complex]) -> str:
    shown = [fmt_number(p).replace("+ j", "± j") for p in poles if p.imag >= -1e-12 * abs(p)]
    return _and(shown) + " 1/s"


def _safe_zero(z: float) -> float:
    """``z`` printed to four digits on its far side (further left), so that the printed value honours the bound."""
    if not math.isfinite(z):
        return z
    e = math.floor(math.log10(abs(z))) - 3
    return -float(f"{math.ceil(abs(z) / 10.0 ** e - 1e-9) * 10.0 ** e:.4g}")


def _third_pole(loop: JointLoop) -> float | None:
    real = [p.real for p in loop.poles if abs(p.imag) <= 1e-9 * abs(p)]
    return min(real) if real else None


def _zeros_spec(loops: Sequence[JointLoop], moved: dict[int, float]) -> list[float]:
    """Every joint's zero (1/s), the moved ones replaced; a joint without a finite zero keeps ``K4 = 0``'s."""
    out = []
    for lp in loops:
        z = moved.get(lp.joint, lp.zero if lp.zero is not None else -lp.K3 / lp.K1)
        out.append(float(f"{z:.6g}"))
    return out


def _simulated(result: Any) -> list[float | None]:
    from designkit.verification.time_domain import response_metrics

    req = result.loaded.spec.requirements
    band = req.settling_band if req is not None else 0.02
    m = response_metrics(result.simulation, settling_band=band)
    joints = m.per_joint or (m,)
    return [j.overshoot if j.amplitude == j.amplitude and abs(j.amplitude) > 0 else None for j in joints]


def _margin_note(result: Any, loops: Sequence[JointLoop]) -> str:
    """Why a joint with ``K2 < 0`` has a small gain margin (and that this is not the overshoot)."""
    cert = next((c.certificate for c in result.checks if c.name == "loop_margins"), None)
    measured = {row.get("input"): row for row in (cert.get("loops", ()) if hasattr(cert, "get") else ())}
    out = []
    for lp in loops:
        g = upper_gain_margin(lp)
        if g is None:
            continue
        pole_sum = sum(-p.real for p in lp.poles)
        s = (f"joint {lp.joint}'s rate gain K2 = {quantity(lp.K2, lp.rate_unit)} is negative: the poles' sum "
             f"{quantity(pole_sum, '1/s')} is below its link's own 1/τ = {quantity(1 / lp.tau, '1/s')}, so the design "
             f"cancels part of the link's damping (1 + Km K2 = {fmt_number(1 + lp.Km * lp.K2)}), and its loop stays "
             f"stable only up to {fmt_number(g)} times its gain ({fmt_number(20 * math.log10(g))} dB, where "
             "K1 (1 + g Km K2) = τ K3)")
        row = measured.get(f"u{lp.joint}")
        if row and row.get("gain_margin") is not None and row.get("phase_margin_deg") is not None:
            s += (f"; the loop-margin check measures ×{fmt_number(row['gain_margin'])} "
                  f"({fmt_number(row['gain_margin_db'])} dB) and a phase margin of "
                  f"{quantity(row['phase_margin_deg'], '°')} at u{lp.joint} on the coupled arm")
        out.append(s + ". That limits its margins, not this overshoot")
    return ". ".join(w[0].upper() + w[1:] for w in out)


def _overshoot(result: Any, check: Any) -> tuple[str, str, tuple[SpecChange, ...]] | None:
    req = result.loaded.spec.requirements
    if req is None or req.overshoot is None or result.simulation is None:
        return None
    limit = float(req.overshoot)
    loops = joint_loops(result.design)
    steps = {lp.joint: poles_step(lp.poles) for lp in loops}
    simulated = _simulated(result)
    moving = [lp for lp in loops if simulated[lp.joint - 1] is not None]
    predicted = {lp.joint: overshoot(lp.poles, lp.zero, steps[lp.joint]) for lp in moving}
    over = [lp for lp in moving if max(predicted[lp.joint], simulated[lp.joint - 1] or 0.0) > limit]
    if not over:
        return None
    causes, fixes, moved_margin, moved_pole = [], [], {}, {}
    margin = float(getattr(result.loaded.spec.controller, "design_margin", 0.0) or 0.0)
    for lp in over:
        pred, sim = predicted[lp.joint], simulated[lp.joint - 1] or 0.0
        alone = overshoot(lp.poles, None, steps[lp.joint])
        where = ("" if lp.zero is None else "right of" if lp.zero > max(p.real for p in lp.poles) else
                 "left of" if lp.zero < min(p.real for p in lp.poles) else "among")
        zero_words = ("no finite zero" if lp.zero is None else
                      f"its zero at {quantity(lp.zero, '1/s')} (K4 = {quantity(lp.K4, 's')}; the zero −K3/(K1 + K3 K4) "
                      f"of q{lp.joint}/qD{lp.joint}) lies {where} its closed-loop poles {_poles(lp.poles)}")
        text = (f"joint {lp.joint}'s loop, as designed on its simplified link, overshoots {fmt_number(pred)} % by "
                f"itself (the simulation: {fmt_number(sim)} % on joint {lp.joint}): {zero_words}")
        if lp.zero is not None:
            text += (f", so its step is the poles' own step, which {_overshoots(alone)}, plus 1/|z| = "
                     f"{quantity(lp.c, 's')} times that step's derivative: the zero's derivative action makes the "
                     "overshoot")
        excess = max(sim - pred, 0.0)
        if excess > 0.1 * limit:
            text += (f"; the intercoupling adds {fmt_number(excess)} percentage points in the simulation")
        causes.append(text)
        target = (1.0 - margin) * limit - excess
        bound = zero_for(lp.poles, limit - excess, steps[lp.joint])
        aimed = zero_for(lp.poles, target, steps[lp.joint]) if target > 0 else None
        if bound is None or aimed is None:
            fixes.append(f"no zero in the left half plane brings joint {lp.joint} within {fmt_number(limit)} %: its "
                         f"poles alone overshoot {fmt_number(alone)} %; better damped closed-loop poles are needed")
            continue
        text = (f"move the zero of joint {lp.joint} to {quantity(_safe_zero(bound), '1/s')} or further left, where its "
                f"loop overshoots {fmt_number(limit - excess)} %" if math.isfinite(bound) else
                f"remove the zero of joint {lp.joint}")
        moved_margin[lp.joint] = _safe_zero(aimed) if math.isfinite(aimed) else None
        third = _third_pole(lp)
        if third is not None and overshoot(lp.poles, third, steps[lp.joint]) <= target:
            rest = [p for p in lp.poles if abs(p - third) > 1e-9 * abs(third)]
            text += (f"; on its third pole, {quantity(third, '1/s')}, it cancels that pole and the loop's step is that "
                     f"of {_poles(rest)}, which {_overshoots(overshoot(rest, None))}")
            moved_pole[lp.joint] = third
        fixes.append(text)
    cause = "; ".join(causes)
    others = [lp for lp in moving if lp not in over]
    if others:
        cause += ". The other joints' loops overshoot " + _and([
            f"{fmt_number(predicted[lp.joint])} % (joint {lp.joint}; simulated "
            f"{fmt_number(simulated[lp.joint - 1] or 0)} %)" for lp in others])
    note = _margin_note(result, loops)
    cause = cause[0].upper() + cause[1:] + "." + (f" {note}." if note else "")
    changes: list[SpecChange] = []
    if moved_margin and all(v is not None for v in moved_margin.values()):
        names = _joints(sorted(moved_margin))
        where = ", ".join(quantity(v, "1/s") for v in moved_margin.values())
        changes.append(SpecChange(
            f"the zero of {names} at {where}, where the loop overshoots {fmt_number((1 - margin) * limit)} % (the "
            f"{fmt_number(limit)} % asked less the design margin of {fmt_number(100 * margin)} %)",
            (("controller.zero", _zeros_spec(loops, moved_margin)),)))  # type: ignore[arg-type]
    if moved_pole:
        names = _joints(sorted(moved_pole))
        where = ", ".join(quantity(v, "1/s") for v in moved_pole.values())
        changes.append(SpecChange(f"the zero of {names} on the third pole, {where}",
                                  (("controller.zero", _zeros_spec(loops, moved_pole)),)))
    fix = "; ".join(fixes)
    if changes:
        fix += (". The zero sets only K4, the reference feed-forward: the closed-loop poles, the loop margins and the "
                "rejection of the intercoupling stay as designed")
    return cause, fix[0].upper() + fix[1:] + ".", tuple(changes)


def _vector(q: Sequence[float]) -> str:
    return "[" + ", ".join(fmt_number(float(v)) for v in q) + "]"


def _workspace(result: Any, check: Any) -> tuple[str, str, tuple[SpecChange, ...]] | None:
    """The workspace certificate failed: the joint's critical inertia against the box's largest (module docstring of
    :mod:`~designkit.families.decentralized_pid.workspace_check`), and the configuration that covers it."""
    cert = check.certificate if hasattr(check.certificate, "get") else {}
    ev = cert.get("evidence") or {}
    rows = {row.get("joint"): row for row in cert.get("joints", ())}
    row = rows.get(ev.get("joint"))
    if not row or row.get("inertia_critical") is None or not row.get("tau_nominal_s"):
        return None
    i = int(ev["joint"])
    lp = joint_loops(result.design)[i - 1]
    unit = row.get("inertia_unit", "kg*m^2")
    d_star = float(row["tau_nominal_s"]) / lp.Km  # D_ii(q*) = f_i tau_i = tau_i/Km_i
    d_crit, d_hi = float(row["inertia_critical"]), float(row["inertia_range"][1])
    ratio, need = d_crit / d_star, d_hi / d_star
    q_star = result.design.data.configuration
    q_max = [float(f"{v:.4g}") if abs(v) > 1e-6 else 0.0 for v in row["q_at_max"]]
    cause = (f"joint {i}'s loop is designed at D_{i}{i}(q*) = {quantity(d_star, unit)} (q* = {_vector(q_star)}; "
             f"τ = {quantity(float(row['tau_nominal_s']), 's')}) and is stable only while τ < K1 (1 + Km K2)/K3 = "
             f"{quantity(float(row['tau_stable_s'][1]), 's')}, i.e. D_{i}{i} < {quantity(d_crit, unit)}, "
             f"{fmt_number(ratio)} times the design value (S1 S2/S3 of its poles {_poles(lp.poles)}); the workspace "
             f"reaches D_{i}{i} = {quantity(float(ev['inertia']), unit)} at q = {_vector(ev['configuration'])} "
             f"(proven at most {quantity(d_hi, unit)}), where the loop's poles reach the real part "
             f"{quantity(float(ev['spectral_abscissa']), '1/s')}")
    margin = float(getattr(result.loaded.spec.controller, "design_margin", 0.0) or 0.0)
    damped = _damped(lp.poles, need * (1.0 + margin))
    fix = (f"poles of joint {i} whose S1 S2/S3 exceeds {fmt_number(need)}"
           + (f", e.g. {_poles(damped)} (the complex pair's real part moved left to reach {fmt_number(1 + margin)} "
              "times that)" if damped else "")
           + f"; or design the joint loops at the configuration where D_{i}{i} is largest, q = {_vector(q_max)}, "
           f"where joint {i} is stable up to {fmt_number(ratio)} times that inertia; or a workspace that keeps "
           f"D_{i}{i} below {quantity(d_crit, unit)}")
    changes = []
    if damped:
        sets = [[_pole_text(p) for p in (damped if k.joint == i else k.poles)] for k in joint_loops(result.design)]
        changes.append(SpecChange(f"the poles of joint {i} at {_poles(damped)}", (("controller.poles", sets),)))
    changes.append(SpecChange(f"the joint loops designed at q = {_vector(q_max)}, where D_{i}{i} is largest",
                              (("controller.configuration", q_max),)))
    return cause[0].upper() + cause[1:] + ".", fix[0].upper() + fix[1:] + ".", tuple(changes)


def pole_ratio(poles: Sequence[complex]) -> float:
    """``S1 S2/S3`` of three poles (their elementary symmetric functions with the signs of ``(s - p)``): the factor
    by which ``tau`` may grow over its design value before the joint loop loses stability."""
    p = np.asarray(poles, dtype=complex)
    S1, S3 = -p.sum().real, -np.prod(p).real
    S2 = (p[0] * p[1] + p[0] * p[2] + p[1] * p[2]).real
    return float(S1 * S2 / S3)


def _damped(poles: Sequence[complex], target: float) -> tuple[complex, ...] | None:
    """The poles with their complex pair's real part scaled (bisection, then printed to three digits on the far
    side) so that :func:`pole_ratio` reaches ``target``; None without a complex pair."""
    if len(poles) != 3 or all(abs(p.imag) <= 1e-9 * abs(p) for p in poles):
        return None

    def moved(k: float) -> tuple[complex, ...]:
        return tuple(complex(k * p.real, p.imag) if abs(p.imag) > 1e-9 * abs(p) else p for p in poles)

    lo, hi = 1.0, 2.0
    while pole_ratio(moved(hi)) < target:
        lo, hi = hi, 2.0 * hi
        if hi > 1e6:
            return None
    for _ in range(BISECTIONS):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if pole_ratio(moved(mid)) < target else (lo, mid)
    pair = next(p for p in poles if p.imag > 1e-9 * abs(p))
    sigma = hi * pair.real
    e = math.floor(math.log10(abs(sigma))) - 2
    sigma = -math.ceil(-sigma / 10.0 ** e - 1e-9) * 10.0 ** e
    return moved(float(f"{sigma:.3g}") / pair.real)


def _pole_text(p: complex) -> Any:
    """A pole as the spec writes it: a number, or ``"a+bi"`` for a complex one."""
    if abs(p.imag) <= 1e-9 * abs(p):
        return float(f"{p.real:.6g}")
    return f"{p.real:.6g}{'+' if p.imag > 0 else '-'}{abs(p.imag):.6g}i"


def diagnose(result: Any, check: Any) -> tuple[str, str, tuple[SpecChange, ...]] | tuple[str, str] | None:
    """``(cause, fix, changes)`` for a failed ``overshoot`` check of a decentralized PID run or its failed
    ``workspace`` certificate (module docstring), else None."""
    if check.passed is not False or not isinstance(result.design.data, DecentralizedPidData) or not result.design.loops:
        return None
    if check.name == "overshoot":
        return _overshoot(result, check)
    if check.name == "workspace":
        return _workspace(result, check)
    return None
