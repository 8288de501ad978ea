"""PID/sliding-mode controller of one link (notes §5.3-5.4, figures 3.1 and 3.2).

Plant ``x1' = x2``, ``x2' = -x2/tau + (Km/tau)(u + xi)``; integral ``x3' = x1 - xD``.  Law::

    u = u0 + du,    du = -M sign(slm)      (or -M sat(slm/epsilon), or the notes' dead zone)
    servo:     u0 = -K1 (x1 - xD) - K2 x2 - K3 x3 + K3 K4 xD,         slm = a1 x1 + a2 x2 + x3
    tracking:  u0 = (tau/Km) xD'' + x2/Km - K1 dx1 - K2 dx2 - K3 x3,   slm = a1 dx1 + a2 dx2 + x3

with ``a1 = -(1/p1 + 1/p2)`` (s), ``a2 = 1/(p1 p2)`` (s^2), the PID gains placing ``p1, p2, p3`` on the nominal
link (:mod:`designkit.synthesis.pid`) and, for the servo, the zero of ``x1/xD`` on ``p3``.

**The sliding variable's transfer function** (derived here; checked by SymPy and python-control in the tests).
Servo, with ``w = du + xi``: ``x1 D(s) = Km [((K1 + K3 K4) s + K3) xD + s w]``, ``D = tau (s - p1)(s - p2)(s - p3)``,
and ``s slm = N(s) x1 - xD`` with ``N = 1 + a1 s + a2 s^2 = (s - p1)(s - p2)/(p1 p2)``.  The zero on ``p3`` and the
unit DC gain give ``Km ((K1 + K3 K4) s + K3) = tau p1 p2 (s - p3)``, so the ``xD`` terms cancel and

    slm(s) = Km/(tau p1 p2) (du + xi)/(s - p3),     slm' = p3 slm + (a2 Km/tau)(du + xi).

The notes print the factor ``Km/tau``: the ``1/(p1 p2) = a2`` is missing (an erratum; it has the sign of
``p1 p2 > 0``, so ``M > sup|xi|`` stands).  The same holds for the tracking form.  With ``du = -M sign(slm)``,
``slm slm' = p3 slm^2 - g (M - xi sign(slm)) |slm| < 0`` when ``M > sup|xi|``; on ``slm = 0``,
``x1 = xD/N(s)`` (servo) or ``dx1 -> 0`` with the poles ``p1, p2`` (tracking): independent of ``xi``, ``Km``,
``tau``.  From rest ``x3(0) = K4 q0 = -a1 q0`` (``K4 = 1/p1 + 1/p2`` on ``p3``), so ``slm(0) = 0``: no reaching phase.

**§5.4, a parameter change as an input-equivalent perturbation.**  The true link ``(Km, tau)`` under the gains of
``(Km0, tau0)``: ``x2' = -x2/tau0 + (Km0/tau0) u0 + (Km/tau)(du + xi_p)`` with
``xi_p = (tau/Km)[(1/tau0 - 1/tau) x2 + (Km/tau - Km0/tau0) u0]``; the sliding variable then obeys
``slm' = p3 slm + (a2 Km/tau)(du + xi_p + xi)``.  The notes print ``Km0/(Km tau0)`` for ``Km0/tau0`` (not
dimensionally consistent).  ``M`` covers ``sup|xi_p|`` over the box and the sliding motion plus the external bound
(:mod:`~designkit.families.pid_sliding_mode.bound`).

**Boundary layer and step.**  The relay is held over each step ``h`` and moves ``slm`` by at most
``h sdot_max``, ``sdot_max = |p3| band + g_max (M + sup|xi|)``; inside the strip ``|slm| < g_min (M - sup|xi|)/|p3|``
either held sign turns ``slm'`` against ``slm``, so ``|slm| <= band`` is invariant once entered
(``h = band/sdot_max``).  ``sat(slm/epsilon)`` is continuous: ``|slm| <= epsilon`` is invariant when
``M > sup|xi|`` and ``|slm| -> g xi/(|p3| + g M/epsilon) < epsilon xi/M``; the step resolves the layer's rate
``|p3| + g_max M/epsilon``.  The dead zone lets ``xi`` drift ``slm`` to the layer's edge, where the relay chatters:
band ``epsilon + h sdot_max`` with ``h = epsilon/(10 sdot_max)``.  The position's distance from the sliding motion
is ``(s/N(s)) slm``: at most ``||s/N||_1 sup|slm|``.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from designkit.errors import SpecError
from designkit.families.pid_sliding_mode import answers
from designkit.families.pid_sliding_mode.bound import corners, design_box, perturbation_bound
from designkit.families.pid_sliding_mode.checks import CERTIFICATE_RULE, RUN_RULE
from designkit.families.pid_sliding_mode.data import LinkSlidingData
from designkit.families.pid_sliding_mode.diagnoses import diagnose
from designkit.families.pid_sliding_mode.figures import FIGURES
from designkit.families.pid_sliding_mode.measure import json_summary
from designkit.families.pid_sliding_mode.spec import KIND, PidSlidingModeSpec, perturbation_level, validate
from designkit.families.pid_sliding_mode.surface import l1_norm, surface
from designkit.simulation.reference import reference_for
from designkit.synthesis import pid
from designkit.synthesis.closed_loop import with_law
from designkit.synthesis.design import Design, Gain, Gains
from designkit.synthesis.family import Display, Family
from designkit.synthesis.knobs import COMMAND_VARIATION, SETTLED_ERROR, Knob
from designkit.synthesis.law import Law, State, dynamic_law
from designkit.synthesis.linearization import Linearization

__all__ = ["FAMILY", "KIND", "PidSlidingModeSpec", "law", "synthesize"]

BAND_FRACTION = 1e-3
"""Default switching band ``BAND_FRACTION e_max/||s/N||_1`` (rad*s): the position error it leaves is at most this
fraction of the reference's largest excursion."""
LAYER_STEPS = 10.0
"""With a dead zone a step moves ``slm`` by at most ``epsilon/LAYER_STEPS``."""
SAT_RESOLUTION = 0.2
"""With ``sat`` the step is ``SAT_RESOLUTION/(|p3| + g_max M/epsilon)``: the layer's linear rate resolved."""
REASON = ("the law switches on slm = 0 (the relay M sign(slm)), where it spends its life: it has no derivative "
          "there, so no linearization describes the loop; the sliding variable's dynamics and the relay's "
          "condition are certified on the parameter box instead")
