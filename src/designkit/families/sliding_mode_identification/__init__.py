"""Sliding-mode parameter identification of the link (notes section 5.5): the ``sliding_mode_identification`` family.

The link ``x1' = x2``, ``x2' = -a x2 + b (u + xi)`` (``a = 1/tau``, ``b = Km/tau``: the sign convention of
section 5.1; section 5.5 writes ``+a x2`` and so estimates ``-1/tau``) is driven by a fixed PD position servo
``u = -K1 (x1 - xD) - K2 x2`` following an exciting reference (a square wave or a PRBS), and a sampled
identifier runs alongside it (:mod:`~designkit.families.sliding_mode_identification.laws`): a sliding-mode
observer of ``x2`` whose switching term's equivalent value is ``x2'`` minus the model's prediction, and the
two-time-point gradient update of ``(ah, bh)``.

**Derivation** (the OCR'd lines re-derived; docs/families/sliding_mode_identification.md):
with ``slm = x2h - x2`` and ``x2h' = -ah x2 + bh u - (c |x2| + d |u|) sign(slm)``,
``slm' = (ah - a) x2 - (bh - b) u - (c |x2| + d |u|) sign(slm)``, so
``d/dt (slm^2/2) <= |slm| (|ah - a| - c) |x2| + |slm| (|bh - b| - d) |u| < 0`` when ``c > max |ah - a|`` and
``d > max |bh - b|`` (and ``(x2, u) != 0``).  With ``phi = (-x2, u)``, ``theta~ = theta - thetah``,
``eps = x2' - phi' thetah = phi' theta~``, the update ``thetah' = Gamma (phi(t) eps1 + phi(t-D) eps2)`` gives, for
``V = theta~' Gamma^-1 theta~ = (a - ah)^2/ga + (b - bh)^2/gb``,
``V' = -2 (eps1^2 + eps2^2) <= 0``, and ``V' < 0`` whenever ``theta~ != 0`` and
``det [x2(t) u(t); x2(t-D) u(t-D)] != 0`` (then ``eps1 = eps2 = 0`` forces ``theta~ = 0``).  Since ``V`` does
not increase, ``|a - ah(t)| <= sqrt(ga V(0))`` and ``|b - bh(t)| <= sqrt(gb V(0))``; with the stated bounds
``|a - ah(0)| <= ea``, ``|b - bh(0)| <= eb``, ``V(0) <= ea^2/ga + eb^2/gb``, so the observer's condition holds
along the whole run when ``c > sqrt(ga V0max)`` and ``d > sqrt(gb V0max)``; the defaults take
:data:`SWITCHING_MARGIN` times these.

**Robot form** (``plant.kind: robot``; notes section 5.5's generalisation ``x' = A phi(x, t)`` with the model
layer's regressor as ``phi``): the arm's base parameters, ``u = Wb(q, qd, qdd) beta``, identified by one observer
per joint and the two-time-point update on the torque equation
(:mod:`~designkit.families.sliding_mode_identification.arm_design`, ``arm_law``, ``arm_checks``, ``arm_report``;
docs/families/sliding_mode_identification.md, "Robot form").

**Contract.**  ``Linearization("none")``: the identifier is a sampled switching observer in discrete memory; the
servo itself is a fixed PD loop, but the family's verdict is about the identification, judged by its own checks
(:mod:`~designkit.families.sliding_mode_identification.checks`).
"""

from __future__ import annotations

import math
from typing import Any

from designkit.errors import SpecError
from designkit.families.sliding_mode_identification.data import ArmIdentifierData, LinkIdentifierData
from designkit.families.sliding_mode_identification.laws import KIND, RECORDED, Identifier, identifier_law
from designkit.families.sliding_mode_identification.spec import LINK_REFERENCES, ROBOT_REFERENCES, SmidSpec, validate
from designkit.synthesis.closed_loop import with_law
from designkit.synthesis.design import Design, Gain, Gains
from designkit.synthesis.family import Display, Family
from designkit.synthesis.knobs import Knob
from designkit.synthesis.law import Law
from designkit.synthesis.linearization import Linearization

__all__ = ["FAMILY", "KIND", "SWITCHING_MARGIN", "SmidSpec", "design", "law", "synthesize", "switching_bounds"]

