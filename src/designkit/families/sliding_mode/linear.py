"""The sliding-mode servo of a single-input linear plant (``transfer_function``, ``state_space``).

Plant ``x' = A(p) x + B(p) (u + xi)``, ``y = C1 x``, ``|xi| <= xi_bar``, the parameters ``p`` in the box of
``plant.uncertainty``.  With the nominal plant's rest ``A x* + B u* = 0``, ``C1 x* = 1`` (per unit of reference) and
``x~ = x - x* xD``::

    s = c x~,     u = u* xD + u_eq0(x~) - K(x~) sign(s),     u_eq0 = -(c A0 x~)/(c B0),     K = k0 + sum_i k_i |x~_i|

**Surface.**  ``c`` from the ``n - 1`` sliding poles by Ackermann's formula on the nominal ``(A0, B0)``
(``c = e P(A0)``, ``e`` the last row of the inverse controllability matrix;
:func:`~designkit.synthesis.pole_placement.ackermann_row`), scaled to ``c B0 = 1``: on ``s = 0`` the motion under the
equivalent control has those poles (on the nominal plant; on another plant of the box the reduced system's poles
are listed per corner).

**Equivalent control** from the nominal model: ``u_eq0`` makes ``s' = 0`` on the nominal plant without
perturbation.  On a plant of the box::

    s' = g(p) x~ - c B(p) K(x~) sign(s) + c B(p) xi + w(p) xD,
    g(p) = c A(p) - (c B(p)/c B0) c A0,      w(p) = c (A(p) x* + B(p) u*)

(``g = 0`` and ``w = 0`` on the nominal plant).  With ``c B > 0`` on the box::

    s s' <= |s| (sum_i (|g_i| - c B k_i) |x~_i| - c B (k0 - xi_bar) + |w| X),     X = max |xD|

**Switching gain from the box.**  ``k_i >= sup |g_i / cB|`` and ``k0 > xi_bar + sup |w X / cB|`` give
``s s' <= -eta |s|`` everywhere, ``eta = min_box (cB (k0 - xi_bar) - |w| X) > 0``: the sliding mode exists on
``s = 0`` and is reached from every state within ``|s(0)|/eta`` (the reaching and sliding conditions).  The design
takes ``k_i = (1 + m) sup |g_i/cB|`` and ``k0 = (1 + m)(xi_bar + sup |w X/cB|)`` (``m`` the spec's margin) unless
``M`` gives ``k0``; the suprema are proven ranges over the box (:func:`designkit.bounds.enclose`: ball arithmetic,
branch and bound), and so is the certificate (:mod:`~designkit.families.sliding_mode.linear_checks`).

**Integration step.**  The command is held over each step ``h``; a step moves ``s`` by at most ``h S(x~)`` with
``S(x~) = sum_i a_i |x~_i| + S_c``, ``a_i = sup|(cA)_i| + cB_max (|c A0_i|/cB0 + k_i)``, ``S_c = cB_max (k0 + xi_bar)
+ sup|w| X``.  ``h = band / S(x~0)`` (``x~0`` the first error, ``band`` the spec's ``chattering_band`` or
``BAND_FRACTION |s(0)|``), at most ``MAX_STEP``; with a boundary layer ``epsilon`` (``sat(s/epsilon)``)
``h = epsilon / (10 S(x~0))``.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from designkit.errors import SpecError
from designkit.synthesis.closed_loop import with_law
from designkit.synthesis.design import Design, FamilyData, Gain, Gains
from designkit.synthesis.law import Law, dynamic_law
from designkit.synthesis.linearization import Linearization
from designkit.synthesis.pole_placement import ackermann_row
from designkit.synthesis.state_space import check_controllable, linear_model

__all__ = ["LINEAR", "LinearSlidingData", "linear_law", "linear_synthesize", "proven_range"]

LINEAR = ("transfer_function", "state_space")
"""The plant kinds this module designs for."""
BAND_FRACTION = 0.05
"""Default band: the first held step at the initial error moves ``s`` by at most this fraction of ``|s(0)|``."""
MAX_STEP = 1e-3
"""Largest step (s) whatever the band."""
LAYER_STEPS = 10.0
ENCLOSE_TOL = 1e-6
REASON = ("the law switches on s = 0 (the relay K(x) sign(s)), where it spends its life: it has no derivative there, "
          "so no linearization describes the loop; its reaching and sliding conditions are certified on the parameter "
          "box instead")


@dataclass(frozen=True)
class LinearSlidingData(FamilyData):
    """What the law, checks and figures read of a sliding-mode design on a linear plant (module docstring).

    Attributes
    ----------
    c : tuple of float
        The surface ``s = c x~``, scaled to ``c B0 = 1`` (so ``s'`` has the input's unit and ``s`` the input's unit
        times s).
    poles : tuple of complex
        The requested sliding poles (1/s).
    x_rest : tuple of float
        ``x*``: the nominal rest per unit of reference (state units per output unit).
    u_rest : float
        ``u*``: the input holding it (input unit per output unit).
    cA0 : tuple of float
        ``c A0`` (``s``'s unit per second per state unit); ``cB0`` its input row, 1.
    k : tuple of float
        The state-proportional switching gains ``k_i`` (input unit per state unit).
    k0 : float
        The constant switching gain (input unit).
    xi_bar : float
        ``sup |xi|`` (input unit).
    margin : float
        The design's relative margin.
    box : dict of str to (float, float)
        The parameter box certified.
    reference_max : float
        ``X``: the largest ``|xD|`` of the run (output unit).
    g_sup : tuple of float
        Proven ``sup |g_i/cB|`` over the box (input unit per state unit).
    w_sup : float
        Proven ``sup |w X/cB|`` over the box (input unit).
    cB_range : (float, float)
        Proven range of ``c B`` over the box.
    cA_sup : tuple of float
        Proven ``sup |(cA)_i|`` over the box.
    band : float
        The band (``s``'s unit) one held step may leave, or the boundary layer's width.
    boundary_layer : float or None
        ``epsilon`` of ``sat(s/epsilon)``, or None.
    max_step : float
        The integration step (s).
    S0 : float
        ``S(x~0)``: the largest ``|s'|`` at the first error over the box.
    corner_poles : tuple of tuple
        ``(corner, poles)``: the sliding motion's poles at each corner of the box.
    """

    c: tuple[float, ...]
    poles: tuple[complex, ...]
    x_rest: tuple[float, ...]
    u_rest: float
    cA0: tuple[float, ...]
    k: tuple[float, ...]
    k0: float
    xi_bar: float
    margin: float
    box: dict[str, tuple[float, float]]
    reference_max: float
    g_sup: tuple[float, ...]
    w_sup: float
    cB_range: tuple[float, float]
    cA_sup: tuple[float, ...]
    band: float
    boundary_layer: float | None
    max_step: float
    S0: float
    corner_poles: tuple[tuple[dict[str, float], tuple[complex, ...]], ...]

    def rate_bound(self, x: np.ndarray) -> np.ndarray:
        """``S(x~)`` (module docstring) at each row of ``x`` (error states)."""
        cb_max = self.cB_range[1]
        a = np.asarray(self.cA_sup) + cb_max * (np.abs(self.cA0) + np.asarray(self.k))
        const = cb_max * (self.k0 + self.xi_bar) + self.w_sup * cb_max
        return np.abs(np.atleast_2d(x)) @ a + const


def proven_range(expr: ca.SX, model: Any, box: dict[str, tuple[float, float]]) -> tuple[float, float]:
    """The proven range of ``expr`` (in the plant parameters ``model.p``) over ``box`` (the other parameters at
    their nominal values): its value when it does not depend on the box, else :func:`designkit.bounds.enclose`."""
    from designkit.bounds import enclose

    names = [n for n in model.names if n in box]
    theta = ca.vertcat(*[ca.SX.sym(n) for n in names]) if names else ca.SX(0, 1)
    full = [theta[names.index(n)] if n in names else float(model.nominal[i]) for i, n in enumerate(model.names)]
    e = ca.substitute(ca.SX(expr), model.p, ca.vertcat(*full)) if model.names else ca.SX(expr)
    if not names or not ca.depends_on(e, theta):
        v = float(ca.evalf(ca.substitute(e, theta, ca.DM.zeros(theta.numel())))) if names else float(ca.evalf(e))
        return v, v
    f = ca.Function("f", [theta], [e], ["p"], ["o"])
    lo = np.array([box[n][0] for n in names], float)
    hi = np.array([box[n][1] for n in names], float)
    if np.all(lo == hi):
        v = float(f(lo))
        return v, v
    enc = enclose(f, {"p": (lo, hi)}, rel_tol=ENCLOSE_TOL)
    return float(enc.lower), float(enc.upper)


def _box(spec: Any, model: Any) -> dict[str, tuple[float, float]]:
    unc = spec.plant.uncertainty
    intervals = dict(unc.intervals) if unc is not None else {}
    change = spec.simulation.plant_change
    changed = {k: float(v) for k, v in (change.values.items() if change is not None else ())}
    box = {}
    for i, name in enumerate(model.names):
        if name in intervals or name in changed:
            nominal = float(model.nominal[i])
            lo, hi = intervals.get(name, (nominal, nominal))
            values = [lo, hi, nominal] + ([changed[name]] if name in changed else [])
            box[name] = (min(values), max(values))
    return box


def _rest(A: np.ndarray, B: np.ndarray, c1: np.ndarray) -> tuple[np.ndarray, float]:
    n = A.shape[0]
    K = np.block([[A, B.reshape(n, 1)], [c1[None, :], np.zeros((1, 1))]])
    if abs(np.linalg.det(K)) <= 1e-12 * max(float(np.prod(np.linalg.norm(K, axis=1))), 1e-300):
        raise SpecError("plant", "the plant has a zero at s = 0: no input holds its output at a constant reference, "
                        "so there is no rest to slide to")
    sol = np.linalg.solve(K, np.concatenate([np.zeros(n), [1.0]]))
    return sol[:n], float(sol[n])


def _reduced_poles(A: np.ndarray, B: np.ndarray, c: np.ndarray) -> np.ndarray:
    n = A.shape[0]
    N = np.linalg.svd(c.reshape(1, n))[2][1:].T
    proj = np.eye(n) - np.outer(B, c) / float(c @ B)
    eig = np.linalg.eigvals(N.T @ proj @ A @ N)
    return eig[np.lexsort((eig.imag, eig.real))]


def linear_synthesize(spec: Any, plant: Any, kind: str) -> Design:
    """The sliding-mode servo of a linear plant (module docstring).

    Raises
    ------
    SpecError
        At ``controller.sliding_poles`` (not ``n - 1`` of them), ``plant.num`` / ``plant.B`` (uncontrollable, at
        the nominal plant or a corner), ``plant`` (no rest), ``controller.M`` (below the proven bound is allowed:
        the certificate judges it).
    """
    ctl, sim = spec.controller, spec.simulation
    if len(plant.inputs) != 1:
        raise SpecError("plant.B", f"the sliding-mode servo drives a single-input plant; this one has "
                        f"{len(plant.inputs)} inputs")
    model = linear_model(plant)
    A0, B0, _ = model.at()
    n = A0.shape[0]
    b0 = B0[:, 0]
    poles = [complex(p) for p in ctl.sliding_poles]
    if len(poles) != n - 1:
        raise SpecError("controller.sliding_poles", f"the {plant.kind} plant has {n} states, so the motion on s = 0 "
                        f"has {n - 1} poles; got {len(poles)}")
    box = _box(spec, model)
    check_controllable(spec, model, box, "no sliding surface places the poles")
    c = ackermann_row(A0, b0, poles)
    c = c / float(c @ b0)
    c1 = np.eye(n)[plant.positions[0]]
    x_rest, u_rest = _rest(A0, b0, c1)
    cv = ca.DM(c).T
    cA, cB = cv @ model.A, (cv @ model.B)[0, 0]
    cA0 = c @ A0
    g = cA - cB * ca.DM(cA0).T  # cB0 = 1
    step = sim.step if not isinstance(sim.step, list | tuple) else sim.step[0]
    amp = float(step) if sim.trajectory is None else 2.0 * float(np.max(np.abs(sim.trajectory.amplitude)))
    q0 = sim.initial_position if not isinstance(sim.initial_position, list | tuple) else sim.initial_position[0]
    X = abs(float(q0 or 0.0)) + abs(amp)
    w = (cv @ (model.A @ ca.DM(x_rest) + model.B * u_rest))[0, 0] * X
    cb_lo, cb_hi = proven_range(cB, model, box)
    if cb_lo <= 0:
        raise SpecError("plant.uncertainty", f"c B ranges over [{cb_lo:.4g}, {cb_hi:.4g}] on the box: the input's "
                        "direction on the surface changes sign (or may), so no switching gain turns s' against s")
    g_sup = tuple(max(abs(v) for v in proven_range(g[0, i] / cB, model, box)) for i in range(n))
    w_sup = max(abs(v) for v in proven_range(w / cB, model, box))
    cA_sup = tuple(max(abs(v) for v in proven_range(cA[0, i], model, box)) for i in range(n))
    m = float(ctl.margin)
    xi_bar = float(ctl.perturbation_bound if ctl.perturbation_bound is not None else
                   max(abs(float(v)) for v in (sim.perturbation.value if isinstance(sim.perturbation.value,
                                                                                    list | tuple)
                                               else [sim.perturbation.value])))
    k = tuple((1.0 + m) * s for s in g_sup)
    k0 = float(ctl.M) if ctl.M is not None else (1.0 + m) * (xi_bar + w_sup)
    x0 = -abs(amp) * x_rest
    S0 = float(np.abs(x0) @ (np.asarray(cA_sup) + cb_hi * (np.abs(cA0) + np.asarray(k)))
               + cb_hi * (k0 + xi_bar) + w_sup * cb_hi)
    eps = ctl.boundary_layer
    if eps is not None:
        band, h = float(eps), float(eps) / (LAYER_STEPS * S0)
    else:
        band = float(ctl.chattering_band) if ctl.chattering_band is not None else BAND_FRACTION * abs(float(c @ x0))
        h = band / S0
    h = min(h, MAX_STEP)
    names = list(box)
    corners = []
    for v in itertools.product(*[sorted({box[nm][0], box[nm][1]}) for nm in names]):
        at = dict(zip(names, v, strict=True))
        Av, Bv, _ = model.at(at)
        corners.append((at, tuple(complex(z) for z in _reduced_poles(Av, Bv[:, 0], c))))
    data = LinearSlidingData(
        c=tuple(float(v) for v in c), poles=tuple(poles), x_rest=tuple(float(v) for v in x_rest), u_rest=u_rest,
        cA0=tuple(float(v) for v in cA0), k=k, k0=k0, xi_bar=xi_bar, margin=m, box=box, reference_max=X,
        g_sup=g_sup, w_sup=w_sup, cB_range=(cb_lo, cb_hi), cA_sup=cA_sup, band=band, boundary_layer=eps,
        max_step=h, S0=S0, corner_poles=tuple(corners))
    u_unit = plant.inputs[0].unit
    units = [s.unit for s in plant.states]
    gains = [Gain(f"c{i + 1}", float(c[i]), f"({u_unit}*s)/({units[i]})" if units[i] else "",
                  "sliding surface coefficient (c B0 = 1)") for i in range(n)]
    gains += [Gain(f"k{i + 1}", k[i], f"{u_unit}/({units[i]})", "switching gain on |x~_i|") for i in range(n)]
    gains.append(Gain("M", k0, u_unit, "constant switching gain k0"))
    notes = [f"Proven over the box: sup|g_i/cB| = {', '.join(f'{v:.4g}' for v in g_sup)}, sup|w X/cB| = "
             f"{w_sup:.4g} (X = {X:g}), cB in [{cb_lo:.6g}, {cb_hi:.6g}]."]
    if u_rest != 0.0:
        notes.append(f"The nominal plant rests at y = xD with x* = [{', '.join(f'{v:.4g}' for v in x_rest)}] xD and "
                     f"u* = {u_rest:.4g} xD: the law feeds u* xD forward and slides on c (x - x* xD) = 0.")
    if ctl.perturbation_bound is None:
        notes.append(f"sup |xi| = {xi_bar:g} taken from simulation.perturbation.value.")
    if ctl.M is not None:
        notes.append(f"Given by the spec (not designed): M = k0 = {k0:g}.")
    formulas = (
        "s = c (x − x* xD),  c = e P(A0) / (e P(A0) B0) (Ackermann on the sliding poles),  A0 x* + B0 u* = 0, "
        "C1 x* = 1",
        "u = u* xD − (c A0 x̃)/(c B0) − (k0 + Σ k_i |x̃_i|) sign(s)",
        "reaching and sliding: k_i ≥ sup|g_i/cB|, k0 > ξ̄ + sup|w X/cB|, cB > 0 on the box, g = cA − (cB/cB0) cA0, "
        "w = c (A x* + B u*)",
        f"gains: k_i = (1 + {m:g}) sup|g_i/cB|, k0 = (1 + {m:g})(ξ̄ + sup|w X/cB|);  h = "
        f"{'ε/(10 S0)' if eps is not None else 'band/S0'} = {h:.4g} s (S0 = {S0:.4g})",
    )
    d = Design(kind=kind, plant=plant, gains=Gains.of(gains), poles=tuple(poles), reference="step",
               formulas=formulas, notes=tuple(notes), data=data)
    return with_law(d, linear_law(d), Linearization("none", reason=REASON))


def linear_law(design: Design, anti_windup: Any = None) -> Law:
    """``u = u* xD - (c A0 x~)/(c B0) - (k0 + sum k_i |x~_i|) sign(s)`` (or ``sat(s/epsilon)``), held over each step
    of at most ``max_step`` when it switches; records ``s``."""
    data: LinearSlidingData = design.data
    c, rest, cA0, k = (np.asarray(v, float) for v in (data.c, data.x_rest, data.cA0, data.k))
    k0, eps, u_rest = float(data.k0), data.boundary_layer, float(data.u_rest)

    def error(s: Any) -> Any:
        return s.y - ca.DM(rest) * s.qD[0]

    def sliding(s: Any) -> Any:
        return ca.dot(ca.DM(c), error(s))

    def command(s: Any) -> Any:
        x = error(s)
        gain = k0 + ca.dot(ca.DM(k), ca.fabs(x))
        relay = ca.sign(sliding(s)) if eps is None else ca.fmin(ca.fmax(sliding(s) / eps, -1.0), 1.0)
        return u_rest * s.qD[0] - ca.dot(ca.DM(cA0), x) - gain * relay

    reason = (f"the command is held over each step; h = {data.max_step:.4g} s moves s by at most "
              f"{'a tenth of the boundary layer' if eps is not None else 'the band'} ({data.band:.4g}) at the first "
              f"error (largest |s'| there over the box {data.S0:.4g})")
    return dynamic_law(
        design.kind, design.plant, command=command,
        settings={"gains": design.gains.to_json(), "boundary_layer": eps, "band": data.band},
        signals={"s": sliding}, signal_units=(f"{design.plant.inputs[0].unit}*s",),
        discontinuous=eps is None, max_step=float(data.max_step), max_step_reason=reason,
    )
