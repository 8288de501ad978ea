"""The PID/sliding-mode controller on ROBEL's elastic joint (notes §5.3 on the plant of appendix B, figure 5.1).

**Why the motor side.**  The relay must act where ``slm'`` sees the input.  On the load position
(``slm = a1 x3 + a2 x4 + z``) ``slm'`` contains ``x4'``, which does not depend on ``u``: the relative degree from
``u`` to ``slm`` is 3, and no relay keeps such a variable at 0 (it oscillates instead).  On the motor position,
``slm = a1 x1 + a2 x2 + z`` with ``z' = x1 - xD``::

    slm' = a1 x2 + x1 - xD + a2 x2',   x2' = -x2/tau1 - k1 (x1 - x3) + (Km/tau1) u,   k1 = KR R1^2/J1

so ``slm' = g (du - du_eq)`` with ``g = a2 Km/tau1 > 0``: the relay ``du = -M sign(slm)`` keeps ``slm = 0`` while
``M > |du_eq|``, the equivalent control's share beyond the PID part ``u0``.  The PID part (``u0 = -K1 (x1 - xD) -
K2 x2 - K3 z + K3 K4 xD``) has its gains from the requested poles on the rigid approximation
(:func:`~designkit.models.elastic.rigid_approximation`) with the zero on ``p3``, as on the link.

**The sliding motion.**  ``slm = 0`` is kinematic: ``s slm = (1 + a1 s + a2 s^2) x1 - xD``, so on it
``x1 = xD/N(s)`` whatever the plant; the load then follows through the transmission alone,

    x3 = k2/(s^2 + s/tau2 + k2) x1 + (R2/J2)/(s^2 + s/tau2 + k2) w,      k2 = KR R2^2/J2,

whose mode is damped only by the link's friction: ``zeta = 1/(2 tau2 sqrt(k2))`` (0.0125 with ROBEL's defaults).
The relay makes the motor follow its model exactly and leaves that mode as lightly damped as the link is.
A load ``w`` leaves no offset (the motor position is held at ``xD``; the spring then carries ``w``):
``x3 - xD = w/(KR R2)`` at rest.

**M** covers ``sup |du_eq|`` along the sliding motion of every corner of ``plant.uncertainty`` (and the nominal
plant), simulated here with the spec's step and load (held-input exact discretisation): ``M = (1 + margin) sup``.
This is a bound from simulations of the sliding motion, not a certificate over the whole box.  The step
``h = band/(g_max (M + sup|du_eq|))`` keeps ``|slm| <= band`` (band: ``1e-3 e_max/||s/N||_1``, or
``controller.switching_band``).
"""

from __future__ import annotations

import dataclasses
import itertools
from typing import Any

import casadi as ca
import numpy as np

from designkit.errors import SpecError
from designkit.families.pid_sliding_mode.data import ElasticSlidingData, LoadMode
from designkit.families.pid_sliding_mode.spec import KIND
from designkit.families.pid_sliding_mode.surface import l1_norm, surface
from designkit.synthesis import pid
from designkit.synthesis.closed_loop import with_law
from designkit.synthesis.design import Design, Gain, Gains
from designkit.synthesis.law import Law, State, dynamic_law
from designkit.synthesis.linearization import Linearization
from designkit.verification.check import Check
from designkit.verification.suite import CheckRule, Context

__all__ = ["BAND", "JSON_KEY", "RELAY", "RELAY_RULE", "RUN_RULE", "extend", "law", "sliding_motion", "synthesize"]

JSON_KEY = "pid_sm_elastic"
"""The key of this design's ``--json`` object (its data is an :class:`ElasticSlidingData`)."""
RELAY, BAND = "pid_sm_elastic_relay", "pid_sm_elastic_band"
"""The names of the relay-amplitude check and of the in-band run check (read by the lab 3 answers)."""
BAND_FRACTION = 1e-3
REASON = ("the law switches on slm = 0 (the relay M sign(slm)), where it spends its life: no linearization "
          "describes the loop; the relay is sized on the sliding motions of the box's corners instead")
