"""Variable structure control by theorem 3 of the notes (section 5.2; ROBEL's figure 5.3): the ``vsc`` family.

Plant ``x' = A(p) x + B(p) u + D(p) d`` (the link, or the elastic joint in ``[theta_m, theta_m', theta_l,
theta_l']`` spring-side coordinates), regulated about the rest state at the reference ``x*(xD)``; with the error
state ``x~ = x - x*(xD)``::

    sigma = c x~,     u = sum_i psi_i x~_i - delta sign(sigma),     psi_i = alpha_i if x~_i sigma > 0, else beta_i

**Sign convention** (figure 5.3's, used throughout): ``alpha_i`` where ``x~_i sigma > 0``, ``beta_i`` where
``x~_i sigma < 0``; with ``cB > 0`` the reaching condition is ``alpha_i < l_i < beta_i``
(:mod:`~designkit.families.vsc.gains`).  Theorem 3 as printed puts ``alpha_i`` on ``x_i sigma < 0``; with that
labelling the same derivation gives ``alpha_i > l_i > beta_i`` (docs/notes-errata.md).

**c** from the ``n - 1`` sliding poles by the Ackermann formula of :mod:`~designkit.families.vsc.surface`,
normalised so that the coefficient of the driven state (``x2``) is 1.  On the elastic joint (``mgl = 0``,
``k2 = KR R2^2/J2``) this is figure 5.3's closed form ``c1 = -(p1 + p2 + p3) - 1/tau2``, ``c2 = 1``,
``c3 = -p1 p2 p3/k2 - c1``, ``c4 = (p1 p2 + p1 p3 + p2 p3)/k2 - 1 - c1/(tau2 k2)`` (the notes print ``c2``
for ``tau2`` in the last term).

**Gains** ``l_i = -(cA)_i/(cB)``: figure 5.3's ``l1 = (tau1/Km)(KR R1^2/J1 - c4 KR R2^2/J2)``,
``l2 = (tau1/Km)(1/tau1 - c1)``, ``l3 = (tau1/Km)(c4 KR R2^2/J2 - KR R1^2/J1)``, ``l4 = (tau1/Km)(c4/tau2 - c3)``
(correct as printed, with ``E`` read as ``B``).  On the link (``c = [c1, 1]``): ``l1 = 0``,
``l2 = (1 - c1 tau)/Km``.

**Integration step.**  The law is discontinuous: the simulator holds its command over each step ``h``, which
moves ``sigma`` by at most ``h S(x~)`` (:mod:`~designkit.families.vsc.measure`).  ``h`` is chosen so that the
first held step at the initial error moves ``sigma`` by at most the band (``chattering_band``, default
``BAND_FRACTION |sigma(0)|``); with a boundary layer, a tenth of it.

**Boundary layer.**  ``psi_i x~_i = m_i x~_i + h_i |x~_i| sign(sigma)`` with ``m_i = (alpha_i + beta_i)/2`` and
``h_i = (alpha_i - beta_i)/2 < 0`` (``psi_i = alpha_i`` exactly when ``x~_i`` and ``sigma`` have one sign), so the
law is ``u = sum m_i x~_i + (sum h_i |x~_i| - delta) sign(sigma)``: one switch.  ``boundary_layer: epsilon``
replaces it by ``sat(sigma/epsilon)``: the law is then continuous (not held over the step); outside the layer it is
the switching law, so the layer is reached and kept (``|sigma| <= epsilon``), and inside it the motion on the
surface is perturbed by ``|sigma| <= epsilon``: at rest the controlled position is off by at most
``|g_sigma| epsilon`` (``g_sigma`` the static gain from ``sigma`` to it on the reduced system) beyond the offset an
unmatched disturbance leaves.  Step ``h = epsilon/(10 S0)``: the layer's gain ``cB (sum |h_i x~_i| + delta)/epsilon``
times ``h`` stays below 0.1.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from designkit.errors import SpecError
from designkit.families.vsc import answers
from designkit.families.vsc.checks import CERTIFICATE_RULE, RUN_RULE
from designkit.families.vsc.data import CornerPoles, VscData
from designkit.families.vsc.diagnoses import diagnose
from designkit.families.vsc.figures import FIGURES
from designkit.families.vsc.gains import LINEAR, bound_ranges, design_gains, rational_forms
from designkit.families.vsc.report import json_summary, section
from designkit.families.vsc.spec import KIND, VscSpec, perturbation_level, validate
from designkit.families.vsc.surface import drive_index, reduced_poles, sliding_surface
from designkit.synthesis.closed_loop import with_law
from designkit.synthesis.design import Design, Gain, Gains
from designkit.synthesis.family import Display, Family
from designkit.synthesis.knobs import COMMAND_VARIATION, SETTLED_ERROR, Knob
from designkit.synthesis.law import Law, dynamic_law
from designkit.synthesis.linearization import Linearization
from designkit.synthesis.state_space import check_controllable, linear_model

__all__ = ["FAMILY", "KIND", "VscSpec", "law", "synthesize"]

BAND_FRACTION = 0.05
"""Default band: the first held step at the initial error moves ``sigma`` by at most this fraction of
``|sigma(0)|``."""
LAYER_STEPS = 10.0
MAX_STEP = 1e-3
"""Largest step (s) whatever the band: the sliding poles' and the plant's time scales are integrated."""
REASON = ("the law switches on sigma = 0 (the relay) and on every x_i sigma = 0 (psi_i between alpha_i and beta_i), "
          "where it spends its life: it has no derivative there, so no linearization describes the loop; theorem 3's "
          "conditions are certified on the parameter box instead")


def design_box(spec: Any, model: Any) -> dict[str, tuple[float, float]]:
    """``plant.uncertainty`` widened to hold the nominal plant and ``simulation.plant_change``'s values (so that
    the certificate covers every plant the run meets); ``{"Km": (nominal, nominal)}`` without either."""
    unc = spec.plant.uncertainty
    intervals = dict(unc.intervals) if unc is not None else {}
    change = spec.simulation.plant_change
    changed = {k: float(v) for k, v in (change.values.items() if change is not None else ())}
    box = {}
    for name in model.names:
        nominal = float(model.nominal[model.names.index(name)])
        if name in intervals or name in changed:
            lo, hi = intervals.get(name, (nominal, nominal))
            values = [lo, hi, nominal] + ([changed[name]] if name in changed else [])
            box[name] = (min(values), max(values))
    if not box and model.names:
        first = "Km" if "Km" in model.names else model.names[0]
        box[first] = (float(model.nominal[model.names.index(first)]),) * 2
    if box.get("mgl", (0.0, 0.0))[1] > 0:
        raise SpecError("plant.uncertainty.mgl", "the regulator is designed for mgl = 0 (no gravity)")
    if box.get("tau2", (1.0, 1.0))[1] == float("inf"):
        raise SpecError("plant.uncertainty.tau2", "must be finite")
    return box


def _surface(spec: Any, model: Any, box: dict) -> np.ndarray:
    A, B, _ = model.at()
    poles = [complex(p) for p in spec.controller.sliding_poles]
    check_controllable(spec, model, box, "no sliding surface places the poles")  # every plant of the box too
    return sliding_surface(A, B, poles)


def linear_rest(plant: Any, A: np.ndarray, B: np.ndarray) -> tuple[np.ndarray, float]:
    """``(x*, u*)`` with ``A x* + B u* = 0`` and ``C1 x* = 1``: the nominal linear plant at rest per unit of
    reference (state units per output unit, input unit per output unit).

    Raises
    ------
    SpecError
        At ``plant``: a plant with a zero at ``s = 0`` (no input holds its output at a nonzero rest).
    """
    n = A.shape[0]
    c = np.eye(n)[plant.positions[0]]
    K = np.block([[A, B.reshape(n, 1)], [c[None, :], np.zeros((1, 1))]])
    if abs(np.linalg.det(K)) <= 1e-12 * max(float(np.prod(np.linalg.norm(K, axis=1))), 1e-300):
        raise SpecError("plant", "the plant has a zero at s = 0 (or A and B leave no rest at y = xD): no input holds "
                        "its output at a constant reference, so there is no rest state to regulate to")
    sol = np.linalg.solve(K, np.concatenate([np.zeros(n), [1.0]]))
    return sol[:n], float(sol[n])


def synthesize(spec: Any, plant: Any) -> Design:
    """The regulator a spec asks for (package docstring): ``c``, the box's ``l_i`` ranges, the gains, the law."""
    ctl, sim = spec.controller, spec.simulation
    model = linear_model(plant)
    box = design_box(spec, model)
    c = _surface(spec, model, box)
    A, B, D = model.at()
    n = len(c)
    step = sim.step if not isinstance(sim.step, list | tuple) else sim.step[0]
    amp = float(step) if sim.trajectory is None else 2.0 * float(np.max(np.abs(sim.trajectory.amplitude)))
    q0 = sim.initial_position if not isinstance(sim.initial_position, list | tuple) else sim.initial_position[0]
    x_max = abs(float(q0 or 0.0)) + abs(amp)
    if plant.kind in LINEAR:
        x_rest, u_rest = linear_rest(plant, A, B)
        rest_forms = (x_rest, u_rest)
    else:
        x_rest = np.asarray(plant.rest_state(1.0), float) - np.asarray(plant.rest_state(0.0), float)
        u_rest, rest_forms = 0.0, None
    forms = rational_forms(plant.kind, c, model, rest_forms, x_max)
    bounds = bound_ranges(forms, model, box)
    rho = max(abs(complex(p)) for p in ctl.sliding_poles)
    cB_nom = float(c @ B.ravel())
    m = float(ctl.margin)
    al, be, S = design_gains(bounds, c, rho, cB_nom, m, ctl.alpha, ctl.beta)
    level = perturbation_level(sim)
    d_bar = float(ctl.perturbation_bound if ctl.perturbation_bound is not None else (level or 0.0))
    ratio = bounds["cD/cB"]
    r_max = max(abs(ratio.lower), abs(ratio.upper))
    mismatch = bounds.get("rest")
    w_max = max(abs(mismatch.lower), abs(mismatch.upper)) if mismatch is not None else 0.0
    delta = (float(ctl.relay_amplitude) if ctl.relay_amplitude is not None else
             (1.0 + m) * (d_bar * r_max + w_max))
    notes = []
    if ctl.relay_amplitude is None:
        src = "controller.perturbation_bound" if ctl.perturbation_bound is not None else "simulation.perturbation"
        notes.append(f"delta = (1 + {m:g}) x ({d_bar:g} x sup|cD/cB| + {w_max:.4g}) = {delta:.4g} (perturbation "
                     f"bound from {src}; {w_max:.4g}: the largest share of sigma' over cB a plant of the box leaves "
                     f"at the nominal rest, |xD| <= {x_max:g})." if mismatch is not None else
                     f"delta = (1 + {m:g}) x {d_bar:g} x sup|cD/cB| = {delta:.4g} (perturbation bound from {src}).")
    if plant.kind in LINEAR and u_rest != 0.0:
        notes.append(f"The nominal plant rests at y = xD with x* = [{', '.join(f'{v:.4g}' for v in x_rest)}] xD and "
                     f"u* = {u_rest:.4g} xD: the law feeds u* xD forward and regulates x - x* xD.")
    given = [k for k in ("alpha", "beta", "relay_amplitude") if getattr(ctl, k) is not None]
    if given:
        notes.append(f"Given by the spec (not designed): {', '.join(given)}.")
    rest = np.asarray(x_rest, float)
    x0 = -abs(amp) * rest
    G = np.array([max(bounds[f"l_{i + 1}"].upper - al[i], be[i] - bounds[f"l_{i + 1}"].lower) for i in range(n)])
    cB_max = bounds["cB"].upper
    cD_max = r_max * cB_max
    S0 = cB_max * (np.abs(x0) @ G + delta + w_max) + cD_max * d_bar
    sigma0 = abs(float(c @ x0))
    eps = ctl.boundary_layer
    if eps is not None:
        band, h = float(eps), float(eps) / (LAYER_STEPS * S0)
    else:
        band = float(ctl.chattering_band) if ctl.chattering_band is not None else BAND_FRACTION * sigma0
        h = band / S0
    h = min(h, MAX_STEP)
    k = drive_index(B)
    cA = c @ A
    state_units = [s.unit for s in plant.states]
    u_unit = plant.inputs[0].unit
    gains = [Gain(f"c{i + 1}", float(c[i]), f"({state_units[k] if k is not None else ''})/({state_units[i]})",
                  "sliding surface coefficient") for i in range(n)]
    gains += [Gain(f"alpha{i + 1}", al[i], f"{u_unit}/({state_units[i]})", f"switching gain where x{i + 1} sigma > 0")
              for i in range(n)]
    gains += [Gain(f"beta{i + 1}", be[i], f"{u_unit}/({state_units[i]})", f"switching gain where x{i + 1} sigma < 0")
              for i in range(n)]
    gains.append(Gain("delta", delta, u_unit, "relay amplitude"))
    position = int(plant.positions[0])
    import itertools

    names = list(box)
    vertex_poles = []
    for v in itertools.product(*[sorted(set(box[nm])) for nm in names]):
        Av, Bv, _ = model.at(dict(zip(names, v, strict=True)))
        vertex_poles.append(CornerPoles(dict(zip(names, v, strict=True)),
                                        tuple(complex(z) for z in reduced_poles(Av, Bv, c))))
    data = VscData(
        c=tuple(c.tolist()), alpha=tuple(al), beta=tuple(be), delta=delta, margin=m, S=tuple(S),
        box={kk: tuple(v) for kk, v in box.items()}, d_bar=d_bar, bounds=bounds, G=tuple(G.tolist()),
        cB_max=cB_max, cD_max=cD_max, cB_nominal=cB_nom, cA_nominal=tuple(cA.tolist()),
        rest_direction=tuple(rest.tolist()), position_index=position, band=band, max_step=h, S0=float(S0),
        boundary_layer=eps, plant_kind=plant.kind, nominal_model=(A, B, D), drive_index=k,
        vertex_poles=tuple(vertex_poles), u_rest=float(u_rest), reference_max=float(x_max))
    formulas = (
        "σ = c x̃ with c from the sliding poles (Ackermann: c = e P(A), e = last row of [B AB … A^(n−1)B]^−1), "
        "normalised c_drive = 1",
        "l_i = −(cA)_i/(cB); reaching: α_i < l_i < β_i on the whole box and δ > sup|cD/cB| d̄",
        f"α_i = min l_i − {m:g} S_i, β_i = max l_i + {m:g} S_i; δ = (1 + {m:g}) d̄ sup|cD/cB| unless given",
        f"h = {'ε/(10 S0)' if eps is not None else 'band/S0'} = {h:.4g} s (S0 = {S0:.4g}: the largest |σ'| at the "
        "initial error over the box)",
    )
    d = Design(kind=KIND, plant=plant, gains=Gains.of(gains),
               poles=tuple(complex(p) for p in ctl.sliding_poles), reference="step", formulas=formulas,
               notes=tuple(notes), data=data)
    return with_law(d, law(d), Linearization("none", reason=REASON))


