"""The feedforward/feedback MRAC as a design: its settings checked, the structure solved, the laws and the frozen
contract (:mod:`designkit.families.mrac.structure`, :mod:`designkit.families.mrac.regressor_law`)."""

from __future__ import annotations

from typing import Any

import numpy as np

from designkit.errors import SpecError
from designkit.families.mrac.data import RegressorData
from designkit.families.mrac.laws import KIND
from designkit.families.mrac.regressor_law import RegressorFreezer, regressor_law
from designkit.families.mrac.structure import Structure, matching, monic, plant_transfer
from designkit.synthesis.closed_loop import with_closed_loop
from designkit.synthesis.design import Design, Gain, Gains
from designkit.synthesis.linearization import Linearization

__all__ = ["design", "law_lines", "synthesize", "validate"]

_COEFFICIENT_ONLY = {
    "poles": "the poles of the PD loop on the link (coefficient form); give the reference_model",
    "nominal": "the link the coefficient form's gains are realised on; the feedforward/feedback structure is "
               "designed on the spec's plant",
    "modification": "a modification of the coefficient form's gradient rule; the feedforward/feedback structure "
                    "chooses its rule with controller.rule",
    "Q": "the coefficient form's weighting of the position and velocity errors; the feedforward/feedback structure's "
         "error is the output's alone",
}


def validate(spec: Any) -> None:
    """Settings of the coefficient form are refused, a reference model is required (``ValueError`` naming the key)."""
    c = spec.controller
    for name, why in _COEFFICIENT_ONLY.items():
        field = type(c).model_fields[name]
        default = field.default_factory() if field.default_factory is not None else field.default
        if name in c.model_fields_set and getattr(c, name) not in (None, default):
            raise ValueError(f"controller.{name}: {why}")
    if c.reference_model is None:
        raise ValueError("controller.reference_model: required by the feedforward_feedback structure (num and den, "
                         "poles, or natural_frequency and damping)")
    if "normalization" in c.model_fields_set and c.rule != "normalized" and c.normalization != 1.0:
        raise ValueError(f"controller.normalization: read by the normalized rule only (controller.rule is {c.rule})")


def _fail(path: str, reason: str) -> SpecError:
    return SpecError(path, reason)


def synthesize(spec: Any, plant: Any) -> Design:
    """The feedforward/feedback MRAC a spec asks for, on the spec's plant at its nominal parameters."""
    c = spec.controller
    if len(plant.inputs) != 1:
        raise _fail("plant.B", f"the plant has {len(plant.inputs)} inputs: the feedforward/feedback structure "
                               "commands one (u = θ'ω)")
    num, den = plant_transfer(plant)
    try:
        kp, Z = monic(num)
    except ValueError:
        raise _fail("plant", "the plant's transfer function from its first input to its first output is zero: "
                             "nothing to control") from None
    _, R = monic(den)
    n, m = len(R) - 1, len(Z) - 1
    if n < 1:
        raise _fail("plant", "the plant has no state: there is nothing for a model-reference controller to adapt")
    if m >= 1 and np.any(np.roots(Z).real >= 0):
        zero = np.roots(Z)[int(np.argmax(np.roots(Z).real))]
        raise _fail("plant", f"the plant has the zero {zero:.4g} on or right of the imaginary axis: the model-matching "
                             "controller cancels the plant's zeros, which must be stable (a minimum-phase plant)")
    mnum, mden = c.reference_model.transfer()
    km, Zm = monic(mnum)
    _, Rm = monic(mden)
    rel, rel_m = n - m, len(Rm) - len(Zm)
    if rel != rel_m:
        raise _fail("controller.reference_model", f"the model's relative degree is {rel_m}, the plant's {rel}: the "
                    "model can be matched only with the plant's relative degree")
    n_lam0 = n - 1 - (len(Zm) - 1)
    if n_lam0 < 0:
        raise _fail("controller.reference_model.num", f"the model has {len(Zm) - 1} zeros, more than the plant's "
                    f"order less one ({n - 1}): the regressor filters cannot contain them")
    if c.filter_poles is not None:
        if len(c.filter_poles) != n_lam0:
            raise _fail("controller.filter_poles", f"must list {n_lam0} poles (the plant's order less one less the "
                        f"model's zeros), got {len(c.filter_poles)}")
        lam0 = np.real(np.poly(np.asarray(c.filter_poles, dtype=complex)))
    else:
        fastest = float(np.max(np.abs(np.roots(Rm))))
        lam0 = np.poly(np.full(n_lam0, -fastest)) if n_lam0 else np.array([1.0])
    theta, lam = matching(num, den, mnum, mden, lam0)
    den_m = np.asarray(mden, dtype=float) / float(mden[0])
    structure = Structure(tuple(float(v) for v in kp * Z / float(monic(den)[0])), tuple(R.tolist()),
                          tuple(float(v) for v in np.asarray(monic(mnum)[1]) * km / float(mden[0])),
                          tuple(den_m.tolist()), tuple(lam.tolist()), theta)
    p = len(theta)
    gamma = [float(v) for v in (c.gamma if isinstance(c.gamma, list) else [c.gamma])]
    if len(gamma) not in (1, p):
        raise _fail("controller.gamma", f"must be one number or {p} (one per adapted parameter "
                                        f"{', '.join(structure.names)}), got {len(gamma)}")
    gamma = gamma * p if len(gamma) == 1 else gamma
    notes = []
    if c.initial is not None:
        if len(c.initial) != p:
            raise _fail("controller.initial", f"must list the {p} adapted parameters {', '.join(structure.names)}, "
                                              f"got {len(c.initial)}")
        initial = tuple(float(v) for v in c.initial)
    else:
        initial = theta
        notes.append("No initial parameters given: the adaptation starts from the ideal parameters of the nominal "
                     "plant (the loop is the model until the plant changes).")
    if c.rule == "lyapunov" and rel > 1:
        notes.append(f"The Lyapunov rule's stability proof needs a strictly positive real model (relative degree 1); "
                     f"this model has relative degree {rel}: no proof holds, the run decides.")
    return design(plant, structure, c.rule, tuple(gamma), initial, float(c.normalization), notes=tuple(notes))


