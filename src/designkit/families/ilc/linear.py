"""Learning on a linear plant: the plant's own sampled model, its lifted map and the family's own trials.

On a ``transfer_function`` or ``state_space`` plant (single input, the first output tracked) the learned signal is
the plant's input itself, played open loop: trial ``k`` applies ``u_k(t_i)``, held over each sample, and between
trials ``u_(k+1) = u_k + Q e_k``.  The trial's sample period ``dt`` is

* the plant's own ``plant.dt`` for a discrete-time plant (``x_(i+1) = A x_i + B u_i``, ``y_i = C x_i``: the model
  as given; a different ``simulation.dt`` is refused);
* ``simulation.dt``, else the step the simulator would choose from the plant's poles and the reference
  (:func:`~designkit.simulation.timing.resolve`), for a continuous-time plant, sampled by the **zero-order hold**
  ``Phi = e^(A dt)``, ``Gamma = int_0^dt e^(A s) ds B`` (``expm`` of the block matrix): the exact response of the
  continuous plant to an input held over each sample, at the sample instants.

The lifted ``H`` is the lower-triangular Toeplitz matrix of the shifted Markov parameters ``h_m = C Phi^(m+s)
Gamma`` (``s`` leading ones vanish: the relative degree in samples is ``r = s + 1``), mapping ``u_0 .. u_(N-1-r)``
to ``e_r .. e_(N-1)`` (:func:`~designkit.families.ilc.lifted.sampled_lifted`); the certificate is that of the
controller's model (``controller.model.parameters`` may differ from the plant's).  The trials are the family's own:
the difference equation of the **true** plant from rest (``x_0 = 0``, the same every trial), sample by sample; the
error the update reads is ``yD - y`` at the samples.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from designkit.errors import SpecError
from designkit.families.ilc.learning import IlcData, check_size, update_rule
from designkit.families.ilc.lifted import sampled_lifted
from designkit.families.ilc.operators import learning_operator
from designkit.simulation.result import SimulationResult
from designkit.simulation.trials import Learning, TrialsResult
from designkit.synthesis.design import Design, Gain, Gains

__all__ = ["LINEAR_PLANTS", "linear_grid", "run_linear_trials", "sampled", "synthesize_linear", "validate_linear"]

LINEAR_PLANTS = ("transfer_function", "state_space")
"""The plant kinds on which the learned signal is the plant's input."""

REFUSED = ("nonlinearity", "delay", "sampling_period", "noise", "perturbation", "plant_change", "initial_position")
"""``simulation`` settings the family's own trials on a linear plant do not run (refused with their key path)."""


def validate_linear(spec: Any) -> None:
    """Refuse what the linear trials do not run (``ValueError`` naming the key path)."""
    sim = spec.simulation
    for name in REFUSED:
        value = getattr(sim, name)
        if value is not None and value != 0:
            raise ValueError(f"simulation.{name}: the learning trials on a {spec.plant.kind} plant are the plant's "
                             "sampled difference equation from rest, input held over each sample; they do not run it")
    for name in ("poles", "damping", "natural_frequency"):
        if getattr(spec.controller, name) is not None:
            raise ValueError(f"controller.{name}: on a {spec.plant.kind} plant the learned signal is the plant's "
                             "input, played open loop; there is no computed-torque feedback whose error poles to give")
    if spec.plant.uncertainty is not None:
        raise ValueError(f"plant.uncertainty: the learning on a {spec.plant.kind} plant is not judged over a "
                         "parameter box (its certificate is the controller's model's); leave it out")