MAX_WINDOW_SAMPLES = 2000
"""Longest window ``D`` in sampling periods (the shift registers' length)."""
SWITCHING_MARGIN = 1.5
"""Default c, d: this factor times the least values the stated error bounds require."""
REASON = ("the identifier is a sampled switching observer (sign of the sliding variable) with shift registers of the "
          "signals D seconds ago in discrete memory: it has no continuous linearization; its own checks judge it")


def switching_bounds(bounds: tuple[float, float], gamma: tuple[float, float]) -> tuple[float, float]:
    """The least ``(c, d)`` the stated error bounds ``(ea, eb)`` require: ``sqrt(g V0max)``, ``V0max = ea^2/ga +
    eb^2/gb`` (module docstring).

    Examples
    --------
    >>> switching_bounds((1.0, 2.0), (1.0, 4.0))
    (1.4142135623730951, 2.8284271247461903)
    """
    v0 = bounds[0] ** 2 / gamma[0] + bounds[1] ** 2 / gamma[1]
    return math.sqrt(gamma[0] * v0), math.sqrt(gamma[1] * v0)


def synthesize(spec: Any, plant: Any) -> Design:
    """The identifier a spec asks for (module docstring; on a robot,
    :func:`~designkit.families.sliding_mode_identification.arm_design.synthesize_arm`)."""
    if plant.kind == "robot":
        from designkit.families.sliding_mode_identification.arm_design import synthesize_arm

        return synthesize_arm(spec, plant)
    cs = spec.controller
    given = cs.adaptation_gains if cs.adaptation_gains is not None else [1.0, 1.0]
    gamma = (float(given[0]), float(given[1]))
    bounds = (float(cs.error_bounds.a), float(cs.error_bounds.b))
    need = switching_bounds(bounds, gamma)
    notes = []
    c = float(cs.c) if cs.c is not None else SWITCHING_MARGIN * need[0]
    d = float(cs.d) if cs.d is not None else SWITCHING_MARGIN * need[1]
    if cs.c is None or cs.d is None:
        notes.append(f"Switching gains not given: {SWITCHING_MARGIN:g} times the least the error bounds require "
                     f"(c = {c:.4g} 1/s, d = {d:.4g} rad/(s²·N·m)).")
    Ts = float(cs.sampling_period)
    if not Ts <= cs.window <= MAX_WINDOW_SAMPLES * Ts:
        raise SpecError("controller.window", f"must be between one and {MAX_WINDOW_SAMPLES} sampling periods "
                        f"({Ts:g} s to {MAX_WINDOW_SAMPLES * Ts:g} s: the signals D seconds ago are kept in shift "
                        f"registers of D/Ts samples), got {cs.window:g}")
    K1, K2 = (float(v[0]) if isinstance(v, list) else float(v) for v in (cs.servo.K1, cs.servo.K2))
    ident = Identifier(K1=K1, K2=K2, c=c, d=d, window=float(cs.window), gamma=gamma,
                       initial=(float(cs.initial_estimates[0]), float(cs.initial_estimates[1])), Ts=Ts)
    return design(plant, ident, bounds, need, notes=tuple(notes))


