"""Linear state regulator by pole placement (ROBEL, figure 5.2): the ``state_regulator`` family.

Plant ``x' = A x + B u + D d``: the elastic joint (``x = [R1 theta_m, R1 theta_m', R2 theta_l, R2 theta_l']``,
spring-side coordinates, the load position ``x3`` controlled), the link (``[x1, x2]``), or any single-input
``transfer_function`` or ``state_space`` plant (its first output controlled, :mod:`designkit.models.linear_plant`),
linearised at rest by CasADi from the plant's own ODE.  The law reads the full state: there is no observer.  Law::

    u = -K x + N xD,      K = e P(A) (Ackermann),      N = -1 / (C (A - B K)^-1 B)

(:mod:`~designkit.synthesis.pole_placement`, :mod:`~designkit.families.state_regulator.gains`).  The loop has no
controller state, so its closed loop is ``A - B K`` with exactly the requested poles; the generic checks judge it:
``pole_placement`` (poles, no finite zero of ``x3/xD``, unit DC gain), ``lyapunov``, ``loop_margins`` (the loop broken
at the plant input: ``L(s) = K (sI - A)^-1 B``), ``robustness`` over ``plant.uncertainty``, ``designed_loop`` and
``time_domain``.
Without integral action a constant load ``w`` leaves the offset ``-C (A - B K)^-1 D w`` (in ``--json``).
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from designkit.errors import SpecError
from designkit.families.state_regulator import answers
from designkit.families.state_regulator.data import StateRegulatorData
from designkit.families.state_regulator.gains import load_offset, reference_gain
from designkit.families.state_regulator.observer import closed_loop_zeros, design_observer, observer_states
from designkit.families.state_regulator.spec import KIND, StateRegulatorSpec, validate
from designkit.synthesis.closed_loop import with_closed_loop
from designkit.synthesis.design import Design, Gain, Gains
from designkit.synthesis.family import Display, Family, PlantField
from designkit.synthesis.knobs import Knob
from designkit.synthesis.law import Law, dynamic_law
from designkit.synthesis.linear_servo import plant_zeros
from designkit.synthesis.pole_placement import place
from designkit.synthesis.state_space import check_controllable, linear_model

__all__ = ["FAMILY", "KIND", "StateRegulatorSpec", "law", "synthesize"]


def _box(spec: Any, model: Any) -> dict[str, tuple[float, float]]:
    unc = spec.plant.uncertainty
    return {k: (float(lo), float(hi)) for k, (lo, hi) in (unc.intervals.items() if unc is not None else ())
            if k in model.names}


def synthesize(spec: Any, plant: Any) -> Design:
    """The regulator a spec asks for: ``K`` from ``controller.poles`` on the nominal plant, ``N`` for a unit
    static gain of the controlled position."""
    model = linear_model(plant)
    check_controllable(spec, model, _box(spec, model))
    A, B, D = model.at()
    poles = tuple(complex(p) for p in spec.controller.poles)
    try:
        K = place(A, B, poles)  # m x n: Ackermann for one input, robust placement for several
    except ValueError as exc:
        raise SpecError("controller.poles", str(exc)) from None
    m = K.shape[0]
    position = int(plant.positions[0])
    obs = None
    if getattr(spec.controller, "observer_poles", None) is not None:
        obs = design_observer(plant, A, B, [complex(p) for p in spec.controller.observer_poles])
    N = reference_gain(A, B, K, position)
    offset = load_offset(A, B, D, K, position) if D.shape[1] else 0.0
    units = [s.unit for s in plant.states]
    gains = []
    for j in range(m):
        u_unit = plant.inputs[j].unit
        on = f" to {plant.inputs[j].name}" if m > 1 else ""
        gains += [Gain(f"K{i + 1}" if m == 1 else f"K{j + 1}_{i + 1}", float(K[j, i]), f"{u_unit}/({units[i]})",
                       f"state feedback on {plant.states[i].name}{on}") for i in range(K.shape[1])]
        gains.append(Gain("N" if m == 1 else f"N{j + 1}", float(np.ravel(N)[j]), f"{u_unit}/({units[position]})",
                          "reference gain (unit static gain)" if m == 1 else
                          f"reference gain to {plant.inputs[j].name} (least-norm unit static gain)"))
    open_loop = np.linalg.eigvals(A)
    d_unit = plant.disturbances[0].unit if plant.disturbances else ""
    data = StateRegulatorData(K=tuple(K[0].tolist()) if m == 1 else tuple(tuple(row) for row in K.tolist()),
                              observer=obs,
                              N=N if m == 1 else tuple(float(v) for v in N),
                              open_loop_poles=tuple(complex(p) for p in open_loop),
                              position_index=position, load_offset_per_unit=offset,
                              load_offset_unit=f"{units[position]} per {d_unit}")
    notes: tuple[str, ...] = ()
    if obs is not None:
        Lm = np.asarray(obs.L)
        gains += [Gain(f"L{i + 1}_{j + 1}", float(Lm[i, j]), f"({units[i]})/(({plant.outputs[j].unit})*s)",
                       f"observer gain from output {plant.outputs[j].name} to {plant.states[i].name}")
                  for j in range(Lm.shape[1]) for i in range(Lm.shape[0])]
        notes = (f"The regulator feeds back the estimate x̂ of a Luenberger observer reading the outputs "
                 f"{', '.join(obs.outputs)}: x̂' = A x̂ + B u + L (y − C x̂), L placing the observer poles; the loop "
                 "has the poles of A − BK and of A − LC (separation), the latter cancelled in y/xD.",)
    elif plant.kind in ("transfer_function", "state_space"):
        names = ", ".join(s.name for s in plant.states)
        notes = (f"The regulator measures the full state ({names}) of the plant realised in "
                 f"{plant.realisation.form}: no observer estimates it.",)
    formulas = (
        "u = −K x + N xD; K = e P(A) (Ackermann), e the last row of [B AB … A^(n−1)B]^−1, P(s) = Π (s − p_j)"
        if m == 1 else "u = −K x + N xD; K places the poles by the robust method of Kautsky, Nichols and Van Dooren "
        "(scipy.signal.place_poles)",
        f"N = −1/(C (A − BK)^−1 B) = {N:.6g} (unit static gain of the controlled position)" if m == 1 else
        "N = −gᵀ/(g gᵀ), g = C (A − BK)^−1 B: the least-norm N giving the controlled position a unit static gain",
        f"a constant load w leaves x − xD = −C (A − BK)^−1 D w = {offset:.4g} {units[position]} per {d_unit} "
        "(no integral action)",
    )
    # the zeros of x/xD in the closed loop (with one input, the plant's own: state feedback does not move them)
    zeros = plant_zeros(A - B @ K, B @ np.ravel(N), np.eye(A.shape[0])[position])
    if obs is not None:
        zeros = closed_loop_zeros(obs, K, np.ravel(N), position)
        formulas = (*formulas, "L = Kₒᵀ, Kₒ placing eig(Aᵀ − Cᵀ Kₒ) at the observer poles (duality)")
        poles = (*poles, *obs.poles)
    d = Design(kind=KIND, plant=plant, gains=Gains.of(gains), poles=poles, zeros=zeros, reference="step",
               formulas=formulas, notes=notes, data=data)
    return with_closed_loop(d, law(d), [0.0, 0.0, 0.0], field="controller.poles")


def law(design: Design, anti_windup: Any = None) -> Law:
    """``u = -K x + N xD`` (input units); records nothing of its own (no state, no switching)."""
    info: StateRegulatorData = design.data
    n = len(design.plant.states)
    K, N = np.asarray(info.K, float).reshape(-1, n), np.ravel(np.asarray(info.N, float))
    if info.observer is not None:
        states, command = observer_states(info.observer, K, N, [s.name for s in design.plant.states])
        return dynamic_law(KIND, design.plant, command=command, states=states,
                           settings={"gains": design.gains.to_json()})
    return dynamic_law(KIND, design.plant, command=lambda s: -ca.mtimes(ca.DM(K), s.y) + ca.DM(N) * s.qD[0],
                       settings={"gains": design.gains.to_json()})


def json_summary(result: Any) -> dict[str, Any]:
    """A ``state_regulator`` object: ``K``, ``N``, the requested and open-loop poles (``[re, im]`` in 1/s) and the
    load offset per unit load."""
    info: StateRegulatorData = result.design.data
    return {KIND: {"K": [list(k) if isinstance(k, tuple) else k for k in info.K],
                   "N": list(info.N) if isinstance(info.N, tuple) else info.N,
                   "poles": [[p.real, p.imag] for p in result.design.poles],
                   "open_loop_poles": [[p.real, p.imag] for p in info.open_loop_poles],
                   "load_offset_per_unit": info.load_offset_per_unit, "load_offset_unit": info.load_offset_unit}}


def law_lines(design: Design) -> tuple[str, ...]:
    """The law with an observer (``()``: the family's own, on the measured state)."""
    info = design.data
    if getattr(info, "observer", None) is None:
        return ()
    return ("u = −K x̂ + N xD", "x̂' = A x̂ + B u + L (y − C x̂): K places eig(A − BK), L places eig(A − LC)")


def loop_line(design: Design) -> str | None:
    """With an observer the loop at the plant input is the observer-based compensator's: no closed form is written
    (``""``); without one the family's own (None)."""
    return "" if getattr(design.data, "observer", None) is not None else None


FAMILY = Family(
    kind=KIND,
    spec=StateRegulatorSpec,
    plants=("elastic_joint", "link", "transfer_function", "state_space"),
    uses=("plant.uncertainty", "plant.uncertainty.grid", "plant.uncertainty.samples"),
    reference="step",
    synthesize=synthesize,
    law=law,
    checks=("pole_placement", "lyapunov", "robustness", "loop_margins", "designed_loop", "time_domain"),
    display=Display(
        label="Linear state regulator (pole placement)",
        law=("u = −K x + N xD", "K = e P(A) places the n requested poles (Ackermann); N gives unit static gain"),
        loop_transfer="L(s) = K (sI − A)^−1 B",
        law_of=law_lines,
        loop_transfer_of=loop_line,
        summary="ROBEL figure 5.2: a state feedback places every closed-loop pole of the plant (on the elastic "
                "joint its motor and link positions and speeds; on a linear plant its realised states, measured or "
                "estimated by an observer); the reference gain makes the controlled position settle on the "
                "reference without load. No integral action: a load torque leaves an offset.",
    ),
    validate=validate,
    json=json_summary,
    plant_fields=(PlantField("observer_poles", ("transfer_function", "state_space"),
                             "a Luenberger observer of the state from the plant's outputs y = C x"),),
    knobs=(Knob("poles", "1/s", "closed-loop poles of x' = (A − B K) x: the regulator's speed", 1e-3, 1e6,
                path="controller.poles"),),
    traits=("state_feedback",),
    answers=answers.ANSWERS,
    predictions=answers.PREDICTIONS,
)