def sampled(plant: Any, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(Phi, Gamma, C)`` of the plant's first input to its first output over one sample ``dt`` (s): the model as
    given when discrete-time, the zero-order hold when continuous."""
    A, B, _, _ = plant.matrices()
    C = np.zeros(A.shape[0])
    C[plant.positions[0]] = 1.0  # the realisation makes the first output a state
    b = B[:, 0]
    if getattr(plant, "dt", None) is not None:
        return A, b, C
    from scipy.linalg import expm

    n = A.shape[0]
    E = expm(np.block([[A, b[:, None]], [np.zeros((1, n + 1))]]) * dt)
    return E[:n, :n], E[:n, n], C


def linear_grid(spec: Any, plant: Any) -> tuple[float, int, str]:
    """``(dt, N, integrator)`` of a trial on a linear plant (module docstring); :class:`SpecError` at
    ``simulation.dt`` or ``simulation.duration``."""
    from designkit.simulation.reference import reference_for

    sim = spec.simulation
    ref = reference_for("trajectory", sim, 1)
    if plant.dt is not None:
        dt = float(plant.dt)
        if sim.dt is not None and abs(float(sim.dt) - dt) > 1e-12 * dt:
            raise SpecError("simulation.dt", f"{float(sim.dt):g} s differs from the discrete-time plant's sample "
                            f"period plant.dt = {dt:g} s; leave it out")
        duration = float(sim.duration) if sim.duration is not None else float(ref.horizon)
        if not duration > 0:
            raise SpecError("simulation.duration", "a learning trial needs a duration (the reference has none)")
        steps = duration / dt
        if abs(steps - round(steps)) > 1e-9 * max(steps, 1.0):
            raise SpecError("simulation.duration", f"{duration:g} s is not a whole number of samples of plant.dt = "
                            f"{dt:g} s")
        return dt, int(round(steps)) + 1, "discrete"
    from designkit.simulation.timing import rates_of, resolve

    A = plant.matrices()[0]
    timing = resolve(spec, rates_of((), np.linalg.eigvals(A), reference_rate=ref.rate), ref.horizon)
    return float(timing.dt), int(timing.n_samples), "zoh"


def _as_tuple(M: np.ndarray) -> tuple[Any, ...]:
    M = np.asarray(M, dtype=float)
    return tuple(tuple(float(v) for v in row) for row in M) if M.ndim == 2 else tuple(float(v) for v in M)


def synthesize_linear(spec: Any, plant: Any, model: Any, kind: str) -> Design:
    """The learning design of a linear plant: the sampled model, its lifted map, the operator and the trials."""
    ctrl = spec.controller
    if plant.n_inputs != 1:
        raise SpecError("plant.B", f"the learning on a linear plant learns one input; this plant has {plant.n_inputs}")
    dt, N, integrator = linear_grid(spec, plant)
    check_size(N, dt, 1, ctrl.trials)
    Phi, Gamma, C = sampled(model, dt)
    try:
        lifted = sampled_lifted(_as_tuple(Phi), _as_tuple(Gamma), _as_tuple(C), dt, N, integrator)
    except ValueError as exc:
        raise SpecError("plant", str(exc)) from None
    u_unit, y_unit = plant.inputs[0].unit, plant.outputs[0].unit
    learning = ctrl.learning
    from designkit.families.ilc.checks import ratio

    h_unit = ratio(y_unit, u_unit)
    filt = None
    if learning.kind == "adjoint":
        per = ratio(u_unit, y_unit)
        name, unit, meaning = "alpha", f"({per})^2" if per else "", "learning gain of Q = alpha H^T"
        if learning.alpha is not None:
            value, source = float(learning.alpha), "controller.learning.alpha"
        else:
            value = 1.0 / lifted.sigma_max[0].estimate ** 2
            source = "computed: 1 / sigma_max(H)^2, which removes the largest singular direction in one trial"
    elif learning.kind == "p_type":
        name, unit, meaning = "gamma", ratio(u_unit, y_unit), "learning gain of the P-type update (advance r)"
        value, source = float(learning.gain), "controller.learning.gain"
    else:
        filt = (tuple(float(v) for v in learning.num), tuple(float(v) for v in learning.den))
        name, unit, meaning = "q0", ratio(u_unit, y_unit), "first coefficient of the learning filter F(z)"
        value, source = filt[0][0] / filt[1][0], "controller.learning.num, den"
    info = IlcData(samples=N, dt=dt, integrator=integrator, trials=ctrl.trials, learning=learning.kind, value=value,
                   value_source=source, model_differs=ctrl.model is not None,
                   sampled=(_as_tuple(Phi), _as_tuple(Gamma), _as_tuple(C)), shift=lifted.shift,
                   units=(u_unit, y_unit), filter=filt)
    what = "discrete-time, as given" if integrator == "discrete" else "continuous, sampled by a zero-order hold"
    notes = [f"Learning: {learning.kind.replace('_', '-')} update, {name} = {value:.6g} {unit} ({source}); "
             f"{ctrl.trials} trials of {N} samples (dt = {dt:g} s, plant {what}); relative degree {lifted.shift} "
             f"sample(s), first Markov parameter h = {lifted.markov[0, 0]:.6g} {h_unit}."]
    if ctrl.model is not None:
        notes.append("The controller's model differs from the true plant: the learning certificate is the model's; "
                     "the trials run on the true plant and measure the difference.")
    operator = learning_operator(learning.kind, filt if filt is not None else value)
    design = Design(kind=kind, plant=model, gains=Gains.of([Gain(name, value, unit, meaning)]), reference="trajectory",
                    notes=tuple(notes), data=info,
                    formulas=("x_(i+1) = Φ x_i + Γ u_k(t_i),  y_i = C x_i  (Φ, Γ: " + what + ")",
                              "e_k = yD − y_k = H (u − u_k),  H lower-triangular Toeplitz of h_m = C Φ^(m+r−1) Γ",
                              "u_(k+1) = u_k + Q e_k:  ‖u − u_(k+1)‖ ≤ ρ ‖u − u_k‖,  ρ = ‖I − Q H‖₂"))
    update = update_rule((), (), info)
    runner = Learning(ctrl.trials, update, operator.describe(),
                      run=lambda spec_, plant_: run_linear_trials(spec_, info, update, plant_))
    return dataclasses.replace(design, learning=runner)


def run_linear_trials(spec: Any, info: IlcData, learn: Any, plant: Any) -> TrialsResult:
    """Every trial of a design with data ``info`` on the true linear ``plant``: its sampled difference equation from
    rest, the input held over each sample, the update ``learn`` between trials."""
    from designkit.simulation.reference import reference_for

    dt, N = float(info.dt), int(info.samples)
    Phi, Gamma, _ = sampled(plant, dt)
    time = np.arange(N) * dt
    reference = reference_for("trajectory", spec.simulation, 1).evaluate(time)
    nx = Phi.shape[0]
    settings = {"dt": dt, "samples": N, "integrator": "difference equation (discrete-time plant)"
                if info.integrator == "discrete" else "exact zero-order hold (expm), input held over each sample",
                "initial_state": [0.0] * nx, "trials": info.trials}
    u = np.zeros((N, 1))
    results, used = [], []
    for k in range(info.trials):
        x = np.zeros((N, nx))
        with np.errstate(over="ignore", invalid="ignore"):
            for i in range(N - 1):
                x[i + 1] = Phi @ x[i] + Gamma * u[i, 0]
        result = SimulationResult(
            time=time, reference=reference, state=x, controller_state=np.zeros((N, 0)), u_command=u, u_applied=u,
            perturbation=np.zeros((N, 1)), measured=x, kind="trajectory", positions=plant.positions,
            velocities=plant.velocities, state_names=tuple(s.name for s in plant.states), controller_state_names=(),
            input_names=tuple(s.name for s in plant.inputs),
            disturbance_names=tuple(s.name for s in plant.disturbances), settings=settings)
        results.append(result)
        frozen = u.copy()
        frozen.setflags(write=False)
        used.append(frozen)
        if k + 1 < info.trials:
            u = np.asarray(learn(result, frozen), dtype=float)
    return TrialsResult(results=tuple(results), feedforward=tuple(used))