GAIN_INFO = {
    "K1": ("N*m/rad", "proportional"),
    "K2": ("N*m*s/rad", "derivative (rate feedback)"),
    "K3": ("N*m/(rad*s)", "integral"),
    "K4": ("s", "reference feedforward (the zero on p3)"),
    "a1": ("s", "sliding variable, x1 coefficient: -(1/p1 + 1/p2)"),
    "a2": ("s^2", "sliding variable, x2 coefficient: 1/(p1 p2)"),
    "M": ("N*m", "relay amplitude"),
}


def _grid(sim: Any, ref: Any, poles: Any) -> np.ndarray:
    slow = min(abs(complex(p).real) for p in poles)
    fast = max(abs(complex(p)) for p in poles)
    T = float(sim.duration) if sim.duration is not None else float(ref.horizon) + 10.0 / slow
    n = int(min(40001, max(4001, 50 * fast * T)))
    return np.linspace(0.0, T, n)


def synthesize(spec: Any, plant: Any) -> Design:
    """The PID/sliding-mode controller a spec asks for (package docstring)."""
    ctl, sim = spec.controller, spec.simulation
    poles = tuple(complex(p) for p in ctl.poles)
    sf = surface(poles)
    form = ctl.form
    values = pid.servo_gains(plant, poles, sf.p3) if form == "servo" else pid.tracking_gains(plant, poles)
    box, notes = design_box(spec, plant)
    ref_kind = "step" if form == "servo" else "trajectory"
    ref = reference_for(ref_kind, sim, 1)
    t = _grid(sim, ref, poles)
    rv = ref.evaluate(t)[:, 0, :]
    Km0, tau0 = float(plant.Km), float(plant.tau)
    external = float(ctl.perturbation_bound if ctl.perturbation_bound is not None else perturbation_level(sim))
    q0 = float(ref.start[0])
    xb = perturbation_bound(sf, form, values, t, rv, box, Km0, tau0, external, q0)
    xi = xb.total
    m = float(ctl.margin)
    if ctl.M is not None:
        M = float(ctl.M)
    elif xi > 0:
        M = (1.0 + m) * xi
    else:
        raise SpecError("controller.M", "nothing for the relay to dominate (no plant.uncertainty, no plant change and "
                        "no perturbation): give M (N*m) or a perturbation_bound")
    v = corners(box)
    g = sf.a2 * v[:, 0] / v[:, 1]
    g_min, g_max = float(np.min(g)), float(np.max(g))
    strip = g_min * (M - xi) / abs(sf.p3)
    l1 = l1_norm(sf)
    e_max = max(float(np.ptp(rv[:, 0])), float(np.max(np.abs(rv[:, 0] - q0))))
    eps = None if ctl.epsilon is None else float(ctl.epsilon)
    if eps is None:
        if ctl.switching_band is not None:
            band, source = float(ctl.switching_band), "controller.switching_band"
            if strip > 0 and band > strip / 2:
                raise SpecError(source, f"{band:g} rad*s is not inside half the strip |slm| < {strip:.4g} rad*s "
                                "where either held sign turns slm' against slm: at most " f"{strip / 2:.4g} rad*s")
        else:
            band, source = BAND_FRACTION * e_max / l1, f"default {BAND_FRACTION:g} e_max/||s/N||₁"
            if strip > 0 and band > strip / 2:
                band = strip / 2
                notes.append(f"The default switching band was narrowed to {band:.4g} rad*s, half the strip.")
        sdot = abs(sf.p3) * band + g_max * (M + xi)
        h, certified, discontinuous = band / sdot, band, True
    elif ctl.layer == "dead_zone":
        sdot = abs(sf.p3) * eps + g_max * (M + xi)
        h = eps / (LAYER_STEPS * sdot)
        certified, source, discontinuous = eps * (1 + 1 / LAYER_STEPS), "controller.epsilon", True
        if strip > 0 and certified > strip:
            raise SpecError("controller.epsilon", f"{eps:g} rad*s: the dead zone's edge band {certified:.4g} rad*s "
                            f"is outside the strip |slm| < {strip:.4g} rad*s where the relay turns slm' against "
                            f"slm: at most {strip / (1 + 1 / LAYER_STEPS):.4g} rad*s")
    else:
        sdot = abs(sf.p3) * eps + g_max * (M + xi)
        h = SAT_RESOLUTION / (abs(sf.p3) + g_max * M / eps)
        certified, source, discontinuous = None, "controller.epsilon", False
    if ctl.M is not None:
        notes.append(f"M = {M:g} N*m given by the spec (not designed).")
    names = ("K1", "K2", "K3", "K4") if form == "servo" else ("K1", "K2", "K3")
    gains = Gains.of(Gain(k, val, *GAIN_INFO[k]) for k, val in
                     [*((k, float(values[k])) for k in names), ("a1", sf.a1), ("a2", sf.a2), ("M", M)])
    data = LinkSlidingData(
        form=form, sliding_variable=("slm = a1 x1 + a2 x2 + x3" if form == "servo" else
                                     "slm = a1 (x1 - xD) + a2 (x2 - xD') + x3"),
        pid_gains=names, a1=sf.a1, a2=sf.a2, p3=sf.p3, g_nominal=sf.a2 * Km0 / tau0, M=M, M_given=ctl.M is not None,
        margin=m, perturbation=xb, box={k: tuple(val) for k, val in box.items()}, nominal=(Km0, tau0), q0=q0,
        epsilon=eps, layer=ctl.layer, band_certified=certified, sdot_max=sdot, max_step=h,
        discontinuous=discontinuous, l1=l1)
    zero = (complex(sf.p3),) if form == "servo" else ()
    formulas = (
        "slm' = p3 slm + (a2 Km/τ)(Δu + ξ), i.e. slm(s) = Km (Δu + ξ)/(τ p1 p2 (s − p3)) (the notes' Km/τ lacks "
        "1/(p1 p2))",
        f"a1 = −(1/p1 + 1/p2) = {sf.a1:.6g} s, a2 = 1/(p1 p2) = {sf.a2:.6g} s²; on slm = 0, x1 = xD/(1 + a1 s + a2 s²)",
        "ξ of a parameter change (§5.4): (τ/Km)[(1/τ0 − 1/τ) x2 + (Km/τ − Km0/τ0) u0]",
        f"M = {M:.4g} N·m against sup|ξ| = {xi:.4g} N·m ({xb.parameter:.4g} N·m of the parameter box at Km = "
        f"{xb.corner[0]:.4g}, τ = {xb.corner[1]:.4g}, plus {external:.4g} N·m external)",
        f"integration step h = {h:.4g} s (ṡlm_max = {sdot:.4g} rad)",
    )
    d = Design(kind=KIND, plant=plant, gains=gains, poles=poles, zeros=zero, reference=ref_kind, formulas=formulas,
               notes=tuple(notes), data=data)
    return with_law(d, law(d), Linearization("none", reason=REASON))