def design(plant: Any, ident: Identifier, bounds: tuple[float, float], need: tuple[float, float], *,
           notes: tuple[str, ...] = ()) -> Design:
    """The design of the identifier ``ident`` on ``plant`` (its law, contract ``none``)."""
    gains = Gains.of([
        Gain("K1", ident.K1, "N*m/rad", "servo proportional gain"),
        Gain("K2", ident.K2, "N*m*s/rad", "servo rate gain"),
        Gain("c", ident.c, "1/s", "observer switching gain on |x2|"),
        Gain("d", ident.d, "rad/(s^2*N*m)", "observer switching gain on |u|"),
        Gain("D", ident.window, "s", "distance of the two time points"),
        Gain("gamma_a", ident.gamma[0], "s/rad^2", "adaptation gain of a"),
        Gain("gamma_b", ident.gamma[1], "1/(s*N^2*m^2)", "adaptation gain of b"),
    ])
    data = LinkIdentifierData(K1=ident.K1, K2=ident.K2, c=ident.c, d=ident.d, window=ident.window,
                              gamma=tuple(ident.gamma), initial=tuple(ident.initial), Ts=ident.Ts,
                              error_bounds=tuple(bounds), required=tuple(need), signals=tuple(RECORDED))
    formulas = (
        "x2' = −a x2 + b u,  a = 1/τ,  b = Km/τ  (the sign convention of §5.1)",
        "x̂2' = −â x2 + b̂ u − (c|x2| + d|u|) sign(slm),  slm = x̂2 − x2",
        "ε1 = x2'(t) + â x2(t) − b̂ u(t),  ε2 = x2'(t−D) + â x2(t−D) − b̂ u(t−D)",
        "â' = −γa (ε1 x2(t) + ε2 x2(t−D)),  b̂' = γb (ε1 u(t) + ε2 u(t−D))",
        "V = (a − â)²/γa + (b − b̂)²/γb,  V' = −2 (ε1² + ε2²)",
        f"c > √(γa V0max) = {need[0]:.4g} 1/s,  d > √(γb V0max) = {need[1]:.4g} rad/(s²·N·m)",
    )
    d = Design(kind=KIND, plant=plant, gains=gains, poles=(), reference="step", formulas=formulas, notes=notes,
               data=data)
    return with_law(d, identifier_law(plant, ident), Linearization("none", reason=REASON))


def law(design: Design, anti_windup: Any = None) -> Law:
    """The law of ``design`` rebuilt from ``design.data`` (``anti_windup`` is refused at the spec)."""
    x = design.data
    if isinstance(x, ArmIdentifierData):
        from designkit.families.sliding_mode_identification.arm_design import arm_law

        return arm_law(design)
    return identifier_law(design.plant, Identifier(K1=x.K1, K2=x.K2, c=x.c, d=x.d, window=x.window,
                                                   gamma=tuple(x.gamma), initial=tuple(x.initial), Ts=x.Ts))


def _family() -> Family:
    from designkit.families.sliding_mode_identification import arm_report, checks, report
    from designkit.families.sliding_mode_identification.arm_design import law_lines

    return Family(
        kind=KIND, spec=SmidSpec, plants=("link", "robot"), reference="step", synthesize=synthesize, law=law,
        uses=("plant.uncertainty", "plant.uncertainty.samples"), checks=(*checks.RULES, "time_domain", "box_runs"),
        validate=validate, references=tuple(dict.fromkeys(LINK_REFERENCES + ROBOT_REFERENCES)),
        display=Display(
            label="Sliding-mode parameter identification",
            law=("u = −K1 (x1 − xD) − K2 x2  (the servo driving the link)",
                 "x̂2' = −â x2 + b̂ u − (c|x2| + d|u|) sign(x̂2 − x2)  (sliding-mode observer)",
                 "ε1 = x2'(t) + â x2(t) − b̂ u(t),  ε2 = x2'(t−D) + â x2(t−D) − b̂ u(t−D)",
                 "â' = −γa (ε1 x2(t) + ε2 x2(t−D)),  b̂' = γb (ε1 u(t) + ε2 u(t−D))"),
            summary="Notes §5.5: a sliding-mode observer gives the link's acceleration on line, and a gradient rule "
                    "on two time points D apart identifies a = 1/τ and b = Km/τ while a PD servo drives the link.",
            law_of=law_lines),
        figures=(*report.FIGURES, *arm_report.FIGURES), sections=(report.section,), diagnoses=(checks.diagnose,),
        json=report.json,
        knobs=(Knob("c", "1/s", "observer gain c of the sliding-mode observer", 1e-9, 1e9, path="controller.c",
                    current=lambda d: float(d.gains["c"]), when=lambda d: "c" in d.gains),
               Knob("d", "rad/(s^2*N*m)", "switching gain d of the observer", 1e-9, 1e9, path="controller.d",
                    role="switching", boundary=True, current=lambda d: float(d.gains["d"]),
                    when=lambda d: "d" in d.gains),
               Knob("switching_gain", "rad/s^2", "switching gain k of the arm's observers", 1e-9, 1e9,
                    path="controller.switching_gain", role="switching", boundary=True,
                    current=lambda d: d.gains["k"], when=lambda d: "k" in d.gains),
               Knob("window", "s", "time D between the two points of the update", 1e-6, 1e6, path="controller.window")),
        traits=("adaptive", "switching"),
    )


FAMILY = _family()
