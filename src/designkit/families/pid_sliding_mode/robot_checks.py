"""The checks of PID/sliding mode on a robot: the hierarchy's relays certified, and what the run shows per joint.

* ``pid_sm_hierarchy`` (order 55, required): every joint's ``M_i`` above the proven ``sup|xi_i|`` over its box
  (:func:`designkit.models.bounds.perturbation_enclosure`), the bound re-checked by sampling: ``|xi_i|`` evaluated
  with the robot's Newton--Euler inverse dynamics (the enclosure used the inertia matrix and the Christoffel
  symbols) at :data:`RECHECK` random points of each joint's box, none above the bound.
* ``pid_sm_robot_xi`` (order 127, required): wherever the run is inside joint ``i``'s box, ``|xi_i(t)|`` is at most
  the proven bound (and so below ``M_i``), ``xi_i(t) = D^_i q_i'' + f_i q_i' - (u_i - g^_i(q))`` from the run's
  states, commands and accelerations (the robot's forward dynamics at the held command).  How much of the run is
  inside each box, and the ``|xi_i|`` met outside it (e.g. the instant a step reference jumps, when the
  acceleration leaves its box), are reported: the certificate does not speak there.  A run inside a joint's box for
  less than half of its samples leaves the check undecided.
* ``pid_sm_robot_in_band`` (order 127, required): after reaching, ``|slm_i|`` stays in its band (the layer
  ``epsilon``, or what the relay held over a step leaves).
* ``pid_sm_robot_precision`` (informational): ``|q_i - q_i of the sliding motion|`` against ``||s/N||_1 max|slm_i|``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from designkit.families.pid_sliding_mode.data import RobotSlidingData
from designkit.families.pid_sliding_mode.measure import hold_of
from designkit.families.pid_sliding_mode.surface import ideal_motion, surface
from designkit.verification.check import Check
from designkit.verification.suite import CheckRule, Context

__all__ = ["CERTIFICATE_RULE", "RECHECK", "RUN_RULE", "box_words", "in_parameter_box", "parameter_values", "recheck",
           "run_parameters", "run_perturbation", "xi_at"]

RECHECK = 4000
"""Random points per joint of the NumPy re-check of the proven bound."""
MOSTLY_INSIDE = 0.5
"""Below this fraction of its samples inside a joint's box, the run check on xi is undecided."""
HIERARCHY, XI, IN_BAND, PRECISION = ("pid_sm_hierarchy", "pid_sm_robot_xi", "pid_sm_robot_in_band",
                                     "pid_sm_robot_precision")


def _vec(values: Any, fmt: str = "{:.3g}") -> str:
    return "(" + ", ".join(fmt.format(float(v)) for v in values) + ")"


def xi_at(plant: Any, info: RobotSlidingData, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray,
          P: np.ndarray | None = None) -> np.ndarray:
    """``xi`` (N*m, shape (N, n)) at the points ``(q, qd, qdd)`` by Newton--Euler: ``D^_i q_i'' + f_i q_i' - (tau_i
    - g^_i)`` with ``tau`` the inverse dynamics (friction included) of the arm with the parameters ``P`` of each
    point (N, n_p; None: the design's nominal ones) and ``g^`` the fed-forward gravity of the nominal parameters
    (or 0)."""
    from designkit.models.perturbation import evaluate_rows

    robot, p = plant.robot, plant.model_parameters()
    q, qd, qdd = (np.atleast_2d(np.asarray(a, dtype=float)) for a in (q, qd, qdd))
    tau = evaluate_rows(robot, "inverse_dynamics", [q, qd, qdd], P, p).reshape(q.shape)
    if info.gravity_feedforward == "measured":
        tau = tau - robot.gravity_torque(q, p=p).reshape(q.shape)
    Dh = np.array([lk.inertia for lk in info.links])
    f = np.array([lk.damping for lk in info.links])
    return Dh * qdd + f * qd - tau


def parameter_values(info: RobotSlidingData, p: Any) -> dict[str, float]:
    """The uncertain parameters' values (SI units) in a whole parameter vector ``p``, by name."""
    return {row["name"]: float(p[row["index"]]) for row in info.parameter_box}