GAIN_INFO = {
    "K1": ("{u}/rad", "proportional (motor position)"), "K2": ("{u}*s/rad", "derivative (motor speed)"),
    "K3": ("{u}/(rad*s)", "integral (motor position error)"), "K4": ("s", "reference feedforward (zero on p3)"),
    "a1": ("s", "sliding variable, x1 coefficient"), "a2": ("s^2", "sliding variable, x2 coefficient"),
    "M": ("{u}", "relay amplitude"),
}


def _held(A: np.ndarray, B: np.ndarray, x0: np.ndarray, U: np.ndarray, t: np.ndarray) -> np.ndarray:
    """States of ``x' = A x + B u`` on the grid ``t`` with ``u`` held at ``U[k-1]`` over ``[t[k-1], t[k]]``."""
    from scipy.linalg import expm

    n, m = A.shape[0], B.shape[1]
    out = np.empty((len(t), n))
    out[0] = x = np.asarray(x0, float)
    cache: dict[float, tuple[np.ndarray, np.ndarray]] = {}
    for k in range(1, len(t)):
        h = round(float(t[k] - t[k - 1]), 15)
        if h not in cache:
            E = expm(np.block([[A, B], [np.zeros((m, n + m))]]) * h)
            cache[h] = (E[:n, :n], E[:n, n:])
        Ad, Bd = cache[h]
        x = Ad @ x + Bd @ U[k - 1]
        out[k] = x
    return out


def sliding_motion(params: Any, a1: float, a2: float, gains: dict[str, float], t: np.ndarray, r: np.ndarray,
                   w: np.ndarray, q0: float) -> dict[str, np.ndarray]:
    """The motion on ``slm = 0`` of the elastic joint ``params`` (module docstring) from rest at ``q0``.

    Returns ``x`` (N x 4, spring-side rad and rad/s), ``u_eq`` (the input that keeps ``slm = 0``), ``u0`` (the
    PID part) and ``du_eq = u_eq - u0`` (input units).
    """
    k1 = params.KR * params.R1**2 / params.J1
    k2 = params.KR * params.R2**2 / params.J2
    A = np.array([[0.0, 1.0, 0.0, 0.0], [-1.0 / a2, -a1 / a2, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0],
                  [k2, 0.0, -k2, -1.0 / params.tau2]])
    B = np.array([[0.0, 0.0], [1.0 / a2, 0.0], [0.0, 0.0], [0.0, params.R2 / params.J2]])
    U = np.column_stack([r, w])
    x = _held(A, B, np.array([q0, 0.0, q0, 0.0]), U, t)
    x1, x2, x3 = x[:, 0], x[:, 1], x[:, 2]
    x2dot = (r - x1 - a1 * x2) / a2
    u_eq = (params.tau1 / params.Km) * (x2dot + x2 / params.tau1 + k1 * (x1 - x3))
    z = -a1 * x1 - a2 * x2
    u0 = -gains["K1"] * (x1 - r) - gains["K2"] * x2 - gains["K3"] * z + gains["K3"] * gains["K4"] * r
    return {"x": x, "u_eq": u_eq, "u0": u0, "du_eq": u_eq - u0}