def law(design: Design, anti_windup: Any = None) -> Law:
    """``u = u0 - M sign(slm)`` (or ``sat``, or the dead zone) with the integral ``x3' = x1 - xD`` (N*m); records
    ``slm`` (rad*s), the switching part ``du`` and the PID part ``u0`` (N*m).  ``anti_windup`` is refused at the
    spec."""
    info: LinkSlidingData = design.data
    G = {k: float(design.gains[k]) for k in (*info.pid_gains, "a1", "a2", "M")}
    a1, a2, M = G["a1"], G["a2"], G["M"]
    Km0, tau0 = info.nominal
    eps, layer, form = info.epsilon, info.layer, info.form

    def e(s: Any) -> Any:
        return s.q[0] - s.qD[0]

    def slm(s: Any) -> Any:
        if form == "servo":
            return a1 * s.q[0] + a2 * s.qd[0] + s.state("x3")
        return a1 * e(s) + a2 * (s.qd[0] - s.qDd[0]) + s.state("x3")

    def u0(s: Any) -> Any:
        if form == "servo":
            return -G["K1"] * e(s) - G["K2"] * s.qd[0] - G["K3"] * s.state("x3") + G["K3"] * G["K4"] * s.qD[0]
        return ((tau0 / Km0) * s.qDdd[0] + s.qd[0] / Km0 - G["K1"] * e(s) - G["K2"] * (s.qd[0] - s.qDd[0])
                - G["K3"] * s.state("x3"))

    def du(s: Any) -> Any:
        v = slm(s)
        if eps is None:
            return -M * ca.sign(v)
        if layer == "saturation":
            return -M * ca.fmin(ca.fmax(v / eps, -1.0), 1.0)
        return ca.if_else(ca.fabs(v) > eps, -M * ca.sign(v), 0.0)

    x30 = -a1 * float(info.q0) if form == "servo" else 0.0
    reason = (f"the relay is held over each step, so slm moves at most h sdot_max per step; "
              f"h = {info.max_step:.4g} s keeps that within "
              f"the band (sdot_max = {info.sdot_max:.4g} rad over the box)"
              if info.discontinuous else
              f"h = {info.max_step:.4g} s resolves the boundary layer's rate |p3| + g_max M/epsilon")
    return dynamic_law(
        KIND, design.plant, command=lambda s: u0(s) + du(s),
        states=[State("x3", e, initial=x30, integral=True)],
        settings={"gains": design.gains.to_json(), "epsilon": eps, "layer": layer if eps is not None else None,
                  "form": form},
        signals={"slm": slm, "du": du, "u0": u0}, signal_units=("rad*s", "N*m", "N*m"),
        discontinuous=bool(info.discontinuous), max_step=float(info.max_step), max_step_reason=reason,
    )


