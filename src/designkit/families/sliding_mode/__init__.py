"""Sliding-mode position servo of one link (notes section 5.1): the ``sliding_mode`` family.

Plant ``x1' = x2``, ``x2' = -a x2 + b (u + xi)``, ``a = 1/tau``, ``b = Km/tau``.  Law, with ``e = x1 - xD``::

    s = x2 + c e,    u = -psi e - M sign(s),    psi = alpha if e s > 0 else beta

**Error coordinates.**  The references a servo follows here (step, square wave, PRBS) are piecewise constant:
between jumps ``xD' = 0``, so ``e' = x2`` and the notes' ``slm = x2 + c x1`` (regulation to 0) is exactly
``s = x2 + c e``.  At a jump of ``xD`` the error jumps by ``-dxD`` and ``s`` by ``-c dxD``: a new reaching phase.

**Derivation** (checked by SymPy and by simulation in ``tests/families/sliding_mode``).
``s' = x2' + c e' = (c - a) x2 + b (u + xi)``; with ``x2 = s - c e``::

    s' = (c - a) s - K_psi e - b M sign(s) + b xi,     K_psi = c (c - a) + b psi,
    s s' = (c - a) s^2 - K_psi e s - b (M - xi sign(s)) |s|.

*Existence of the sliding mode on s = 0.*  On ``s = 0``, ``s' = 0`` gives the equivalent control
``u_eq = -k e - xi`` with ``k = (a - c) c / b = c (1 - c tau)/Km``.  A sliding mode exists where ``u_eq`` lies
between the two controls ``u+ = -psi+ e - M`` (``s > 0``) and ``u- = -psi- e + M`` (``s < 0``) (Utkin; notes
theorem 1): for ``e > 0`` (``psi+ = alpha``, ``psi- = beta``) ``(k - alpha) e < M - xi`` and
``(beta - k) e < M + xi``, mirrored for ``e < 0``.  For every ``e``: **alpha >= k, beta <= k, M > |xi|** -- the
notes' ``alpha > (a - c) c/b``, ``beta < (a - c) c/b``, ``M > |xi|``, correct as printed (strict, for a margin).
Equivalently ``-K_psi e s <= 0`` on both sides, and then ``s s' <= (c - a) s^2 - b (M - xi_bar)|s|``: near the
line ``|s|`` shrinks at ``eta = b (M - xi_bar)`` at least -- everywhere when ``c tau <= 1`` (reaching within
``|s(0)|/eta``), only in the strip ``|s| < b (M - xi_bar)/(c - a)`` when the line is faster than the link.

*Reaching (every trajectory meets s = 0 in finite time).*  In the phase plane ``(e, e')`` let ``A = {e s > 0}``
(``psi = alpha``) and ``B = {e s < 0}`` (``psi = beta``).  On ``e = 0``, ``e' = s``: trajectories enter ``A``
there, so ``A`` is left only through ``s = 0``; in ``B``, ``e' = s - c e`` has the sign of ``-e``, so ``B`` is
left (in finite time) through ``s = 0`` or into ``A``.  In ``A`` the angle ``theta = atan2(e', e)`` obeys
``theta' = -(b alpha e^2 + a e e' + e'^2)/r^2 + e f/r^2`` with ``f = b (xi - M sign(s))``, and ``e f <= 0`` there
when ``M >= |xi|``.  The form ``b alpha e^2 + a e e' + e'^2`` is positive definite iff ``a^2 < 4 b alpha``, i.e.
the ``alpha`` structure ``e'' + a e' + b alpha e = 0`` is a **focus**: then ``theta`` turns clockwise at a rate
bounded below, and the trajectory leaves the sector ``A`` (angle < pi) through ``s = 0``.  So the reaching
condition is **alpha > a^2/(4 b) = 1/(4 Km tau)** (with ``M >= |xi|``).  What it buys: with real roots
``mu`` of ``mu^2 + a mu + b alpha`` the eigenvector lines ``e' = mu e`` lie inside ``A`` when ``mu > -c`` (both
do when ``c > a/2``, since ``alpha >= k`` puts ``-c`` left of both roots), and a trajectory on one goes to the
origin inside ``A`` without ever sliding (it does with ``M = 0``; the relay only rescues it near the origin).
Since ``(a - c) c <= a^2/4`` (``(c - a/2)^2 >= 0``), the notes' ``max{(a - c) c/b, a^2/(4 b)}`` is always
``a^2/(4 b)``: the focus condition implies the ``alpha``-side existence condition (equal only at ``c = a/2``).

*On the line* ``e' = -c e``: ``e(t) = e(t0) exp(-c (t - t0))``, whatever ``Km``, ``tau`` and ``|xi| < M``.

**Design and certificate.**  The conditions multiplied by ``Km`` or ``4 Km tau`` (affine or multi-affine in
``(Km, tau)``, :mod:`~designkit.families.sliding_mode.conditions`) are met with a margin at the box's corners
by a linear program (:mod:`~designkit.families.sliding_mode.design_lp`) and certified on the whole box by the
condition-certificate core (:mod:`~designkit.families.sliding_mode.checks`).

**Integration step.**  The law is discontinuous: the simulator holds its command over each step ``h``.  A step
moves ``s`` by at most ``h sdot_max`` (:func:`~designkit.families.sliding_mode.conditions.sdot_bound`); inside
the strip ``s'`` has the sign opposite to ``s`` at the step's start for the whole step, so
``|s_k| <= delta => |s_k+1| <= max(|s_k|, h sdot_max - |s_k|) <= delta`` when ``h = delta / sdot_max``: the band
``|s| <= delta`` (spec ``chattering_band``, at most half the strip) is invariant once entered, and leaves
``|e| <= delta/c``.  With a boundary layer ``epsilon`` (``sat(s/epsilon)``; the notes' section 5.4 prints a dead
zone, which lets the perturbation push ``s`` to the band's edge and chatter there) ``h = epsilon/(10 sdot_max)``:
a step moves ``s`` by a tenth of the layer and the held linear part ``h b M/epsilon <= 0.1`` is integrated
faithfully; the layer is invariant when ``epsilon`` is inside the strip (half of it is asked), and
``|s| -> epsilon xi/M``.
"""