def _scenario(spec: Any, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    from designkit.simulation.reference import reference_for

    sim = spec.simulation
    ref = reference_for("step", sim, 1)
    r = np.asarray(ref.evaluate(t)[:, 0, 0], float)
    pert = sim.perturbation
    w = np.zeros_like(t)
    if pert is not None:
        value = pert.value[0] if isinstance(pert.value, list | tuple) else pert.value
        w = np.where(t >= float(pert.time), float(value), 0.0)
    return r, w, float(ref.start[0])


def synthesize(spec: Any, plant: Any) -> Design:
    """The motor-side PID/sliding-mode controller of the elastic joint (module docstring)."""
    from designkit.models.elastic import rigid_approximation
    from designkit.models.link import LinkPlant

    ctl, sim = spec.controller, spec.simulation
    if ctl.form != "servo":
        raise SpecError("controller.form", "the elastic joint is driven by the servo form (figure 3.1) only")
    if ctl.epsilon is not None and ctl.layer == "dead_zone":
        raise SpecError("controller.layer", "the elastic joint's controller takes a saturation layer or none")
    if (spec.plant.mgl or 0.0) > 0:
        raise SpecError("plant.mgl", "designed on the joint without gravity (mgl = 0)")
    from designkit.synthesis.state_space import check_controllable, linear_model

    unc = spec.plant.uncertainty
    box = {k: (float(lo), float(hi)) for k, (lo, hi) in (unc.intervals.items() if unc is not None else ())}
    check_controllable(spec, linear_model(plant), box, "the motor's sliding mode cannot move the link")
    poles = tuple(complex(p) for p in ctl.poles)
    sf = surface(poles)
    Km_r, tau_r = rigid_approximation(plant.params)
    values = pid.servo_gains(LinkPlant(Km=Km_r, tau=tau_r), poles, sf.p3)
    T = float(sim.duration) if sim.duration is not None else 10.0 / min(abs(p.real) for p in poles)
    t = np.linspace(0.0, T, int(min(40001, max(4001, 200 * T))))
    r, w, q0 = _scenario(spec, t)
    corners = [dict(zip(box, v, strict=True)) for v in itertools.product(*box.values())] or [{}]
    worst, at, g = 0.0, {}, []
    for corner in [{}, *corners]:
        params = dataclasses.replace(plant.params, **corner)
        motion = sliding_motion(params, sf.a1, sf.a2, values, t, r, w, q0)
        peak = float(np.max(np.abs(motion["du_eq"])))
        g.append(sf.a2 * params.Km / params.tau1)
        if peak > worst:
            worst, at = peak, corner
    m = float(ctl.margin)
    M = float(ctl.M) if ctl.M is not None else (1.0 + m) * worst
    l1 = l1_norm(sf)
    e_max = float(np.max(np.abs(r - q0)))
    eps = None if ctl.epsilon is None else float(ctl.epsilon)
    band = float(ctl.switching_band) if ctl.switching_band is not None else BAND_FRACTION * e_max / l1
    g_max = max(g)
    sdot = g_max * (M + worst)
    h = band / sdot if eps is None else 0.2 / (abs(sf.p3) + g_max * M / eps)
    u = plant.inputs[0].unit
    gains = Gains.of(Gain(k, float(v), GAIN_INFO[k][0].format(u=u), GAIN_INFO[k][1]) for k, v in
                     [*values.items(), ("a1", sf.a1), ("a2", sf.a2), ("M", M)])
    nominal = sliding_motion(plant.params, sf.a1, sf.a2, values, t, r, w, q0)
    k2 = plant.params.KR * plant.params.R2**2 / plant.params.J2
    zeta = 1.0 / (2.0 * plant.params.tau2 * np.sqrt(k2))
    every = max(1, len(t) // 2000)
    data = ElasticSlidingData(
        pid_gains=tuple(values), a1=sf.a1, a2=sf.a2, p3=sf.p3, M=M, sup_du_eq=worst, sup_at=at,
        band=band if eps is None else eps, epsilon=eps, max_step=h, q0=q0, rigid=(Km_r, tau_r),
        load_mode=LoadMode(k2, float(np.sqrt(k2)), zeta), ideal_t=t[::every], ideal_x1=nominal["x"][::every, 0],
        ideal_x3=nominal["x"][::every, 2])
    formulas = (
        "slm = a1 x1 + a2 x2 + z (motor side), z' = x1 − xD; u = u0 − M sign(slm)",
        "on slm = 0: x1 = xD/(1 + a1 s + a2 s²), x3 = k2 x1/(s² + s/τ2 + k2) (+ the load through R2/J2)",
        f"M = {M:.4g} {u} against sup|Δu_eq| = {worst:.4g} {u} on the sliding motions of the box's corners",
        f"integration step h = {h:.4g} s",
    )
    notes = (f"The sliding variable is on the motor (relative degree 1); on the load the relay could not slide "
             f"(relative degree 3). The load's mode on slm = 0 has ω = {np.sqrt(k2):.4g} rad/s and damping "
             f"{zeta:.3g} (the link's friction only).",)
    d = Design(kind=KIND, plant=plant, gains=gains, poles=poles, zeros=(complex(sf.p3),), reference="step",
               formulas=formulas, notes=notes, data=data)
    return with_law(d, law(d), Linearization("none", reason=REASON))


def law(design: Design, anti_windup: Any = None) -> Law:
    """``u = u0 - M sign(slm)`` (or ``sat(slm/epsilon)``) on the motor side; records ``slm``, ``du``, ``u0``."""
    info: ElasticSlidingData = design.data
    G = {k: float(design.gains[k]) for k in (*info.pid_gains, "a1", "a2", "M")}
    eps = info.epsilon

    def slm(s: Any) -> Any:
        return G["a1"] * s.y[0] + G["a2"] * s.y[1] + s.state("z")

    def u0(s: Any) -> Any:
        return (-G["K1"] * (s.y[0] - s.qD[0]) - G["K2"] * s.y[1] - G["K3"] * s.state("z")
                + G["K3"] * G["K4"] * s.qD[0])

    def du(s: Any) -> Any:
        v = slm(s)
        return -G["M"] * (ca.sign(v) if eps is None else ca.fmin(ca.fmax(v / eps, -1.0), 1.0))

    return dynamic_law(
        KIND, design.plant, command=lambda s: u0(s) + du(s),
        # z integrates the motor's position error, not the controlled (link) position's: no integral action on the
        # link (a load leaves w/(KR R2) there), so not one of the law's integral_states
        states=[State("z", lambda s: s.y[0] - s.qD[0], initial=-G["a1"] * float(info.q0))],
        settings={"gains": design.gains.to_json(), "epsilon": eps, "side": "motor"},
        signals={"slm": slm, "du": du, "u0": u0}, signal_units=("rad*s", "input", "input"),
        discontinuous=eps is None, max_step=float(info.max_step),
        max_step_reason=f"h = {info.max_step:.4g} s keeps the held relay within the band {info.band:.4g} rad*s",
    )


def _relay(design: Any, ctx: Context) -> tuple[Check, ...]:
    info: ElasticSlidingData = design.data
    M, sup = info.M, info.sup_du_eq
    at = ", ".join(f"{k} = {v:g}" for k, v in info.sup_at.items()) or "the nominal plant"
    ok = sup < M
    return (Check(RELAY, ok, "M > sup|Δu_eq| on the sliding motions", M, M - sup, "input",
                  f"M = {M:.4g} is {'above' if ok else 'NOT above'} the largest equivalent switching control "
                  f"{sup:.4g} needed to stay on slm = 0 (at {at}; the nominal plant and every corner of the box "
                  "simulated with the spec's step and load): a bound from simulations, not a certificate",
                  {"M": M, "sup_du_eq": sup, "at": dict(info.sup_at)}),)


def _run(design: Any, ctx: Context) -> tuple[Check, ...]:
    info: ElasticSlidingData = design.data
    sim = ctx.simulation
    t = np.asarray(sim.time, float)
    slm = np.asarray(sim.signals["slm"], float)
    u = np.asarray(sim.u_command[:, 0], float)
    band = float(info.band)
    worst = float(np.max(np.abs(slm)))
    ok = worst <= band * (1 + 1e-9)
    switches = int(np.count_nonzero(np.diff(np.sign(slm)) != 0))
    rate = switches / float(t[-1] - t[0])
    tv = float(np.sum(np.abs(np.diff(u))))
    x3 = np.asarray(sim.state[:, 2], float)
    ideal = np.interp(t, info.ideal_t, info.ideal_x3)
    dev = float(np.max(np.abs(x3 - ideal)))
    from designkit.verification.switching import judge_run

    calm, words, physics = judge_run(design, sim, ctx.spec)
    return (
        Check(BAND, ok, f"|slm| <= {band:.4g} rad*s", worst, band - worst, "rad*s",
              f"the largest |slm| over the run is {worst:.4g} rad*s against the band {band:.4g} rad*s: "
              + ("the motor slides" if ok else "it leaves the band: the relay does not hold the motor on slm = 0"),
              {"band": band, "max_abs_slm": worst}),
        Check("pid_sm_elastic_chattering", calm, "switching part within the equivalent control, rate not set by "
              "the step", rate, None, "1/s",
              f"{words}; slm changes sign {switches} times ({rate:.4g} per s); total variation of u {tv:.4g} "
              "[informational]", {"switches": switches, "total_variation_u": tv, "switching": physics},
              required=False),
        Check("pid_sm_elastic_motion", True, "reported", dev, None, "rad",
              f"the load stays within {dev:.4g} rad of its sliding motion x3 = k2 x1/(s² + s/τ2 + k2) at the "
              f"nominal plant (mode {info.load_mode.omega:.4g} rad/s, damping {info.load_mode.zeta:.3g})"
              " [informational]", {"deviation": dev}, required=False),
    )


RELAY_RULE = CheckRule(name=RELAY, order=55, applies=lambda d, c: isinstance(d.data, ElasticSlidingData), run=_relay,
                       label="Relay dominates the equivalent control (elastic joint)")
RUN_RULE = CheckRule(
    name="pid_sm_elastic_run", order=127,
    applies=lambda d, c: (c.simulation is not None and isinstance(d.data, ElasticSlidingData)
                          and "slm" in c.simulation.signals),
    run=_run, label="Sliding mode of the motor in the simulated run (elastic joint)",
    labels={BAND: "The motor stays in the band around slm = 0",
            "pid_sm_elastic_chattering": "Chattering (measured)",
            "pid_sm_elastic_motion": "Load against its sliding motion (measured)"})


def _draw_slm(t: np.ndarray, slm: np.ndarray, band: float) -> Any:
    from designkit.display.figure import plain_ticks
    from designkit.display.svg import BLUE, GREEN, new_figure, plot_decimated, tag

    fig, (ax,) = new_figure(6.8, 3.6)
    tag(fig, "band", ax.fill_between([t[0], t[-1]], -band, band, color=GREEN, alpha=0.2, lw=0,
                                     label=f"band |slm| ≤ {band:.3g} rad·s"))
    tag(fig, "slm", *plot_decimated(ax, t, slm, color=BLUE, lw=1.0, label="slm = a1 x1 + a2 x2 + z (motor)"))
    ax.set_yscale("symlog", linthresh=band, linscale=1.0)
    plain_ticks(ax.yaxis)
    ax.set_xlim(t[0], t[-1])
    ax.set_xlabel("time (s)")
    ax.set_ylabel("slm (rad·s)")
    ax.legend(loc="best", framealpha=0.9)
    return fig


def sliding_variable_figure(result: Any) -> Any:
    """The motor's sliding variable against its band (symmetric-log axis, linear within the band)."""
    from designkit.display.figure import Figure
    from designkit.display.svg import render_tagged

    sim = result.simulation
    if sim is None or not isinstance(result.design.data, ElasticSlidingData):
        return None
    band = float(result.design.data.band)
    svg, keys, _ = render_tagged(_draw_slm, np.asarray(sim.time, float), np.asarray(sim.signals["slm"], float), band)
    drawn = [w for k, w in (("band", "the band (green)"), ("slm", "the motor's sliding variable (blue)")) if k in keys]
    return Figure("PID/sliding mode on the elastic joint: the motor's sliding variable",
                  f"The motor's sliding variable over the run; the axis is linear within ±{band:.3g} rad·s. Drawn: "
                  + " and ".join(drawn) + ".", svg, "fig-pid-sm-elastic-slm.svg", (BAND,))


def _draw_motion(t: np.ndarray, ref: np.ndarray, x: np.ndarray, info: ElasticSlidingData) -> Any:
    from designkit.display.figure import REFERENCE_STYLE
    from designkit.display.svg import BLUE, GREEN, ORANGE, PURPLE, RED, new_figure, plot_decimated, tag

    fig, (ax,) = new_figure(6.8, 4.0)
    tag(fig, "reference", *plot_decimated(ax, t, ref, color=GREEN, **REFERENCE_STYLE, label="reference xD"))
    it = np.asarray(info.ideal_t, float)
    tag(fig, "ideal-motor", ax.plot(it, info.ideal_x1, color=ORANGE, lw=1.6, label="motor on slm = 0: xD/N(s)")[0])
    tag(fig, "motor", *plot_decimated(ax, t, x[:, 0], color=BLUE, lw=1.0, label="motor x1"))
    tag(fig, "ideal-link", ax.plot(it, info.ideal_x3, color=RED, lw=1.6, ls="--",
                                   label="link on slm = 0: k2 x1/(s² + s/τ2 + k2)")[0])
    tag(fig, "link", *plot_decimated(ax, t, x[:, 2], color=PURPLE, lw=1.0, label="link x3"))
    ax.set_xlim(t[0], t[-1])
    ax.set_xlabel("time (s)")
    ax.set_ylabel("position, spring side (rad)")
    ax.legend(loc="best", framealpha=0.9)
    return fig


def motion_figure(result: Any) -> Any:
    """The motor and the link against their motions on ``slm = 0`` at the nominal plant."""
    from designkit.display.figure import Figure
    from designkit.display.svg import render_tagged

    sim = result.simulation
    info = result.design.data
    if sim is None or not isinstance(info, ElasticSlidingData):
        return None
    t = np.asarray(sim.time, float)
    svg, keys, _ = render_tagged(_draw_motion, t, np.asarray(sim.reference[:, 0, 0], float),
                                 np.asarray(sim.state, float), info)
    words = {"reference": "the reference (dash-dot)", "ideal-motor": "the motor's sliding motion (orange)",
             "motor": "the simulated motor (blue)", "ideal-link": "the link's motion on the surface (dashed, red)",
             "link": "the simulated link (purple)"}
    mode = info.load_mode
    return Figure("PID/sliding mode on the elastic joint: motor and link",
                  f"The motor follows its sliding motion; the link hangs on the spring with its own mode "
                  f"({mode.omega:.4g} rad/s, damping {mode.zeta:.3g}). Drawn: "
                  + ", ".join(words[k] for k in keys if k in words) + ".", svg, "fig-pid-sm-elastic-motion.svg",
                  ("pid_sm_elastic_motion",))


def json_summary(result: Any) -> dict[str, Any]:
    """The gains, ``M`` against ``sup|du_eq|``, the load mode on the sliding surface."""
    d = result.design
    info: ElasticSlidingData = d.data
    return {JSON_KEY: {"gains": {k: float(d.gains[k]) for k in info.pid_gains}, "a1": info.a1, "a2": info.a2,
                       "p3": info.p3, "M": info.M, "sup_du_eq": info.sup_du_eq, "band": info.band,
                       "max_step": info.max_step, "rigid": {"Km": info.rigid[0], "tau": info.rigid[1]},
                       "load_mode": info.load_mode.to_json()}}


def extend(family: Any) -> Any:
    """``family`` (the link's) also designing for the elastic joint: synthesis, law, checks and JSON dispatched on
    the plant kind (an elastic design's data is an :class:`ElasticSlidingData`)."""
    base_synth, base_law, base_json = family.synthesize, family.law, family.json

    def synth(spec: Any, plant: Any) -> Design:
        if plant.kind == "elastic_joint":
            from designkit.families.pid_sliding_mode.spec import refuse_chatter_limit

            refuse_chatter_limit(spec, plant.kind)
            return synthesize(spec, plant)
        return base_synth(spec, plant)

    def law_of(design: Design, anti_windup: Any = None) -> Law:
        if isinstance(design.data, ElasticSlidingData):
            return law(design, anti_windup)
        return base_law(design, anti_windup)

    def json_of(result: Any) -> Any:
        if isinstance(result.design.data, ElasticSlidingData):
            return json_summary(result)
        return base_json(result) if base_json is not None else {}

    return dataclasses.replace(family, plants=(*family.plants, "elastic_joint"), synthesize=synth, law=law_of,
                               checks=(*family.checks, RELAY_RULE, RUN_RULE), json=json_of,
                               figures=(*family.figures, sliding_variable_figure, motion_figure))
