"""The sliding-mode identifier's law (notes section 5.5): a PD servo driving the link, and the sampled identifier
running alongside it as discrete memory.

Sign convention (that of notes section 5.1, stated here because section 5.5 flips it): the link's speed equation
is ``x2' = -a x2 + b u`` with ``a = 1/tau`` (1/s) and ``b = Km/tau`` ((rad/s^2)/(N*m)), both positive.  With
``phi = (-x2, u)`` and ``theta = (a, b)`` it reads ``x2' = phi' theta``.

At each sample ``k`` (period ``Ts``), from the measured ``x2`` and the command ``u`` of that sample::

    slm   = x2h - x2                                     sliding variable of the observer (rad/s)
    sw    = -(c |x2| + d |u|) sign(slm)                  switching term (rad/s^2), held over the sample
    x2h  <- x2h + Ts (-ah x2 + bh u + sw)                observer x2h' = -ah x2 + bh u + sw (exact for the hold)
    sw_eq = sw(k-1) + (slm(k-1) - slm(k))/Ts             the last sample's equivalent switching term
    x2d   = model(k-1) + sw_eq                           mean x2' over the last sample (exact)
    xm    = (x2(k-1) + x2(k))/2                          mean speed over it (to O(Ts^2)), u(k-1) its command
    eps1  = x2d - (-ah xm + bh u(k-1))                   regression error now
    eps2  = x2d(t-D) - (-ah xm(t-D) + bh u(t-D))         the same D earlier with today's estimates
    ah   <- ah + Ts ga (-xm eps1 - xm(t-D) eps2)
    bh   <- bh + Ts gb ( u(k-1) eps1 + u(t-D) eps2)

The delayed values come from shift registers of ``N = round(D/Ts)`` samples (zeros before the first ``D``
seconds, which makes ``eps2 = 0`` there).  The recorded signals are the memory after the sample: the
estimates, ``slm``, ``eps1``, ``eps2``, the determinant ``x2(t) u(t-D) - u(t) x2(t-D)`` and ``x2d``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca

from designkit.synthesis.law import Law, LawSymbols, Memory, dynamic_law

__all__ = ["Identifier", "KIND", "RECORDED", "identifier_law"]

KIND = "sliding_mode_identification"
"""The controller kind of this family (the spec's ``controller.kind``)."""
RECORDED = ("a_hat", "b_hat", "slm", "eps1", "eps2", "det", "x2dot")
"""The recorded signals, in order."""
RECORDED_UNITS = ("1/s", "rad/(s^2*N*m)", "rad/s", "rad/s^2", "rad/s^2", "rad*N*m/s", "rad/s^2")
"""Their units."""


@dataclass(frozen=True)
class Identifier:
    """The numbers of the law (module docstring).

    Parameters
    ----------
    K1, K2 : float
        PD servo gains (N*m/rad, N*m*s/rad).
    c, d : float
        Switching gains of the observer (1/s, (rad/s^2)/(N*m)): ``c > max |ah - a|``, ``d > max |bh - b|``.
    window : float
        ``D`` (s), the distance between the two time points.
    gamma : tuple of float
        Adaptation gains ``(ga, gb)``: ``ga`` in s/rad^2, ``gb`` in 1/(s (N*m)^2).
    initial : tuple of float
        ``(ah(0), bh(0))``.
    Ts : float
        Sampling period (s).
    """

    K1: float
    K2: float
    c: float
    d: float
    window: float
    gamma: tuple[float, float]
    initial: tuple[float, float]
    Ts: float

    @property
    def samples(self) -> int:
        """``N = round(D/Ts)`` (at least 1): the delay in samples."""
        return max(1, int(round(self.window / self.Ts)))


def identifier_law(plant: Any, ident: Identifier) -> Law:
    """The PD servo with the sampled sliding-mode identifier alongside (module docstring)."""
    N = ident.samples
    Ts, ga, gb = ident.Ts, float(ident.gamma[0]), float(ident.gamma[1])
    memo: dict[int, dict[str, ca.SX]] = {}

    def parts(s: LawSymbols) -> dict[str, ca.SX]:
        key = id(s)
        if key not in memo:
            x1, x2 = s.q[0], s.qd[0]
            u = -ident.K1 * (x1 - s.qD[0]) - ident.K2 * x2
            ah, bh, x2h = (s.memory(n) for n in ("a_hat", "b_hat", "x2h"))
            px2, pu, pslm, psw, pmodel = (s.memory(n) for n in ("px2", "pu", "pslm", "psw", "pmodel"))
            slm = x2h - x2
            sw = -(ident.c * ca.fabs(x2) + ident.d * ca.fabs(u)) * ca.sign(slm)
            model = -ah * x2 + bh * u
            # the last sample's equivalent switching term and the mean x2' over it (exact for the held sample)
            sw_eq = psw + (pslm - slm) / Ts
            xdot = pmodel + sw_eq
            xm = 0.5 * (px2 + x2)  # mean speed over the last sample (to O(Ts^2))
            eps1 = xdot - (-ah * xm + bh * pu)
            x2D, uD, xdD = (s.memory(f"{n}_{N - 1}") for n in ("bx2", "bu", "bxd"))
            eps2 = xdD - (-ah * x2D + bh * uD)
            memo[key] = {
                "u": u, "x2": x2, "xm": xm, "pu": pu, "x2h": x2h + Ts * (model + sw),
                "a_hat": ah + Ts * ga * (-xm * eps1 - x2D * eps2),
                "b_hat": bh + Ts * gb * (pu * eps1 + uD * eps2),
                "px2": x2, "pslm": slm, "psw": sw, "pmodel": model,
                "slm": slm, "eps1": eps1, "eps2": eps2, "det": xm * uD - pu * x2D, "x2dot": xdot}
        return memo[key]

    def take(name: str):
        return lambda s: parts(s)[name]

    memory = [Memory("a_hat", take("a_hat"), float(ident.initial[0]), "1/s"),
              Memory("b_hat", take("b_hat"), float(ident.initial[1]), "rad/(s^2*N*m)"),
              Memory("x2h", take("x2h"), 0.0, "rad/s"),
              Memory("px2", take("px2"), 0.0, "rad/s"), Memory("pu", take("u"), 0.0, "N*m"),
              Memory("pslm", take("pslm"), 0.0, "rad/s"), Memory("psw", take("psw"), 0.0, "rad/s^2"),
              Memory("pmodel", take("pmodel"), 0.0, "rad/s^2")]
    memory += [Memory(n, take(n), 0.0, unit) for n, unit in
               zip(RECORDED[2:], RECORDED_UNITS[2:], strict=True)]
    for name, source, unit in (("bx2", "xm", "rad/s"), ("bu", "pu", "N*m"), ("bxd", "x2dot", "rad/s^2")):
        memory.append(Memory(f"{name}_0", take(source), 0.0, unit))
        memory += [Memory(f"{name}_{j}", (lambda s, n=f"{name}_{j - 1}": s.memory(n)), 0.0, unit)
                   for j in range(1, N)]
    recorded = {n: (lambda s, n=n: s.memory(n)) for n in RECORDED}
    return dynamic_law(
        KIND, plant, command=lambda s: -ident.K1 * (s.q[0] - s.qD[0]) - ident.K2 * s.qd[0], memory=memory,
        signals=recorded, signal_units=RECORDED_UNITS, sampling_period=Ts,
        sampling_period_source="controller.sampling_period", discontinuous=True,
        settings={"servo": {"K1": ident.K1, "K2": ident.K2}, "c": ident.c, "d": ident.d, "window": ident.window,
                  "gamma": list(ident.gamma), "initial": list(ident.initial), "sampling_period": Ts,
                  "delay_samples": N},
    )
