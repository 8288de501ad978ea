"""What happens between trials: the trial's grid, the bounds on the lifted size, and the update rule.

The learned signal ``d_k`` is one acceleration (rad/s^2) per joint and instant; the law maps it into the
command through the model's inertia, ``M^(q) d_k`` (``Law.feedforward``).  The update reads the trial's
*measured* error ``e_k = qD - y_q`` (the controller's view: the true error when there is no noise) at the
samples ``1 .. N-1`` (``e_0`` does not depend on ``d``), computes ``d_{k+1} = d_k + Q e_k`` on the samples
``0 .. N-2``, and holds the last value over the last step, which moves no recorded sample.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.errors import SpecError
from designkit.families.ilc.lifted import MAX_LIFTED, MAX_TRIAL_SAMPLES, LiftedModel, lifted_model
from designkit.families.ilc.operators import Adjoint, Filter, PType, learning_operator
from designkit.synthesis.design import FamilyData

__all__ = ["IlcData", "check_size", "lifted_errors", "lifted_of", "operator_of", "trial_grid", "update_rule"]


@dataclass(frozen=True)
class IlcData(FamilyData):
    """The ILC family's design data (:attr:`~designkit.synthesis.design.Design.data`): the trial's grid and the
    learning operator.

    Attributes
    ----------
    samples : int
        Samples of a trial, ``N``.
    dt : float
        The grid's step (s).
    integrator : str
        The simulator's integrator on that grid (the lifted model is its discretization).
    trials : int
        Trials run (``controller.trials``).
    learning : str
        The operator ``Q``: ``"adjoint"`` or ``"p_type"``.
    value : float
        Its gain: ``alpha`` (1/s^4) of the adjoint update, ``gamma`` (1/s^2) of the P-type update.
    value_source : str
        Where the gain comes from, in words.
    model_differs : bool
        Whether the controller's model differs from the true plant (the certificate is then the model's).
    sampled : tuple or None
        A linear plant's sampled model ``(Phi, Gamma, C)`` as nested tuples (the controller's model, sampled at
        ``dt``: :mod:`~designkit.families.ilc.linear`); None on a robot.
    shift : int
        The relative degree in samples (1 on a robot).
    units : tuple of str
        ``(learned signal, tracked output)`` units: ``("rad/s^2", "rad")`` on a robot, the plant's input and first
        output on a linear plant.
    filter : tuple or None
        ``(num, den)`` of the ``filter`` learning operator.
    """

    samples: int
    dt: float
    integrator: str
    trials: int
    learning: str
    value: float
    value_source: str
    model_differs: bool = False
    sampled: tuple[Any, ...] | None = None
    shift: int = 1
    units: tuple[str, str] = ("rad/s^2", "rad")
    filter: tuple[Any, ...] | None = None


def trial_grid(spec: Any, design: Any, plant: Any) -> Any:
    """The time grid the simulator will use for ``design`` on the true ``plant`` (a
    :class:`~designkit.simulation.timing.Timing`), chosen from the same rates as
    :func:`designkit.simulation.run.build`: the requested poles, the nominal closed loop, the closed loop on the
    true plant and the reference's rate.  Cheap: no simulation is built."""
    import contextlib

    from designkit.simulation.reference import reference_of
    from designkit.simulation.timing import rates_of, resolve
    from designkit.synthesis.closed_loop import linearize

    ref = reference_of(spec, design)
    sets = [design.closed_loop.poles] if design.closed_loop is not None else []
    op = design.operating_point
    if plant is not design.plant and op:
        with contextlib.suppress(ValueError):
            sets.append(linearize(plant, design.linear_law, op["r"], z0=[*op["x"], *op["xc"]])[0].poles)
    rates = rates_of(design.poles, *sets, reference_rate=ref.rate)
    return resolve(spec, rates, ref.horizon)


