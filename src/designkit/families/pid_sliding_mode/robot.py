"""PID/sliding mode on a manipulator: one loop per joint, the relays from the hierarchy of control (notes §5.4).

Joint ``i`` is designed as the one-link controller (package docstring) on its simplified link
``D^_i q_i'' + f_i q_i' = u_i - g^_i(q) + xi_i`` (``Km_i = 1/f_i``, ``tau_i = D^_i/f_i``, ``f_i`` the joint's viscous
friction, ``D^_i`` the middle of ``D_ii``'s sampled range over the workspace), with the gravity feed-forward
``g^_i(q)`` of the model (``gravity_feedforward: measured``) or none -- all three of the *nominal* parameters
``p0`` (the spec's values).  The true arm's parameters ``p`` lie anywhere in the box ``plant.uncertainty`` (``p0``
without one).  Everything else is the perturbation::

    -xi_i = (D_ii(q, p) - D^_i) q_i'' + sum_(j != i) D_ij(q, p) q_j'' + sum_(j,k) Gamma_ijk(q, p) q_j' q_k'
            + (g_i(q, p) - [g_i(q, p0) with the feed-forward]) + (Fv_i(p) - f_i) q_i' + Fc_i(p) sign(q_i')

(the robot's ``M(q) q'' + C(q, q') q' + g(q) + Fv q' + Fc sign(q') = u``, minus the simplified model), and
``slm_i' = p3 slm_i + (a2/D^_i)(du_i + xi_i)`` holds *exactly* on the arm, so ``M_i > sup|xi_i|`` makes
``slm_i slm_i' < 0`` off ``slm_i = 0``.

**The hierarchy of control.**  ``sup|xi_i|`` is proven (:func:`designkit.models.bounds.perturbation_enclosure`)
over the workspace box ``controller.workspace``, the parameter box ``plant.uncertainty``, the velocity limits
``|q_j'| <= plant.limits.velocity[j]`` and an acceleration box of joint ``i``'s own: designing from the last link
to the first, the links after ``i`` are assumed in sliding mode, so their accelerations are those of their sliding
motion (the reference through ``1/(1 + a1 s + a2 s^2)``, or the trajectory itself when tracking), at most its
largest value over the run's reference and at most the acceleration limit; joint ``i`` and the links before it are
bounded by ``plant.limits.acceleration``.  ``M_i = (1 + margin) sup|xi_i|`` (the proven bound) unless ``M`` is
given (the same for every joint).  Whether the run stays in each joint's box, and the ``|xi_i(t)|`` it meets, are
measured (:mod:`~designkit.families.pid_sliding_mode.robot_checks`) on the true arm: the run's plant.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import casadi as ca
import numpy as np

from designkit.errors import ModelError, SpecError
from designkit.families.pid_sliding_mode.data import RobotSlidingData
from designkit.families.pid_sliding_mode.spec import KIND
from designkit.families.pid_sliding_mode.surface import Surface, ideal_motion, l1_norm, surface
from designkit.simulation.reference import reference_for
from designkit.spec.fields import joint_values
from designkit.spec.workspace import workspace_box
from designkit.synthesis import pid
from designkit.synthesis.closed_loop import with_law
from designkit.synthesis.design import Design, Gain, Gains, freeze
from designkit.synthesis.law import Law, State, dynamic_law
from designkit.synthesis.linearization import Linearization

__all__ = ["law", "motion_box", "parameter_box", "sliding_acceleration", "synthesize"]

BAND_FRACTION, LAYER_STEPS, SAT_RESOLUTION = 1e-3, 10.0, 0.2
"""As the one-link design (package module): default switching band, dead-zone and saturation steps."""
GAIN_INFO = {"K1": ("N*m/rad", "proportional"), "K2": ("N*m*s/rad", "derivative (rate feedback)"),
             "K3": ("N*m/(rad*s)", "integral"), "K4": ("s", "reference feedforward (the zero on p3)")}
SAMPLES = 2000
"""Random configurations of the sampled ``D_ii`` range and of the sampled lower bound of ``sup|xi_i|``."""


def motion_box(spec: Any, plant: Any) -> dict[str, Any]:
    """The workspace (rad or m), velocity (rad/s) and acceleration (rad/s^2) limits the hierarchy bounds over.

    Raises
    ------
    SpecError
        ``controller.workspace`` missing (or out of the joint limits, ``low >= high``), ``plant.limits.velocity``
        or ``plant.limits.acceleration`` missing or of the wrong length.
    """
    n = plant.n_joints
    if spec.controller.workspace is None:
        raise SpecError("controller.workspace", "the hierarchy of control bounds xi over a box of configurations: "
                        "give workspace: {low, high} (rad per joint) or workspace: joint_limits")
    ws = workspace_box(spec, plant)
    limits = spec.plant.limits
    out = {"low": list(ws["low"]), "high": list(ws["high"]), "source": ws["source"]}
    for key, unit in (("velocity", "rad/s"), ("acceleration", "rad/s^2")):
        value = getattr(limits, key, None) if limits is not None else None
        if value is None:
            raise SpecError(f"plant.limits.{key}", f"the hierarchy of control bounds xi over the joints' {key} "
                            f"limits: give plant.limits.{key} ({unit}, one value or one per joint)")
        out[key] = list(joint_values(value, n, f"plant.limits.{key}"))
    return out


def sliding_acceleration(sf: Surface, form: str, t: np.ndarray, ref: np.ndarray, start: float) -> float:
    """The largest ``|q''|`` (rad/s^2) of the sliding motion of one joint along its reference ``ref`` (N, 3):
    servo ``q'' = (qD - q - a1 q')/a2`` on ``a2 q'' + a1 q' + q = qD``, tracking ``qD''``."""
    if form == "tracking":
        return float(np.max(np.abs(ref[:, 2])))
    x1, x2, _ = ideal_motion(sf, t, ref, form, start=start)
    return float(np.max(np.abs((ref[:, 0] - x1 - sf.a1 * x2) / sf.a2)))


def _grid(sim: Any, ref: Any, poles: Any) -> np.ndarray:
    slow = min(abs(complex(p).real) for p in poles)
    fast = max(abs(complex(p)) for p in poles)
    T = float(sim.duration) if sim.duration is not None else float(ref.horizon) + 10.0 / slow
    return np.linspace(0.0, T, int(min(40001, max(4001, 50 * fast * T))))


def _coulomb(plant: Any) -> np.ndarray:
    """Each joint's Coulomb friction (N*m) at the nominal parameters."""
    if not plant.robot.friction:
        return np.zeros(plant.n_joints)
    robot = plant.robot
    syms = ca.vertcat(*[s for _, s in robot.description.symbols])
    values = ca.vertcat(*[ca.SX(link.coulomb) for link in robot.description.links])
    f = ca.Function("coulomb", [syms], [values])
    p = plant.model_parameters()
    return np.abs(np.array(f(p if p is not None else ca.DM(0, 1)), dtype=float).reshape(-1))


def parameter_box(spec: Any, plant: Any) -> tuple[tuple[np.ndarray, np.ndarray] | None, list[dict]]:
    """The box of the true arm's parameters from ``plant.uncertainty`` (the others at their nominal values), and
    one row per uncertain parameter: ``name``, ``low``, ``high``, ``nominal``, ``unit``, ``meaning``.  ``(None,
    [])`` without an uncertainty.  The loader has checked the names and each end (a mass below zero is refused at
    ``plant.uncertainty.<name>``)."""
    unc = spec.plant.uncertainty
    if unc is None:
        return None, []
    p0 = np.array(plant.model_parameters(), dtype=float)
    lo, hi = p0.copy(), p0.copy()
    names = plant.parameter_names
    rows = []
    for name, (a, b) in unc.intervals.items():
        k = names.index(name)
        lo[k], hi[k] = a, b
        par = plant.parameter(name)
        rows.append({"name": name, "index": k, "low": float(a), "high": float(b), "nominal": float(p0[k]),
                     "unit": par.unit, "meaning": par.meaning})
    return (lo, hi), rows


def synthesize(spec: Any, plant: Any) -> Design:
    """The per-joint PID/sliding-mode controller with the hierarchy's relay amplitudes (module docstring)."""
    from designkit.models.bounds import perturbation_enclosure
    from designkit.models.link import simplified_link

    ctl, sim = spec.controller, spec.simulation
    n, robot, p = plant.n_joints, plant.robot, plant.model_parameters()
    for key in ("perturbation", "nonlinearity", "delay"):
        if getattr(sim, key, None):
            raise SpecError(f"simulation.{key}", "not supported by pid_sliding_mode on a robot yet: the run's xi is "
                            "computed from the commanded torques on the arm the bound covers")
    if ctl.perturbation_bound is not None:
        raise SpecError("controller.perturbation_bound", "on a robot xi is bounded from the model over the "
                        "workspace box (the hierarchy of control); an external bound is not supported there yet")
    if not robot.friction:
        raise SpecError("plant.friction", "each joint is designed on Km = 1/f (f its viscous friction): set "
                        "plant.friction: true")
    box = motion_box(spec, plant)
    lo, hi = np.array(box["low"]), np.array(box["high"])
    V, A = np.array(box["velocity"]), np.array(box["acceleration"])
    poles = tuple(complex(p_) for p_ in ctl.poles)
    sf = surface(poles)
    form = ctl.form
    rng = np.random.default_rng(0)
    Ds = robot.mass_matrix(lo + (hi - lo) * rng.random((SAMPLES, n)), p=p).reshape(-1, n, n)
    centre = 0.5 * (lo + hi)
    links, gains, d_range = [], [], []
    for i in range(n):
        d_lo, d_hi = float(np.min(Ds[:, i, i])), float(np.max(Ds[:, i, i]))
        try:
            lk = simplified_link(robot, i, centre, p=p)
        except ModelError as exc:
            raise SpecError("plant", f"joint {i + 1}: {exc.message}") from None
        inertia = 0.5 * (d_lo + d_hi)
        link = type(lk)(Km=1.0 / lk.damping, tau=inertia / lk.damping, inertia=inertia, damping=lk.damping)
        links.append(link)
        d_range.append([d_lo, d_hi])
        gains.append(pid.servo_gains(link, poles, sf.p3) if form == "servo" else pid.tracking_gains(link, poles))
    ref_kind = "step" if form == "servo" else "trajectory"
    ref = reference_for(ref_kind, sim, n)
    t = _grid(sim, ref, poles)
    rv = ref.evaluate(t)
    starts = np.asarray(ref.start, dtype=float).reshape(n)
    ahat = np.array([sliding_acceleration(sf, form, t, rv[:, j, :], starts[j]) for j in range(n)])
    rows = np.tile(A, (n, 1))
    for i in range(n):
        rows[i, i + 1:] = np.minimum(A[i + 1:], ahat[i + 1:])
    gravity = ctl.gravity_feedforward == "none"
    Fc = _coulomb(plant)
    p_box, box_rows = parameter_box(spec, plant)
    enc = perturbation_enclosure(
        robot, q=(lo, hi), qd_limit=V, qdd_limits=rows, inertia=[lk.inertia for lk in links],
        damping=[lk.damping for lk in links], coulomb=Fc, gravity=gravity, p=p, p_box=p_box,
        rel_tol=float(ctl.workspace.tolerance), max_boxes=int(ctl.work_limit), samples=SAMPLES)
    upper = np.array(enc.upper)
    m = float(ctl.margin)
    M = np.full(n, float(ctl.M)) if ctl.M is not None else (1.0 + m) * upper
    g = np.array([sf.a2 / lk.inertia for lk in links])
    l1 = l1_norm(sf)
    e_max = np.maximum(np.ptp(rv[:, :, 0], axis=0), np.max(np.abs(rv[:, :, 0] - starts), axis=0))
    strip = g * (M - upper) / abs(sf.p3)
    eps = None if ctl.epsilon is None else float(ctl.epsilon)
    notes = [f"M = {ctl.M:g} N*m given by the spec for every joint (not designed)."] if ctl.M is not None else []
    if eps is None:
        if ctl.switching_band is not None:
            band = np.full(n, float(ctl.switching_band))
        else:
            band = BAND_FRACTION * np.maximum(e_max, 1e-6) / l1
            narrowed = (strip > 0) & (band > strip / 2)
            band = np.where(narrowed, strip / 2, band)
        sdot = abs(sf.p3) * band + g * (M + upper)
        h, discontinuous = float(np.min(band / sdot)), True
    elif ctl.layer == "dead_zone":
        sdot = abs(sf.p3) * eps + g * (M + upper)
        h = float(np.min(eps / (LAYER_STEPS * sdot)))
        discontinuous = True
    else:
        sdot = abs(sf.p3) * eps + g * (M + upper)
        h = float(SAT_RESOLUTION / np.max(abs(sf.p3) + g * M / eps))
        discontinuous = False
    names = ("K1", "K2", "K3", "K4") if form == "servo" else ("K1", "K2", "K3")
    glist = [Gain(k, [float(gj[k]) for gj in gains], *GAIN_INFO[k]) for k in names]
    glist += [Gain("a1", sf.a1, "s", "sliding variable, q coefficient: -(1/p1 + 1/p2)"),
              Gain("a2", sf.a2, "s^2", "sliding variable, q' coefficient: 1/(p1 p2)"),
              Gain("M", M.tolist(), "N*m", "relay amplitude per joint (the hierarchy of control)")]
    data = RobotSlidingData(
        form=form, pid_gains=names, a1=sf.a1, a2=sf.a2, p3=sf.p3,
        gains=tuple({k: float(gj[k]) for k in names} for gj in gains), links=tuple(links),
        inertia_range=tuple(tuple(r) for r in d_range), gravity_feedforward=ctl.gravity_feedforward,
        M=tuple(M.tolist()), M_given=ctl.M is not None, margin=m,
        enclosure=dataclasses.replace(enc, argmax=freeze(tuple(enc.argmax)), terms=freeze(tuple(enc.terms))),
        workspace=box, parameter_box=tuple(box_rows), acceleration_rows=tuple(map(tuple, rows.tolist())),
        sliding_acceleration=tuple(ahat.tolist()), coulomb=tuple(Fc.tolist()), q0=tuple(starts.tolist()),
        epsilon=eps, layer=ctl.layer, sdot_max=tuple(sdot.tolist()), max_step=h, discontinuous=discontinuous, l1=l1)
    formulas = (
        "−ξ_i = (D_ii(q) − D̂_i) q̈_i + Σ_{j≠i} D_ij(q) q̈_j + Σ_jk Γ_ijk(q) q̇_j q̇_k + [g_i(q)] + Fc_i sign(q̇_i)"
        if not box_rows else
        "−ξ_i = (D_ii(q, p) − D̂_i) q̈_i + Σ_{j≠i} D_ij(q, p) q̈_j + Σ_jk Γ_ijk(q, p) q̇_j q̇_k + (g_i(q, p) − ĝ_i(q)) "
        "+ (f_i(p) − f_i) q̇_i + Fc_i(p) sign(q̇_i), p anywhere in the parameter box (ĝ_i = 0 without feed-forward)",
        "slm_i' = p3 slm_i + (a2/D̂_i)(Δu_i + ξ_i) on the arm; M_i = (1 + margin) × proven sup|ξ_i|",
        "hierarchy: joint i's box takes the later joints' accelerations from their sliding motion",
        f"integration step h = {h:.4g} s",
    )
    d = Design(kind=KIND, plant=plant, gains=Gains.of(glist), poles=poles,
               zeros=(complex(sf.p3),) if form == "servo" else (), reference=ref_kind, formulas=formulas,
               notes=tuple(notes), data=data)
    reason = ("the law switches on slm_i = 0 (the relays M_i sign(slm_i)): no linearization describes the loop; "
              "the relay amplitudes are certified over the workspace, velocity and acceleration box"
              + (" and the parameter box" if box_rows else "") + " instead")
    return with_law(d, law(d), Linearization("none", reason=reason))


def law(design: Design, anti_windup: Any = None) -> Law:
    """``u_i = u0_i + du_i (+ g^_i(q))`` per joint, with the integrals ``x3_i' = q_i - qD_i`` (N*m); records
    ``slm<i>`` (rad*s), ``du<i>`` and ``u0<i>`` (N*m)."""
    info: RobotSlidingData = design.data
    plant = design.plant
    n = plant.n_joints
    a1, a2 = info.a1, info.a2
    M, G, links = info.M, info.gains, info.links
    eps, layer, form = info.epsilon, info.layer, info.form
    gravity = plant.robot.functions["gravity_torque"]
    p = plant.model_parameters()

    def g_hat(s: Any) -> Any:
        q = ca.vertcat(*[s.q[i] for i in range(n)])
        return gravity(q, ca.DM(p)) if p is not None else gravity(q)

    def slm(i: int) -> Any:
        def f(s: Any) -> Any:
            if form == "servo":
                return a1 * s.q[i] + a2 * s.qd[i] + s.state(f"x3_{i + 1}")
            return a1 * (s.q[i] - s.qD[i]) + a2 * (s.qd[i] - s.qDd[i]) + s.state(f"x3_{i + 1}")
        return f

    def u0(i: int) -> Any:
        k = G[i]

        def f(s: Any) -> Any:
            e = s.q[i] - s.qD[i]
            if form == "servo":
                return -k["K1"] * e - k["K2"] * s.qd[i] - k["K3"] * s.state(f"x3_{i + 1}") + k["K3"] * k["K4"] * s.qD[i]
            return (links[i].inertia * s.qDdd[i] + links[i].damping * s.qd[i] - k["K1"] * e
                    - k["K2"] * (s.qd[i] - s.qDd[i]) - k["K3"] * s.state(f"x3_{i + 1}"))
        return f

    def du(i: int) -> Any:
        def f(s: Any) -> Any:
            v = slm(i)(s)
            if eps is None:
                return -M[i] * ca.sign(v)
            if layer == "saturation":
                return -M[i] * ca.fmin(ca.fmax(v / eps, -1.0), 1.0)
            return ca.if_else(ca.fabs(v) > eps, -M[i] * ca.sign(v), 0.0)
        return f

    def command(s: Any) -> Any:
        u = ca.vertcat(*[u0(i)(s) + du(i)(s) for i in range(n)])
        return u + g_hat(s) if info.gravity_feedforward == "measured" else u

    def error(i: int) -> Any:
        return lambda s: s.q[i] - s.qD[i]

    q0 = info.q0
    states = [State(f"x3_{i + 1}", error(i), initial=(-a1 * q0[i] if form == "servo" else 0.0), integral=True)
              for i in range(n)]
    signals: dict[str, Any] = {}
    for i in range(n):
        signals[f"slm{i + 1}"] = slm(i)
        signals[f"du{i + 1}"] = du(i)
        signals[f"u0{i + 1}"] = u0(i)
    reason = (f"h = {info.max_step:.4g} s: the relays held over a step move each slm_i by at most h sdot_max_i, "
              "within its band" if info.discontinuous else
              f"h = {info.max_step:.4g} s resolves the boundary layers' rate |p3| + g_i M_i/epsilon")
    return dynamic_law(
        KIND, plant, command=command, states=states,
        settings={"M": list(M), "epsilon": eps, "layer": layer if eps is not None else None, "form": form,
                  "gravity_feedforward": info.gravity_feedforward},
        signals=signals, signal_units=("rad*s", "N*m", "N*m") * n,
        discontinuous=bool(info.discontinuous), max_step=float(info.max_step), max_step_reason=reason,
    )