from __future__ import annotations

import math
from typing import Any

import casadi as ca

from designkit.errors import ModelError, SpecError
from designkit.families.sliding_mode.checks import CERTIFICATE_RULE, RUN_RULE
from designkit.families.sliding_mode.conditions import PARAMETERS, SlidingGains, reaching_rate, sdot_bound, strip_width
from designkit.families.sliding_mode.data import SlidingData
from designkit.families.sliding_mode.design_lp import design_gains
from designkit.families.sliding_mode.diagnoses import diagnose
from designkit.families.sliding_mode.figures import FIGURES
from designkit.families.sliding_mode.linear import LINEAR, LinearSlidingData, linear_law, linear_synthesize
from designkit.families.sliding_mode.linear_figures import LINEAR_FIGURES
from designkit.families.sliding_mode.measure import json_summary
from designkit.families.sliding_mode.spec import (
    KIND,
    SlidingModeSpec,
    perturbation_level,
    reference_amplitude,
    validate,
)
from designkit.synthesis.closed_loop import with_law
from designkit.synthesis.design import Design, Gain, Gains
from designkit.synthesis.family import Display, Family, PlantField
from designkit.synthesis.knobs import COMMAND_VARIATION, SETTLED_ERROR, Knob
from designkit.synthesis.law import Law, dynamic_law
from designkit.synthesis.linearization import Linearization

__all__ = ["FAMILY", "KIND", "SlidingModeSpec", "law", "synthesize"]

BAND_FRACTION = 1e-3
"""Default chattering band ``delta = BAND_FRACTION c e_max`` (rad/s): the error it leaves, ``delta/c``, is this
fraction of the largest error jump."""
LAYER_STEPS = 10.0
"""With a boundary layer ``epsilon`` a step moves ``s`` by at most ``epsilon / LAYER_STEPS``."""
REASON = ("the law switches on s = 0 (the relay M sign(s)) and on e s = 0 (psi between alpha and beta), where it "
          "spends its life: it has no derivative there, so no linearization describes the loop; its existence and "
          "reaching conditions are certified on the parameter box instead")