def check_size(samples: int, dt: float, joints: int, trials: int) -> None:
    """Refuse a lifted size ``N n`` above :data:`MAX_LIFTED` (``simulation.duration``) or ``trials N n`` above
    :data:`MAX_TRIAL_SAMPLES` (``controller.trials``), with :class:`SpecError`."""
    size = samples * joints
    span = f"{(samples - 1) * dt:.6g} s at dt = {dt:.3g} s"
    if size > MAX_LIFTED:
        raise SpecError("simulation.duration", f"a learning trial of {span} has {samples} samples x {joints} "
                        f"joints = {size} lifted unknowns, more than {MAX_LIFTED} (the bound of the lifted model); "
                        "shorten simulation.duration or set a coarser simulation.dt")
    if size * trials > MAX_TRIAL_SAMPLES:
        raise SpecError("controller.trials", f"{trials} trials of {samples} samples x {joints} joints = "
                        f"{size * trials} recorded samples, more than {MAX_TRIAL_SAMPLES} (every trial is kept); "
                        f"ask for at most {MAX_TRIAL_SAMPLES // size} trials or a shorter trial")


def _lifted(K1: tuple[float, ...], K2: tuple[float, ...], info: IlcData, time: np.ndarray | None) -> LiftedModel:
    if info.sampled is not None:
        from designkit.families.ilc.lifted import sampled_lifted

        samples = int(info.samples) if time is None or len(time) < 2 else int(len(time))
        return sampled_lifted(*info.sampled, float(info.dt), samples, str(info.integrator))
    if time is None or len(time) < 2:
        return lifted_model(K1, K2, float(info.dt), int(info.samples), str(info.integrator))
    dt = float(time[1] - time[0])
    if int(len(time)) == int(info.samples) and abs(dt - float(info.dt)) <= 1e-9 * dt:
        dt = float(info.dt)  # the same grid: share the cached model
    return lifted_model(K1, K2, dt, int(len(time)), str(info.integrator))


def _gains(design: Any) -> tuple[tuple[float, ...], tuple[float, ...]]:
    if design.data.sampled is not None:
        return (), ()
    return tuple(tuple(np.atleast_1d(np.asarray(design.gains[k], dtype=float)).tolist()) for k in ("K1", "K2"))


def lifted_of(design: Any, time: np.ndarray | None = None) -> LiftedModel:
    """The lifted model of an ``ilc`` design, on the grid of ``time`` (a run's instants) or the design's grid."""
    return _lifted(*_gains(design), design.data, time)


def operator_of(design: Any) -> Adjoint | PType | Filter:
    """The learning operator of an ``ilc`` design."""
    info = design.data
    return learning_operator(str(info.learning), info.filter if info.learning == "filter" else float(info.value))


def lifted_errors(result: Any, shift: int = 1) -> np.ndarray:
    """``e = qD - y_q`` of a trial at the samples ``shift .. N-1``, ``(n, L)`` (rad on a robot): what the learning
    sees."""
    y = np.asarray(result.measured, dtype=float)[:, list(result.positions)]
    return (np.asarray(result.desired, dtype=float) - y).T[:, shift:]


def update_rule(K1: tuple[float, ...], K2: tuple[float, ...], info: IlcData) -> Any:
    """The :data:`~designkit.simulation.trials.LearningRule` ``(result_k, d_k) -> d_{k+1}`` of the gains and the
    design's data (grid, operator, trials)."""
    operator = learning_operator(str(info.learning), info.filter if info.learning == "filter" else float(info.value))

    def update(result: Any, feedforward: np.ndarray) -> np.ndarray:
        lifted = _lifted(K1, K2, info, result.time)
        check_size(lifted.samples, lifted.dt, lifted.n, int(info.trials))
        d = np.asarray(feedforward, dtype=float).T  # (n, N)
        with np.errstate(all="ignore"):  # a diverged trial gives a non-finite update, judged by the checks
            nxt = d[:, :lifted.L] + operator.apply(lifted, lifted_errors(result, lifted.shift))
        out = np.empty_like(d)
        out[:, :lifted.L] = nxt
        out[:, lifted.L:] = nxt[:, -1:]
        return out.T

    return update