def recheck(plant: Any, info: RobotSlidingData, points: int = RECHECK, seed: int = 1) -> tuple[np.ndarray, list[dict]]:
    """Per joint the largest ``|xi_i|`` at ``points`` random points of its box (half of them on the velocity,
    acceleration and parameter vertices; the parameters drawn from ``plant.uncertainty``'s box), and where: a NumPy
    re-check of the proven bound."""
    ws = info.workspace
    lo, hi = np.array(ws["low"]), np.array(ws["high"])
    V = np.array(ws["velocity"])
    rows = np.array(info.acceleration_rows)
    box = info.parameter_box
    n = lo.size
    rng = np.random.default_rng(seed)
    best, where = np.zeros(n), []
    for i in range(n):
        q = lo + (hi - lo) * rng.random((points, n))
        qd = V * rng.uniform(-1.0, 1.0, (points, n))
        qdd = rows[i] * rng.uniform(-1.0, 1.0, (points, n))
        half = points // 2
        qd[:half] = V * np.sign(qd[:half])
        qdd[:half] = rows[i] * np.sign(qdd[:half])
        P = None
        if box:
            P = np.tile(np.asarray(plant.model_parameters(), dtype=float), (points, 1))
            u = rng.random((points, len(box)))
            u[:half] = np.round(u[:half])
            for r, row in enumerate(box):
                P[:, row["index"]] = row["low"] + (row["high"] - row["low"]) * u[:, r]
        xi = np.abs(xi_at(plant, info, q, qd, qdd, P)[:, i])
        k = int(np.argmax(xi))
        best[i] = xi[k]
        at = {"q": q[k].tolist(), "qd": qd[k].tolist(), "qdd": qdd[k].tolist()}
        if P is not None:
            at["p"] = P[k].tolist()
        where.append(at)
    return best, where


def _at(info: RobotSlidingData, at: dict) -> str:
    """Where a value is attained, in words and units."""
    s = f"q = {_vec(at['q'])} rad, q̇ = {_vec(at['qd'])} rad/s, q̈ = {_vec(at['qdd'])} rad/s²"
    units = {row["name"]: row["unit"] for row in info.parameter_box}
    if "p" in at:
        s += "".join(f", {k} = {v:.4g} {units[k]}" for k, v in parameter_values(info, at["p"]).items())
    return s


def box_words(info: RobotSlidingData) -> str:
    """The parameter box in words (empty without one)."""
    box = info.parameter_box
    if not box:
        return ""
    return ("the true arm's parameters anywhere in " + ", ".join(
        f"{r['name']} ∈ [{r['low']:.4g}, {r['high']:.4g}] {r['unit']} ({r['meaning']}; nominal {r['nominal']:.4g})"
        for r in box) + ", the controller designed on the nominal values")


def _hierarchy(design: Any, ctx: Context) -> tuple[Check, ...]:
    info: RobotSlidingData = design.data
    M, bound, sampled = (np.array(v) for v in (info.M, info.bound, info.sampled))
    re, re_at = recheck(design.plant, info)
    covered = re <= bound * (1 + 1e-12) + 1e-12
    dominates = bound < M
    ok = bool(np.all(covered) and np.all(dominates))
    parts = []
    for i in range(M.size):
        at = info.enclosure.argmax[i]
        s = (f"joint {i + 1}: M = {M[i]:.4g} N·m against the proven sup|ξ| = {bound[i]:.4g} N·m (attained "
             f"{sampled[i]:.4g} N·m at {_at(info, at)}; re-check by Newton–Euler at {RECHECK} random points: "
             f"largest {re[i]:.4g} N·m)")
        if not dominates[i]:
            s += (f" — M is below the bound by {bound[i] - M[i]:.4g} N·m ({100 * (bound[i] - M[i]) / bound[i]:.3g} %)"
                  + (", and below the attained value: the relay certainly does not dominate ξ there"
                     if M[i] < sampled[i] else "")
                  + f"; M ≥ {bound[i]:.4g} N·m meets the condition, {(1 + info.margin) * bound[i]:.4g} N·m keeps "
                    f"the {100 * info.margin:g} % margin")
        if not covered[i]:
            s += f" — the re-check found {re[i]:.4g} N·m above the proven bound: the enclosure is wrong"
        parts.append(s)
    over = box_words(info)
    enc = info.enclosure
    work = (("over " + over + "; " if over else "")
            + f"{enc.boxes} {'boxes of configurations and parameters' if over else 'configuration boxes'} in "
            f"{enc.seconds:.3g} s (tolerance {enc.rel_tol:g}, work "
            f"limit {enc.max_boxes} boxes per joint; converged: "
            + ", ".join("yes" if c else "no" for c in info.enclosure.converged) + ")")
    cert = {"M": info.M, "bound": info.bound, "sampled": info.sampled, "argmax": info.enclosure.argmax,
            "terms": info.enclosure.terms, "recheck_max": re.tolist(), "recheck_at": re_at, "recheck_points": RECHECK,
            "boxes": info.enclosure.boxes, "seconds": info.enclosure.seconds, "converged": info.enclosure.converged,
            "acceleration_rows": info.acceleration_rows, "workspace": info.workspace,
            "parameter_box": info.parameter_box}
    return (Check(HIERARCHY, ok, "M_i > proven sup|ξ_i| over joint i's box, every joint", float(np.min(M - bound)),
                  float(np.min(M - bound)), "N*m", "; ".join(parts) + ". Bound: " + work + ".", cert),)