GAIN_INFO = {
    "alpha": ("N*m/rad", "structure gain where e s > 0"),
    "beta": ("N*m/rad", "structure gain where e s < 0"),
    "M": ("N*m", "relay amplitude"),
    "c": ("1/s", "slope of the sliding line s = x2 + c e (pole -c on it)"),
}


def design_box(spec: Any, plant: Any) -> tuple[dict[str, tuple[float, float]], list[str]]:
    """The ``(Km, tau)`` box the design and certificate cover: ``plant.uncertainty`` (the nominal value where an
    interval is missing), widened to contain the nominal plant and ``simulation.plant_change`` so that it holds
    every plant the run meets; and notes saying where it was widened."""
    unc = spec.plant.uncertainty
    intervals = unc.intervals if unc is not None else {}
    change = spec.simulation.plant_change
    if change is not None:
        try:
            plant.with_params(**change.values)
        except ModelError as exc:
            raise SpecError(f"simulation.plant_change.values.{exc.field}", exc.message) from None
    box, notes = {}, []
    for name in PARAMETERS:
        nominal = float(plant.parameter(name).value)
        lo, hi = intervals.get(name, (nominal, nominal))
        values = [lo, hi, nominal] + ([float(change.values[name])] if change and name in change.values else [])
        box[name] = (min(values), max(values))
        if name in intervals and box[name] != (lo, hi):
            notes.append(f"The {name} interval [{lo:g}, {hi:g}] was widened to [{box[name][0]:g}, {box[name][1]:g}] "
                         "to hold the nominal plant and the plant change the run meets.")
    return box, notes


def _band(ctl: Any, g: SlidingGains, xi_bar: float, box: dict, e_max: float) -> tuple[float, float, str, list[str]]:
    """``(band, h, source, notes)``: the band ``|s| <= band`` (rad/s) and the largest step ``h`` (s)."""
    strip = strip_width(g.M, xi_bar, g.c, box)
    notes: list[str] = []
    if ctl.boundary_layer is not None:
        eps = float(ctl.boundary_layer)
        if strip > 0 and eps > strip / 2:
            raise SpecError("controller.boundary_layer", f"{eps:g} rad/s is not inside half the strip |s| < "
                            f"{strip:.4g} rad/s where s s' < 0 holds (the layer's invariance needs it): at most "
                            f"{strip / 2:.4g} rad/s")
        return eps, eps / (LAYER_STEPS * sdot_bound(g, xi_bar, box, e_max, eps)), "controller.boundary_layer", notes
    if ctl.chattering_band is not None:
        delta, source = float(ctl.chattering_band), "controller.chattering_band"
        if strip > 0 and delta > strip / 2:
            raise SpecError("controller.chattering_band", f"{delta:g} rad/s is not inside half the strip |s| < "
                            f"{strip:.4g} rad/s where s s' < 0 holds (the band's invariance needs it): at most "
                            f"{strip / 2:.4g} rad/s")
    else:
        delta, source = BAND_FRACTION * g.c * e_max, f"default {BAND_FRACTION:g} c e_max"
        if strip > 0 and delta > strip / 2:
            delta = strip / 2
            notes.append(f"The default chattering band was narrowed to {delta:.4g} rad/s, half the strip where "
                         "s s' < 0 holds.")
    return delta, delta / sdot_bound(g, xi_bar, box, e_max, delta), source, notes


def _max_control(spec: Any) -> float | None:
    req = spec.requirements
    value = None if req is None else req.max_control
    return min(value) if isinstance(value, list | tuple) else value