FAMILY = Family(
    kind=KIND,
    spec=PidSlidingModeSpec,
    plants=("link",),
    uses=("plant.uncertainty",),
    reference="step",
    references=("step", "square", "prbs", "quintic", "sine", "trapezoidal", "via_points"),
    synthesize=synthesize,
    law=law,
    checks=(CERTIFICATE_RULE, RUN_RULE, "time_domain"),
    display=Display(
        label="PID/sliding-mode controller",
        law=("slm = a1 x1 + a2 x2 + x3 (servo) or a1 Δx1 + a2 Δx2 + x3 (tracking), x3' = x1 − xD",
             "u = u0 − M sign(slm), u0 the PID with its zero on p3 (servo) or the PID tracker",
             "sat(slm/ε) or a dead zone |slm| < ε replaces sign(slm) with a boundary layer"),
        summary="Notes §5.3–5.4: a relay added to the one-link PID keeps the sliding variable slm at 0, where the "
                "response is 1/(1 + a1 s + a2 s²) whatever Km, τ and a bounded perturbation; M covers the "
                "input-equivalent perturbation of the parameter box (§5.4), certified on the box.",
    ),
    validate=validate,
    figures=FIGURES,
    json=json_summary,
    knobs=(Knob("M", "N*m", "amplitude of the relay on the sliding variable", 1e-6, 1e6, path="controller.M",
                role="switching", boundary=True, current=lambda d: d.gains["M"],
                when=lambda d: np.ndim(d.gains["M"]) == 0),
           Knob("poles", "1/s", "closed-loop poles of the PID part (the sliding motion keeps two)", 1e-3, 1e6,
                path="controller.poles"),
           Knob("epsilon", "rad*s", "boundary layer |slm| ≤ ε replacing the relay's sign", 1e-9, 1e6,
                path="controller.epsilon")),
    traits=("switching",),
    metrics=(SETTLED_ERROR, COMMAND_VARIATION),
    diagnoses=(diagnose,),
    answers=answers.ANSWERS,
    predictions=answers.PREDICTIONS,
)

from designkit.families.pid_sliding_mode.elastic import extend as _with_elastic_joint  # noqa: E402

FAMILY = _with_elastic_joint(FAMILY)
"""The family also designs for ROBEL's elastic joint (motor-side sliding variable; pid_sliding_mode/elastic.py)."""

from designkit.families.pid_sliding_mode.robot_family import extend as _with_robots  # noqa: E402

FAMILY = _with_robots(FAMILY)
"""The family also designs for robots, one loop per joint with the hierarchy of control's relays
(pid_sliding_mode/robot.py)."""