def design(plant: Any, structure: Structure, rule: str, gamma: tuple[float, ...], initial: tuple[float, ...],
           normalization: float = 1.0, *, notes: tuple[str, ...] = ()) -> Design:
    """The feedforward/feedback MRAC on ``plant`` (module docstring), its linear checks on the loop frozen at
    ``initial``.
    """
    gains = Gains.of([Gain(name, value, "", f"ideal value (the nominal loop is the model); starts at {v0:.6g}")
                      for name, value, v0 in zip(structure.names, structure.ideal, initial, strict=True)]
                     + [Gain(f"gamma{k + 1}", g, "", f"adaptation gain of {name}")
                        for k, (name, g) in enumerate(zip(structure.names, gamma, strict=True))])
    data = RegressorData(structure=structure, rule=rule, gamma=tuple(gamma), initial=tuple(initial),
                         normalization=normalization)
    # no requested poles: the loop's poles follow from the initial parameters, nothing is placed (so the
    # ``pole_placement`` check, which judges requested poles and a unit static gain, does not apply)
    d = Design(kind=KIND, plant=plant, gains=gains, poles=(), reference="step",
               formulas=law_lines(data), notes=notes, data=data)
    adaptive = regressor_law(plant, structure, rule, gamma, initial, normalization)
    lin = Linearization("frozen", reason="u = θᵀω with the parameters held (no adaptation, no reference model or "
                        "sensitivity filter)", parameters=structure.names, initial=tuple(initial),
                        units=("",) * len(initial), freeze=RegressorFreezer(plant, structure))
    return with_closed_loop(d, adaptive, [0.0, 0.0, 0.0], field="controller.initial", linearization=lin)


def law_lines(data: RegressorData) -> tuple[str, ...]:
    """The law in words (the report's law lines and the design's formulas)."""
    n = data.structure.order
    omega = "ω = (uc, −y)" if n == 1 else "ω = (uc, −y, −(α/Λ) y, −(α/Λ) u),  α = (s^(n−2), …, 1)"
    rule = {"mit": "θ' = −γ sign(kp/km) e φ,  φ = Gm(p)/Gm(0) ω  (MIT rule, filtered-signal sensitivity)",
            "lyapunov": "θ' = −γ sign(kp/km) e ω  (Lyapunov rule)",
            "normalized": "θ' = −γ sign(kp/km) e φ/(α0 + φᵀφ),  φ = Gm(p)/Gm(0) ω  (normalized MIT rule)"}[data.rule]
    return (f"u = θᵀω,  {omega}", "ym = Gm(p) uc  (reference model),  e = y − ym", rule)