def synthesize(spec: Any, plant: Any) -> Design:
    """The sliding-mode servo a spec asks for (package docstring): box, LP gains, band and step, law; on a linear
    plant :func:`~designkit.families.sliding_mode.linear.linear_synthesize`."""
    if plant.kind in LINEAR:
        return linear_synthesize(spec, plant, KIND)
    ctl, sim = spec.controller, spec.simulation
    c = -float(ctl.sliding_poles[0].real)
    box, notes = design_box(spec, plant)
    level = perturbation_level(sim)
    xi_bar = float(ctl.perturbation_bound if ctl.perturbation_bound is not None else level)
    amplitude, e_max = reference_amplitude(sim)
    fixed = {n: float(getattr(ctl, n)) for n in ("alpha", "beta", "M") if getattr(ctl, n) is not None}
    lp = design_gains(c, box, xi_bar, float(ctl.margin), e_max, fixed=fixed, u_max=_max_control(spec),
                      omega_r=ctl.reaching_frequency, solver=spec.numerics.solver)
    g = SlidingGains(lp.alpha, lp.beta, lp.M, c)
    band, h, band_source, band_notes = _band(ctl, g, xi_bar, box, e_max)
    sdot = sdot_bound(g, xi_bar, box, e_max, band)
    strip = strip_width(g.M, xi_bar, c, box)
    if ctl.perturbation_bound is None:
        notes.append(f"sup |xi| = {xi_bar:g} N*m taken from simulation.perturbation.value.")
    if lp.torque_rows.startswith("dropped"):
        notes.append(f"Torque rows {lp.torque_rows}.")
    if fixed:
        notes.append(f"Given by the spec (not designed): {', '.join(f'{k} = {v:g}' for k, v in fixed.items())}.")
    gains = Gains.of(Gain(k, v, *GAIN_INFO[k]) for k, v in (("alpha", g.alpha), ("beta", g.beta), ("M", g.M),
                                                             ("c", c)))
    m = float(ctl.margin)
    data = SlidingData(
        c=c, xi_bar=xi_bar, margin=m, box={k: list(v) for k, v in box.items()},
        amplitude=amplitude, e_max=e_max, band=band, band_source=band_source,
        boundary_layer=ctl.boundary_layer, max_step=h, sdot_max=sdot,
        strip=strip if math.isfinite(strip) else None,
        reaching_rate=reaching_rate(g.M, xi_bar, box), lp=dict(lp.certificate), torque_rows=lp.torque_rows,
        objective=lp.objective, fixed=sorted(fixed), reaching_frequency=ctl.reaching_frequency,
    )
    formulas = (
        "existence of the sliding mode: α Km − c + c² τ > 0 and c − c² τ − β Km > 0, i.e. α > (a − c) c/b > β",
        "reaching: 4 α Km τ − 1 > 0, i.e. α > a²/(4 b) (the α structure is a focus); the relay: M > sup|ξ|",
        f"gains: the LP over the box's corners min e_max (α − β) + 2 M with margin {m:g} (e_max = {e_max:g} rad)",
        f"h = {'ε/(10 ṡ_max)' if ctl.boundary_layer else 'δ/ṡ_max'} = {h:.4g} s (the integration step, with "
        f"ṡ_max = {sdot:.4g} rad/s² the fastest ṡ over the box for |e| ≤ {e_max:g} rad)",
    )
    d = Design(kind=KIND, plant=plant, gains=gains, poles=(complex(-c),), reference="step", formulas=formulas,
               notes=(*notes, *band_notes), data=data)
    return with_law(d, law(d), Linearization("none", reason=REASON))


def law(design: Design, anti_windup: Any = None) -> Law:
    """``u = -psi e - M sign(s)`` (or ``M sat(s/epsilon)``), ``s = x2 + c e``, held over each step of at most
    ``max_step`` (N*m); records ``s`` (rad/s) and ``psi`` (N*m/rad).  ``anti_windup`` is refused at the spec."""
    if isinstance(design.data, LinearSlidingData):
        return linear_law(design, anti_windup)
    al, be, M, c = (float(design.gains[k]) for k in ("alpha", "beta", "M", "c"))
    info = design.data
    eps = info.boundary_layer

    def error(s: Any) -> Any:
        return s.q[0] - s.qD[0]

    def sliding(s: Any) -> Any:
        return s.qd[0] + c * error(s)

    def psi(s: Any) -> Any:
        return ca.if_else(error(s) * sliding(s) > 0, al, be)

    def relay(s: Any) -> Any:
        return M * (ca.sign(sliding(s)) if eps is None else ca.fmin(ca.fmax(sliding(s) / eps, -1.0), 1.0))

    what = "a tenth of the boundary layer" if eps is not None else "the chattering band"
    reason = (f"the command is held over each step, so s moves at most h sdot_max per step; h = {info.max_step:.4g} "
              f"s keeps that within {what} ({info.band:.4g} rad/s; sdot_max = {info.sdot_max:.4g} rad/s^2 over "
              f"the box for |e| <= {info.e_max:g} rad)")
    return dynamic_law(
        KIND, design.plant, command=lambda s: -psi(s) * error(s) - relay(s),
        settings={"gains": design.gains.to_json(), "boundary_layer": eps, "band": info.band},
        signals={"s": sliding, "psi": psi}, signal_units=("rad/s", "N*m/rad"),
        discontinuous=True, max_step=float(info.max_step), max_step_reason=reason,
    )