CERTIFICATE_RULE = CheckRule(
    name="pid_sm_hierarchy", order=55, applies=lambda d, c: isinstance(d.data, RobotSlidingData), run=_hierarchy,
    label="Hierarchy of control: each relay above its joint's proven perturbation bound",
    labels={HIERARCHY: "Every joint's relay dominates its proven sup|ξ| (workspace, velocity and acceleration box)"},
    glossary=(("ξ_i", "the torque joint i's simplified link leaves out: inertia variation, coupling, Coriolis and "
                      "centrifugal torques, gravity not fed forward, Coulomb friction, N·m"),),
)


def run_parameters(sim: Any, plant: Any) -> np.ndarray | None:
    """The true arm's parameter vector at every sample of the run (N, n_p): ``plant``'s, changed by
    ``simulation.plant_change`` from the sample it applies on; None for a robot without parameters."""
    p = plant.model_parameters()
    if p is None:
        return None
    t = np.asarray(sim.time, dtype=float)
    P = np.tile(np.asarray(p, dtype=float), (t.size, 1))
    change = (getattr(sim, "settings", None) or {}).get("plant_change")
    if change and change.get("time_applied") is not None:
        P[t >= change["time_applied"]] = np.asarray(plant.with_params(**change["values"]).parameter_vector)
    return P


def run_perturbation(design: Any, sim: Any, plant: Any = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(xi, inside, qdd)`` along the run on the true ``plant`` (the design's when None; with
    ``simulation.plant_change`` applied from its sample on): ``xi[k, i]`` (N*m, module docstring), ``inside[k, i]``
    whether sample ``k`` is inside joint ``i``'s box (never where the true parameters are outside the parameter
    box), ``qdd`` the accelerations (rad/s^2) from the true arm's forward dynamics; the gravity feed-forward is the
    design's (nominal parameters)."""
    from designkit.models.perturbation import evaluate_rows

    info: RobotSlidingData = design.data
    true = design.plant if plant is None else plant
    n = true.n_joints
    x = np.asarray(sim.state, dtype=float)
    q, qd = x[:, list(true.positions)], x[:, list(true.velocities)]
    u = np.asarray(sim.u_command, dtype=float)[:, :n]
    P = run_parameters(sim, true)
    p0 = design.plant.model_parameters()
    qdd = evaluate_rows(true.robot, "forward_dynamics", [q, qd, u], P, p0).reshape(q.shape)
    ghat = true.robot.gravity_torque(q, p=p0).reshape(q.shape) if info.gravity_feedforward == "measured" else 0.0
    Dh = np.array([lk.inertia for lk in info.links])
    f = np.array([lk.damping for lk in info.links])
    xi = Dh * qdd + f * qd - (u - ghat)
    ws = info.workspace
    rows = np.array(info.acceleration_rows)
    tol = 1e-9
    state_in = (np.all((q >= np.array(ws["low"]) - tol) & (q <= np.array(ws["high"]) + tol), axis=1)
                & np.all(np.abs(qd) <= np.array(ws["velocity"]) + tol, axis=1))
    if P is not None:
        state_in &= in_parameter_box(info, design.plant, P)
    inside = np.column_stack([state_in & np.all(np.abs(qdd) <= rows[i] + tol, axis=1) for i in range(n)])
    return xi, inside, qdd


