"""The robot form's design: the spec read against the arm (names, gains per joint, the adaptation gains' default)
and the :class:`~designkit.synthesis.design.Design` of the identifier.

**Default adaptation gains.**  Along the reference itself (``q = qD``, ``qd = qD'``, ``qdd = qD''``: the motion the
servo is asked to follow; the regressor does not depend on the parameters being identified) the two-point
information matrix ``Phi(t) = Y(t)' Y(t) + Y(t - D)' Y(t - D)`` is computed every sample over the run; ``Gamma``
is its mean's inverse diagonal (each parameter's rate balanced), scaled so that the sampled step
``Ts lambda_max(Gamma^1/2 Phi Gamma^1/2)`` peaks at :data:`DEFAULT_STEP` along it (below 2 the sampled update
cannot increase ``V``; the run's own step is checked).  A square wave or a PRBS is at rest between its jumps:
along it the inertial columns vanish, so the gains must then be given.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from designkit.errors import SpecError
from designkit.families.sliding_mode_identification.arm import base_of, parameter_unit, regressor_symbols
from designkit.families.sliding_mode_identification.arm_law import ArmIdentifier, arm_identifier_law
from designkit.families.sliding_mode_identification.data import ArmIdentifierData
from designkit.families.sliding_mode_identification.laws import KIND
from designkit.families.sliding_mode_identification.spec import LINK_REFERENCES
from designkit.simulation.reference import reference_for
from designkit.spec.fields import per_joint
from designkit.synthesis.closed_loop import with_law
from designkit.synthesis.design import Design, Gain, Gains
from designkit.synthesis.law import Law
from designkit.synthesis.linearization import Linearization

__all__ = ["DEFAULT_STEP", "LAW", "arm_law", "gain_unit", "law_lines", "regressor_rows", "synthesize_arm"]

DEFAULT_STEP = 0.5
"""The peak sampled step ``Ts lambda_max(Gamma^1/2 Phi Gamma^1/2)`` the default gains give along the reference."""
MAX_WINDOW_SAMPLES = 2000
"""Longest window ``D`` in sampling periods (the shift registers' length)."""
REASON = ("the identifier is a sampled switching observer per joint with shift registers of the signals D seconds ago "
          "in discrete memory: it has no continuous linearization; its own checks judge it")


def regressor_rows(Wb: Any, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
    """``Wb`` at ``N`` states (arrays ``(N, n)``): ``(N, n, b)``."""
    N, n = q.shape
    if N == 0:
        return np.zeros((0, n, Wb.size2_out(0)))
    out = np.asarray(Wb.map(N)(q.T, qd.T, qdd.T), dtype=float)  # n x (b N), blocks per state
    return out.reshape(n, N, -1).transpose(1, 0, 2)


_GAIN_UNITS = {"kg": "kg^2/(N^2*m^2*s)", "kg*m": "kg^2/(N^2*s)", "kg*m^2": "kg^2*m^2/(N^2*s)",
               "N*m*s/rad": "s/rad^2", "N*m": "1/s"}


def gain_unit(unit: str) -> str:
    """The unit of an adaptation gain for a parameter in ``unit``: ``unit^2/((N*m)^2 s)`` simplified (``theta^' =
    Gamma Y' eps``, ``eps`` in N*m and ``Y theta`` in N*m).

    Examples
    --------
    >>> gain_unit("kg*m^2"), gain_unit("N*m*s/rad"), gain_unit("N*m")
    ('kg^2*m^2/(N^2*s)', 's/rad^2', '1/s')
    """
    return _GAIN_UNITS.get(unit, f"({unit})^2/(N^2*m^2*s)" if unit else "1/(N^2*m^2*s)")


def _joints(value: Any, n: int, key: str) -> tuple[float, ...]:
    try:
        return per_joint(value, n, key)
    except ValueError as exc:
        path, msg = str(exc).split(": ", 1)
        raise SpecError(path, msg) from None


def _reference_kind(spec: Any) -> str:
    traj = spec.simulation.trajectory
    return "step" if traj is None or traj.kind in LINK_REFERENCES else "trajectory"


def _default_gains(spec: Any, Wb: Any, cols: list[int], names: tuple[str, ...], n: int, N: int,
                   Ts: float) -> tuple[np.ndarray, float, float]:
    """``(gamma, peak step, slowest rate 1/s)`` along the reference (module docstring)."""
    sim = spec.simulation
    ref = reference_for(_reference_kind(spec), sim, n)
    duration = float(sim.duration) if sim.duration is not None else float(ref.horizon)
    t = np.arange(0.0, duration + 0.5 * Ts, Ts)
    r = ref.evaluate(t)
    Y = regressor_rows(Wb, r[:, :, 0], r[:, :, 1], r[:, :, 2])[:, :, cols]
    if len(t) <= N:
        raise SpecError("controller.window", f"D = {N * Ts:g} s is longer than the run ({duration:g} s)")
    Ybar = np.concatenate([Y[N:], Y[:-N]], axis=1)  # (K, 2n, p)
    G = np.einsum("kip,kiq->pq", Ybar, Ybar) / len(Ybar)
    diag = np.diag(G)
    scale = max(float(diag.max()), 1e-300)
    quiet = [x for x, g in zip(names, diag, strict=True) if g <= 1e-12 * scale]
    if quiet:
        if _reference_kind(spec) == "step":
            what, fix = "a square wave or a PRBS is at rest between its jumps", "drive the arm along a multisine"
        else:
            what, fix = "its regressor column vanishes along the reference", "move every joint along the reference"
        raise SpecError("controller.adaptation_gains", f"no default for {', '.join(quiet)}: {what}; give the gains "
                        f"(one per identified parameter), or {fix}")
    gamma = 1.0 / diag
    lam = np.linalg.eigvalsh(np.einsum("kip,p,kjp->kij", Ybar, gamma, Ybar))[:, -1]
    c = DEFAULT_STEP / (Ts * float(lam.max()))
    gamma = c * gamma
    root = np.sqrt(gamma)
    rate = float(np.linalg.eigvalsh(root[:, None] * G * root[None, :])[0])
    return gamma, DEFAULT_STEP, rate


def _gains(spec: Any, names: tuple[str, ...], defaults: Any) -> tuple[tuple[float, ...], str]:
    given = spec.controller.adaptation_gains
    if given is None:
        gamma, step, rate = defaults()
        return tuple(float(g) for g in gamma), (
            f"Adaptation gains not given: the inverse diagonal of the two-point information matrix along the "
            f"reference, scaled to a peak sampled step Ts λmax(Γ½ Φ Γ½) = {step:g} along it; there the slowest "
            f"direction converges at {rate:.3g} 1/s.")
    if isinstance(given, list):
        if len(given) != len(names):
            raise SpecError("controller.adaptation_gains", f"needs one gain per identified parameter ({len(names)}: "
                            f"{', '.join(names)}), got {len(given)}")
        return tuple(float(g) for g in given), "Adaptation gains given by the spec."
    for name in given:
        if name not in names:
            raise SpecError(f"controller.adaptation_gains.{name}", f"not an identified parameter (identified: "
                            f"{', '.join(names)})")
    missing = [x for x in names if x not in given]
    if missing:
        raise SpecError("controller.adaptation_gains", f"no gain for {', '.join(missing)}: name every identified "
                        "parameter, or leave the gains out for the default")
    return tuple(float(given[x]) for x in names), "Adaptation gains given by the spec."


def synthesize_arm(spec: Any, plant: Any) -> Design:
    """The identifier a spec asks for on the robot ``plant`` (module docstring)."""
    cs = spec.controller
    n = plant.n_joints
    base = base_of(plant)
    every = tuple(base.names)
    names = tuple(cs.identify) if cs.identify is not None else every
    for k, x in enumerate(names):
        if x not in every:
            raise SpecError(f"controller.identify[{k}]", f"the arm has no base parameter {x!r}; its base parameters "
                            f"are {', '.join(every)}")
    initial = dict(cs.initial_estimates or {})
    for x in initial:
        if x not in names:
            raise SpecError(f"controller.initial_estimates.{x}", f"not an identified parameter (identified: "
                            f"{', '.join(names)})")
    Ts, window = float(cs.sampling_period), float(cs.window)
    if not Ts <= window <= MAX_WINDOW_SAMPLES * Ts:
        raise SpecError("controller.window", f"must be between one and {MAX_WINDOW_SAMPLES} sampling periods "
                        f"({Ts:g} s to {MAX_WINDOW_SAMPLES * Ts:g} s: the signals D seconds ago are kept in shift "
                        f"registers of D/Ts samples), got {window:g}")
    change = spec.simulation.plant_change
    if change is not None:
        fixed = regressor_symbols(plant)
        for x in change.values:
            if x in fixed:
                raise SpecError(f"simulation.plant_change.values.{x}", f"{x} enters the regressor (the arm's "
                                "kinematics or gravity), which the identifier holds fixed; change a mass, an "
                                "inertia or a friction")
    K1 = _joints(cs.servo.K1, n, "controller.servo.K1")
    K2 = _joints(cs.servo.K2, n, "controller.servo.K2")
    switching = _joints(cs.switching_gain, n, "controller.switching_gain")
    q0 = _joints(spec.simulation.initial_position if spec.simulation.initial_position is not None else 0.0, n,
                 "simulation.initial_position")
    cols = [every.index(x) for x in names]
    known = tuple((k, float(base.beta[k])) for k in range(len(every)) if k not in cols)
    N = max(1, int(round(window / Ts)))
    gamma, how = _gains(spec, names, lambda: _default_gains(spec, base.W_base, cols, names, n, N, Ts))
    ident = ArmIdentifier(K1=K1, K2=K2, switching=switching, window=window, Ts=Ts, names=names, columns=tuple(cols),
                          known=known, gamma=gamma, initial=tuple(float(initial.get(x, 0.0)) for x in names),
                          start=q0)
    return arm_design(spec, plant, ident, how)


def arm_design(spec: Any, plant: Any, ident: ArmIdentifier, how: str) -> Design:
    """The design of ``ident`` on ``plant`` (its law, contract ``none``)."""
    base = base_of(plant)
    units = tuple(parameter_unit(x) for x in ident.names)
    gains = Gains.of([
        Gain("K1", list(ident.K1), "N*m/rad", "servo proportional gain per joint"),
        Gain("K2", list(ident.K2), "N*m*s/rad", "servo rate gain per joint"),
        Gain("k", list(ident.switching), "rad/s^2", "observer switching gain per joint"),
        Gain("D", ident.window, "s", "distance of the two time points"),
        *(Gain(f"gamma_{x}", g, gain_unit(u), f"adaptation gain of {x}")
          for x, g, u in zip(ident.names, ident.gamma, units, strict=True)),
    ])
    known = [base.names[c] for c, _ in ident.known]
    notes = [how,
             f"Identified: {len(ident.names)} of the {len(base.names)} base parameters"
             + (f"; known at the model's values: {', '.join(known)}." if known else "."),
             "Base parameters (the model layer's regrouping): " + "; ".join(base.regrouping) + "."]
    formulas = (
        "τ = Wb(q, q̇, q̈) β = Y(q, q̇, q̈) θ + Wk(q, q̇, q̈) βk  (θ the identified base parameters, βk known)",
        "V = (θ − θ̂)ᵀ Γ⁻¹ (θ − θ̂),  V' = −2 (|ε1|² + |ε2|²)/m²",
        "V(k+1) − V(k) ≤ −(Ts/m²) θ̃ᵀ Φ θ̃ (2 − Ts λmax(Γ½ Φ Γ½)/m²),  Φ = Y(t)ᵀY(t) + Y(t−D)ᵀY(t−D)",
    )
    kind = "step" if spec.simulation.trajectory is None or spec.simulation.trajectory.kind in LINK_REFERENCES \
        else "trajectory"
    data = ArmIdentifierData(identifier=ident, base_names=tuple(base.names), K=base.K.tolist(), units=tuple(units),
                             Ts=ident.Ts, window=ident.window, gamma=tuple(ident.gamma), initial=tuple(ident.initial),
                             model_beta=base.beta.tolist(), kinematics=tuple(regressor_symbols(plant)),
                             gains_source=how)
    d = Design(kind=KIND, plant=plant, gains=gains, poles=(), reference=kind, formulas=formulas, notes=tuple(notes),
               data=data)
    return with_law(d, arm_identifier_law(plant, ident, base.W_base), Linearization("none", reason=REASON))


LAW = ("u = K1 (qD − q) + K2 (q̇D − q̇)  (a PD servo per joint driving the arm)",
       "q̂̇j' = [M̂(q)⁻¹ (u − ĥ(q, q̇))]j − kj sign(q̂̇j − q̇j)  (a sliding-mode observer per joint)",
       "ε1 = u(t) − Y(t) θ̂ − Wk(t) βk,  ε2 = u(t−D) − Y(t−D) θ̂ − Wk(t−D) βk",
       "θ̂' = Γ (Y(t)ᵀ ε1 + Y(t−D)ᵀ ε2)/m²,  m² = max(1, Ts tr(Γ Φ))")
"""The robot form's law as the report writes it."""


def law_lines(design: Design) -> tuple[str, ...]:
    """:data:`LAW` for a robot-form design, nothing for the link's (the family's own lines)."""
    return LAW if isinstance(design.data, ArmIdentifierData) else ()


def arm_law(design: Design) -> Law:
    """The law of a robot-form ``design`` rebuilt from ``design.data``."""
    ident = design.data.identifier
    return arm_identifier_law(design.plant, ident, base_of(design.plant).W_base)