def json_of(result: Any) -> dict[str, Any]:
    """The ``sliding`` object of ``verify --json``: the link's numbers and measurements
    (:func:`~designkit.families.sliding_mode.measure.json_summary`), or on a linear plant the surface, the gains
    and the proven ranges they come from."""
    info = result.design.data
    if not isinstance(info, LinearSlidingData):
        return json_summary(result)
    return {"sliding": {"sliding_function": "s = c (x - x* xD)", "c": list(info.c), "k": list(info.k), "k0": info.k0,
                        "u_rest": info.u_rest, "x_rest": list(info.x_rest), "perturbation_bound": info.xi_bar,
                        "margin": info.margin, "box": {k: list(v) for k, v in info.box.items()},
                        "sup_g_over_cB": list(info.g_sup), "sup_w_over_cB": info.w_sup, "cB_range": list(info.cB_range),
                        "band_target": info.band, "boundary_layer": info.boundary_layer, "max_step": info.max_step,
                        "S0": info.S0}}


def law_lines(design: Any) -> tuple[str, ...]:
    """The law on a linear plant (``()`` on the link: the family's own lines)."""
    if not isinstance(design.data, LinearSlidingData):
        return ()
    return ("s = c (x − x* xD), c from the sliding poles (Ackermann, c B0 = 1)",
            "u = u* xD − c A0 x̃ − (k0 + Σ k_i |x̃_i|) sign(s);  sat(s/ε) replaces sign(s) with a boundary layer")


FAMILY = Family(
    kind=KIND,
    spec=SlidingModeSpec,
    plants=("link", *LINEAR),
    uses=("plant.uncertainty",),
    reference="step",
    references=("step", "square", "prbs"),
    synthesize=synthesize,
    law=law,
    checks=(CERTIFICATE_RULE, RUN_RULE, "time_domain"),
    display=Display(
        label="Sliding-mode position servo",
        law_of=law_lines,
        law=("s = x2 + c (x1 − xD)", "u = −ψ (x1 − xD) − M sign(s)",
             "ψ = α on the side (x1 − xD) s > 0 and β on the other; sat(s/ε) replaces sign(s) with a boundary layer"),
        summary="Notes §5.1: a switching law brings the link onto the sliding line s = 0, where x1 − xD decays as "
                "exp(−c t) whatever Km, τ and a bounded perturbation; the gains come from a linear program over the "
                "corners of the (Km, τ) box and the existence and reaching conditions are certified on the box.",
    ),
    validate=validate,
    figures=(*FIGURES, *LINEAR_FIGURES),
    diagnoses=(diagnose,),
    json=json_of,
    plant_fields=tuple(PlantField(name, ("link",), what) for name, what in (
        ("alpha", "the structure gain where e s > 0 of the link's law"),
        ("beta", "the structure gain where e s < 0 of the link's law"),
        ("reaching_frequency", "the natural frequency of the link's alpha structure"))),
    knobs=(Knob("M", "N*m", "switching amplitude of the relay", 1e-6, 1e6, path="controller.M", role="switching",
                boundary=True, current=lambda d: float(d.gains["M"])),
           Knob("sliding_poles", "1/s", "pole −c of the motion on the sliding line", 1e-3, 1e6,
                path="controller.sliding_poles"),
           Knob("margin", "", "relative margin of the designed gains on every condition", 1e-3, 10,
                path="controller.margin")),
    traits=("switching",),
    metrics=(SETTLED_ERROR, COMMAND_VARIATION),
)