def in_parameter_box(info: RobotSlidingData, nominal: Any, params: np.ndarray) -> np.ndarray:
    """Per row of ``params`` (N, n_p), whether those parameters are ones the bound covers: in the parameter box,
    the others at the nominal plant's values."""
    p0 = np.asarray(nominal.model_parameters(), dtype=float)
    lo, hi = p0.copy(), p0.copy()
    for row in info.parameter_box:
        lo[row["index"]], hi[row["index"]] = row["low"], row["high"]
    return np.all((lo <= params) & (params <= hi), axis=1)


def bands(info: RobotSlidingData, hold: float) -> np.ndarray:
    """Per joint the band ``|slm_i| <= band_i`` (rad*s) the run's hold leaves."""
    n = len(info.M)
    if info.epsilon is None:
        return hold * np.array(info.sdot_max)
    if info.layer == "saturation":
        return np.full(n, float(info.epsilon))
    return float(info.epsilon) + hold * np.array(info.sdot_max)


def _arm_words(info: RobotSlidingData, sim: Any, true: Any) -> str:
    """The simulated arm's uncertain parameters in words (empty without a parameter box)."""
    box = info.parameter_box
    P = run_parameters(sim, true)
    if not box or P is None:
        return ""
    change = (getattr(sim, "settings", None) or {}).get("plant_change")
    words = []
    for row in box:
        k, unit = row["index"], row["unit"]
        s = f"{row['name']} = {P[0, k]:.4g} {unit}"
        if P[-1, k] != P[0, k]:
            s += f" until {change['time_applied']:.4g} s, then {P[-1, k]:.4g} {unit}"
        words.append(s)
    return "The simulated arm: " + ", ".join(words) + ". "