def law(design: Design, anti_windup: Any = None) -> Law:
    """``u = sum_i psi_i x~_i - delta sign(sigma)``, held over each step of at most ``max_step``; with a boundary
    layer the continuous ``u = sum_i m_i x~_i + (sum_i h_i |x~_i| - delta) sat(sigma/epsilon)``, ``m_i = (alpha_i +
    beta_i)/2``, ``h_i = (alpha_i - beta_i)/2`` (the same law outside the layer: ``psi_i x_i = m_i x_i +
    h_i |x_i| sign(sigma)``).  Records ``sigma`` and ``u_eq = -(cB)^-1 c A x~`` (nominal model, no perturbation)."""
    data: VscData = design.data
    c, al, be = (np.asarray(v, float) for v in (data.c, data.alpha, data.beta))
    delta, eps = float(data.delta), data.boundary_layer
    rest = np.asarray(data.rest_direction, float)
    cA, cB = np.asarray(data.cA_nominal, float), float(data.cB_nominal)

    def error(s: Any) -> Any:
        return s.y - ca.DM(rest) * s.qD[0]

    def sigma(s: Any) -> Any:
        return ca.dot(ca.DM(c), error(s))

    mid, half = (al + be) / 2.0, (al - be) / 2.0

    u_rest = float(data.u_rest)

    def command(s: Any) -> Any:
        return u_rest * s.qD[0] + switching(s)

    def switching(s: Any) -> Any:
        x, sg = error(s), sigma(s)
        if eps is None:
            u = 0
            for i in range(len(c)):
                u = u + ca.if_else(x[i] * sg > 0, al[i], be[i]) * x[i]
            return u - delta * ca.sign(sg)
        # psi_i x_i = mid_i x_i + half_i |x_i| sign(sigma) (psi_i = alpha_i iff sign(x_i) = sign(sigma)), so
        # u = sum mid_i x_i + (sum half_i |x_i| - delta) sign(sigma): the layer replaces this one sign(sigma)
        gap = 0
        for i in range(len(c)):
            gap = gap + half[i] * ca.fabs(x[i])
        return ca.dot(ca.DM(mid), x) + (gap - delta) * ca.fmin(ca.fmax(sg / eps, -1.0), 1.0)

    def u_eq(s: Any) -> Any:
        return u_rest * s.qD[0] - ca.dot(ca.DM(cA), error(s)) / cB

    reason = (f"the command is held over each step; h = {data.max_step:.4g} s moves sigma by at most "
              f"{'a tenth of the boundary layer' if eps is not None else 'the band'} ({data.band:.4g}) at the "
              f"initial error (largest |sigma'| there over the box {data.S0:.4g})")
    unit = design.plant.states[data.drive_index].unit if data.drive_index is not None else ""
    return dynamic_law(
        KIND, design.plant, command=command,
        settings={"gains": design.gains.to_json(), "boundary_layer": eps, "band": data.band},
        signals={"sigma": sigma, "u_eq": u_eq}, signal_units=(unit, design.plant.inputs[0].unit),
        discontinuous=eps is None, max_step=float(data.max_step), max_step_reason=reason,
    )