def _run(design: Any, ctx: Context) -> tuple[Check, ...]:
    info: RobotSlidingData = design.data
    sim = ctx.simulation
    n = len(info.M)
    M, bound = np.array(info.M), np.array(info.bound)
    true = ctx.true_plant(design)
    xi, inside, qdd = run_perturbation(design, sim, true)
    peak = np.max(np.abs(xi), axis=0)
    peak_in = np.array([np.max(np.abs(xi[inside[:, i], i]), initial=0.0) for i in range(n)])
    frac = inside.mean(axis=0)
    t = np.asarray(sim.time, dtype=float)
    ok_xi: bool | None = bool(np.all(peak_in <= bound * (1 + 1e-9)) and np.all(peak_in < M))
    mostly_out = [i + 1 for i in range(n) if frac[i] < MOSTLY_INSIDE]
    if ok_xi and mostly_out:
        ok_xi = None  # undecided: the certificate does not describe this run
    parts = []
    for i in range(n):
        out = ~inside[:, i]
        s = (f"joint {i + 1}: inside its box for {100 * frac[i]:.4g} % of the samples, largest |ξ| there "
             f"{peak_in[i]:.4g} N·m against the proven bound {bound[i]:.4g} N·m and M = {M[i]:.4g} N·m")
        if out.any():
            k = np.flatnonzero(out)
            s += (f"; outside it ({k.size} samples, {t[k[0]]:.4g} to {t[k[-1]]:.4g} s) |ξ| reaches {peak[i]:.4g} N·m, "
                  "where the certificate does not speak")
        parts.append(s)
    if mostly_out:
        parts.append(f"the run is outside the box of joint{'s' if len(mostly_out) > 1 else ''} "
                     f"{', '.join(map(str, mostly_out))} for more than {100 * (1 - MOSTLY_INSIDE):g} % of its "
                     "samples, so the proven bound does not describe it (e.g. a later joint held still: its sliding "
                     "motion's acceleration is 0, which the boundary layer's approximate sliding never meets)")
    qdd_peak = np.max(np.abs(qdd), axis=0)
    xi_check = Check(XI, ok_xi, "|ξ_i(t)| ≤ proven bound < M_i wherever the run is inside joint i's box",
                     float(np.min(bound - peak_in)), float(np.min(bound - peak_in)), "N*m", _arm_words(info, sim, true)
                     + "; ".join(parts) + f". Largest accelerations of the run {_vec(qdd_peak)} rad/s² (limits "
                     f"{_vec(info.workspace['acceleration'])} rad/s²).",
                     {"peak_xi": peak.tolist(), "peak_xi_inside": peak_in.tolist(), "inside_fraction": frac.tolist(),
                      "peak_acceleration": qdd_peak.tolist()})
    hold = hold_of(sim)
    band = bands(info, hold)
    sf = surface(design.poles)
    ref = np.asarray(sim.reference, dtype=float)
    x = np.asarray(sim.state, dtype=float)
    ok_band, b_parts, worst_all, dev_parts, dev_ok = True, [], [], [], True
    for i in range(n):
        slm = np.asarray(sim.signals[f"slm{i + 1}"], dtype=float)
        idx = np.flatnonzero(np.abs(slm) <= band[i] * (1 + 1e-9))
        if idx.size == 0:
            ok_band = False
            b_parts.append(f"joint {i + 1}: |slm| never entered its band {band[i]:.4g} rad·s")
            worst_all.append(float(np.max(np.abs(slm))))
            continue
        r = int(idx[0])
        worst = float(np.max(np.abs(slm[r:])))
        worst_all.append(worst)
        inside_band = worst <= band[i] * (1 + 1e-9)
        ok_band &= inside_band
        b_parts.append(f"joint {i + 1}: band {band[i]:.4g} rad·s entered after {t[r] - t[0]:.4g} s, largest |slm| "
                       f"after it {worst:.4g} rad·s" + ("" if inside_band else f" ({worst / band[i]:.3g} times the "
                                                                                "band)"))
        qi = x[:, design.plant.positions[i]]
        ideal = ideal_motion(sf, t, ref[:, i, :], info.form, start=float(qi[0]))[0]
        dev = float(np.max(np.abs(qi[r:] - ideal[r:])))
        lim = float(info.l1) * float(np.max(np.abs(slm)))
        dev_ok &= dev <= lim * (1 + 1e-3) + 1e-12
        dev_parts.append(f"joint {i + 1}: {dev:.4g} rad from its sliding motion (bound ‖s/N‖₁ max|slm| = {lim:.4g} "
                         f"rad, ‖s/N‖₁ × band = {float(info.l1) * band[i]:.4g} rad)")
    what = {None: "the band the relays held over a step leave", "saturation": "the boundary layer ε",
            "dead_zone": "the dead zone ε plus one held step"}[None if info.epsilon is None else info.layer]
    margin = float(np.min(band - np.array(worst_all)))
    band_check = Check(IN_BAND, bool(ok_band), f"|slm_i| within {what} after reaching, every joint",
                       float(np.max(worst_all)), margin, "rad*s", "; ".join(b_parts) + ".",
                       {"band": band.tolist(), "worst": worst_all, "hold": hold})
    precision = Check(PRECISION, bool(dev_ok), "|q_i − q_i of the sliding motion| ≤ ‖s/N‖₁ max|slm_i|", None, None,
                      "rad", "; ".join(dev_parts) + " [informational]", {"l1": info.l1}, required=False)
    return xi_check, band_check, precision


RUN_RULE = CheckRule(
    name="pid_sm_robot_run", order=127,
    applies=lambda d, c: (c.simulation is not None and isinstance(d.data, RobotSlidingData)
                          and "slm1" in c.simulation.signals),
    run=_run, label="Sliding mode on every joint of the simulated arm",
    labels={XI: "The perturbation the run meets inside the box stays below the proven bound (every joint)",
            IN_BAND: "Every joint stays in its band around slm_i = 0",
            PRECISION: "Distance of each joint from its sliding motion (measured)"},
    glossary=(("slm_i", "joint i's sliding variable a1 q_i + a2 q̇_i + x3_i, rad·s"),),
)