FAMILY = Family(
    kind=KIND,
    spec=VscSpec,
    plants=("link", "elastic_joint", *LINEAR),
    uses=("plant.uncertainty",),
    reference="step",
    references=("step", "square", "prbs"),
    synthesize=synthesize,
    law=law,
    checks=(CERTIFICATE_RULE, RUN_RULE, "time_domain"),
    display=Display(
        label="Variable structure state regulator (theorem 3)",
        law=("σ = c (x − x*(xD)), c from the sliding poles", "u = Σ ψ_i x̃_i − δ sign(σ)",
             "ψ_i = α_i where x̃_i σ > 0 and β_i where x̃_i σ < 0; sat(σ/ε) replaces sign(σ) with a boundary layer"),
        summary="Notes §5.2, theorem 3 (ROBEL, figure 5.3): a switching state feedback drives the state onto the "
                "surface σ = c x̃ = 0, whose sliding motion has the requested poles; the gains bracket the "
                "equivalent-control gains l_i on the whole parameter box, certified there.",
    ),
    validate=validate,
    figures=FIGURES,
    sections=(section,),
    diagnoses=(diagnose,),
    json=json_summary,
    knobs=(Knob("relay_amplitude", "input", "relay amplitude δ of the switching term", 1e-6, 1e6,
                path="controller.relay_amplitude", role="switching", boundary=True,
                current=lambda d: float(d.gains["delta"])),
           Knob("sliding_poles", "1/s", "poles of the sliding motion on σ = c x = 0", 1e-3, 1e6,
                path="controller.sliding_poles"),
           Knob("margin", "", "relative margin of the designed gains on every condition", 1e-3, 10,
                path="controller.margin"),
           Knob("chattering_band", "rad/s", "band |σ| ≤ band the command held over one step may leave (sets the "
                "step)", 1e-12, 1e6, path="controller.chattering_band", current=lambda d: float(d.data.band),
                when=lambda d: d.data.boundary_layer is None)),
    traits=("switching", "state_feedback"),
    metrics=(SETTLED_ERROR, COMMAND_VARIATION),
    answers=answers.ANSWERS,
    predictions=answers.PREDICTIONS,
)
