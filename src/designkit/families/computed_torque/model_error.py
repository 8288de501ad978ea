"""A model-based (computed-torque) law whose model differs from the true plant: the tracking error the
model-error torque predicts, against the measured one, and the fixes (a larger K1, or the plant's values
in the controller's model).

With the true plant ``M q'' + h = u`` and the law ``u = M^ (qD'' + K1 e + K2 e') + h^`` the errors obey
``e'' + K2 e' + K1 e = M^^-1 (tau_plant - tau_model)`` (:class:`ModelErrorPrediction`).  Entry point:
:func:`explain` (cause and fix of a failing ``tracking_error`` or ``tracking_bounds`` check).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.display.numbers import TARGET, at_time, fmt_number, quantity, relative_gap, unit
from designkit.models.torques import model_error_torque

__all__ = [
    "MODEL_PATH_SAMPLES",
    "PREDICTION_AGREEMENT",
    "ModelErrorPrediction",
    "explain",
    "model_error_prediction",
    "static_model_error",
]

MODEL_PATH_SAMPLES = 2001
"""At most this many instants of the run at which the model-error torque is evaluated."""
PREDICTION_AGREEMENT = 0.5
"""The model-error torque "explains" a measured error when its prediction is within this relative gap."""


@dataclass(frozen=True)
class ModelErrorPrediction:
    """The tracking error the model-error torque of a model-based law predicts along the run.

    With the true plant ``M q'' + h = u`` and the law ``u = M^ (qD'' + K1 e + K2 e') + h^``
    (``e = qD - q``), the errors obey ``e'' + K2 e' + K1 e = M^^-1 (tau_plant - tau_model)``, where
    ``tau_plant - tau_model = ID_plant(q, q', q'') - ID_model(q, q', q'')`` is the model-error torque
    (:func:`designkit.models.torques.model_error_torque`).  Its quasi-static response is
    ``e = (M^ K1)^-1 (tau_plant - tau_model)``; at rest ``(M^ K1)^-1 (g - g^)``.

    Parameters
    ----------
    time : ndarray, shape (N,)
        Instants of the run (s) at which the prediction is evaluated.
    torque : ndarray, shape (N, n)
        Model-error torque ``tau_plant - tau_model`` (N·m, N for a prismatic joint).
    predicted : ndarray, shape (N, n)
        Quasi-static error ``(M^ K1)^-1 (tau_plant - tau_model)`` (rad or m), sign of ``qD - q``.
    measured : ndarray, shape (N, n)
        Simulated ``|q - qD|`` at the same instants (rad or m).
    static_error : ndarray, shape (n,)
        ``(M^ K1)^-1 (g - g^)`` at the final configuration (rad or m).
    gravity_error : ndarray, shape (n,)
        ``g(q_f) - g^(q_f)`` at the final configuration (N·m).
    """

    time: np.ndarray
    torque: np.ndarray
    predicted: np.ndarray
    measured: np.ndarray
    static_error: np.ndarray
    gravity_error: np.ndarray

    @property
    def joint(self) -> int:
        """0-based joint of the largest measured error."""
        return int(np.unravel_index(int(np.argmax(self.measured)), self.measured.shape)[1])

    @property
    def measured_peak(self) -> float:
        """Largest measured ``|q - qD|`` (rad or m)."""
        return float(np.max(self.measured))

    @property
    def predicted_peak(self) -> float:
        """Largest predicted ``|e|`` over every joint (rad or m)."""
        return float(np.max(np.abs(self.predicted)))


def _model_based(result: Any) -> bool:
    """A computed-torque design whose controller model differs from the true plant (gains K1, K2 of
    ``e'' + K2 e' + K1 e = 0``, joints tracked), both plants robots."""
    from designkit.families.computed_torque import KIND

    design, plant = result.design, result.plant
    if design.kind != KIND or plant is None or plant is design.plant or not design.data.model_differs:
        return False
    if not all(hasattr(p, "robot") for p in (plant, design.plant)) or result.simulation is None:
        return False
    if "K1" not in design.gains or "K2" not in design.gains or result.simulation.task_space:
        return False
    return design.motion is None


def static_model_error(plant: Any, model: Any, K1: Any, q: Any) -> tuple[np.ndarray, np.ndarray]:
    """The error at rest ``(M^(q) K1)^-1 (g(q) - g^(q))`` a model-based law leaves at configuration ``q``.

    Parameters
    ----------
    plant, model : RobotPlant
        The true plant and the controller's model.
    K1 : array_like, shape (n,)
        Position error gains (1/s²).
    q : array_like, shape (n,)
        Configuration (rad or m).

    Returns
    -------
    error, gravity_error : ndarray, shape (n,)
        ``qD - q`` at rest (rad or m) and ``g(q) - g^(q)`` (N·m or N).
    """
    q = np.atleast_2d(np.asarray(q, dtype=float))
    n = q.shape[1]
    g = np.asarray(plant.robot.gravity_torque(q, p=plant.model_parameters()), dtype=float).reshape(n)
    g_hat = np.asarray(model.robot.gravity_torque(q, p=model.model_parameters()), dtype=float).reshape(n)
    M_hat = np.asarray(model.robot.mass_matrix(q, p=model.model_parameters()), dtype=float).reshape(n, n)
    k1 = np.broadcast_to(np.asarray(K1, dtype=float), (n,))
    return np.linalg.solve(M_hat * k1[None, :], g - g_hat), g - g_hat


def _quasi_static(plant: Any, model: Any, K1: np.ndarray, q: np.ndarray, qd: np.ndarray,
                  qdd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Model-error torque and ``(M^ K1)^-1`` of it at a batch of states (shapes (N, n))."""
    torque = model_error_torque(plant, model, q, qd, qdd)
    n = q.shape[1]
    M_hat = np.asarray(model.robot.mass_matrix(q, p=model.model_parameters()), dtype=float).reshape(-1, n, n)
    return torque, np.linalg.solve(M_hat * K1[None, None, :], torque[..., None])[..., 0]


def _run_path(sim: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None:
    """``(t, q, qd, qdd, |q - qD|)`` of the run, at most :data:`MODEL_PATH_SAMPLES` instants (None if not finite)."""
    t = np.asarray(sim.time, dtype=float)
    state = np.asarray(sim.state, dtype=float)
    q, qd = state[:, list(sim.positions)], state[:, list(sim.velocities)]
    err = np.abs(np.asarray(sim.tracking_errors, dtype=float))
    if t.size < 3 or not (np.all(np.isfinite(q)) and np.all(np.isfinite(qd)) and np.all(np.isfinite(err))):
        return None
    qdd = np.gradient(qd, t, axis=0)
    stride = max(1, math.ceil(t.size / MODEL_PATH_SAMPLES))
    keep = np.unique(np.append(np.arange(0, t.size, stride), np.argmax(np.max(err, axis=1))))
    return t[keep], q[keep], qd[keep], qdd[keep], err[keep]


def model_error_prediction(result: Any, plant: Any = None, model: Any = None) -> ModelErrorPrediction | None:
    """The quasi-static error the model-error torque predicts along the run (see :class:`ModelErrorPrediction`).

    Parameters
    ----------
    result : designkit.pipeline.PipelineResult
        A run of a model-based joint-space law (its ``simulation``, ``design`` and ``plant``).
    plant : RobotPlant, optional
        The true plant (default ``result.plant``), e.g. one corner of the uncertainty box: its
        torque is evaluated along the simulated path of ``result`` (the error is small, so the path
        barely depends on it).
    model : RobotPlant, optional
        The controller's model (default ``result.design.plant``), e.g. a corrected one.

    Returns
    -------
    ModelErrorPrediction or None
        None when the design is not a model-based joint-space law with a model that differs from
        the plant, or the run is not finite.
    """
    if not _model_based(result):
        return None
    path = _run_path(result.simulation)
    if path is None:
        return None
    t, q, qd, qdd, err = path
    plant = result.plant if plant is None else plant
    model = result.design.plant if model is None else model
    n = q.shape[1]
    K1 = np.broadcast_to(np.asarray(result.design.gains["K1"], dtype=float), (n,)).copy()
    torque, predicted = _quasi_static(plant, model, K1, q, qd, qdd)
    static, gravity = static_model_error(plant, model, K1, q[-1])
    return ModelErrorPrediction(time=t - float(np.asarray(result.simulation.time)[0]), torque=torque,
                                predicted=predicted, measured=err, static_error=static, gravity_error=gravity)


def _differences(plant: Any, model: Any) -> list[str]:
    """``"m6 2.59 (model 2.09)"`` for every parameter on which the model differs from the plant, and friction."""
    out = []
    for p in plant.parameters:
        try:
            believed = model.parameter(p.name).value
        except Exception:  # noqa: BLE001 -- a parameter the model does not have
            continue
        if believed != p.value:
            out.append(f"{p.name} = {quantity(p.value, p.unit)} (model {fmt_number(believed)})")
    if plant.robot.friction != model.robot.friction:
        out.append("friction " + ("left out of the model" if plant.robot.friction else "assumed by the model only"))
    return out


def _payload_words(plant: Any, model: Any) -> str:
    """``"the plant carries a 2.5 kg payload on link 6, the model assumes 2 kg"``, ``""`` when the payloads agree."""
    true, believed = getattr(plant, "payload", None), getattr(model, "payload", None)
    if true == believed or true is None:
        return ""
    mass, link = true
    assumed = (f"the model assumes {quantity(believed[0], 'kg')}" + (f" on link {believed[1]}" if believed[1] != link
                                                                 else "")) if believed else "the model none"
    return f"the plant carries a {quantity(mass, 'kg')} payload on link {link}, {assumed}"


def _joint_unit(plant: Any, j: int, what: str = "position") -> str:
    unit = plant.inputs[j].unit
    return ("m" if what == "position" else "N") if unit == "N" else ("rad" if what == "position" else "N*m")


def _corrected_model(result: Any) -> tuple[Any, str] | None:
    """The controller's model with the true payload (or the true parameter values) and the spec text that gives it."""
    plant, model = result.plant, result.design.plant
    true, believed = getattr(plant, "payload", None), getattr(model, "payload", None)
    if true is not None and true != believed and hasattr(model, "with_payload"):
        try:
            fixed = model.with_payload(*true)
        except Exception:  # noqa: BLE001 -- a payload the model cannot carry: no such fix
            return None
        return fixed, f"controller.model.payload: {{mass: {fmt_number(true[0])}, link: {true[1]}}}"
    changed = {p.name: p.value for p in plant.parameters if model.parameter(p.name).value != p.value}
    if changed:
        try:
            fixed = model.with_params(**changed)
        except Exception:  # noqa: BLE001
            return None
        return fixed, "controller.model.parameters: {" + ", ".join(
            f"{k}: {fmt_number(v)}" for k, v in changed.items()) + "}"
    return None


def _gain_fix(result: Any, predicted: float, limit: float, what: str, unit: str = "rad") -> str:
    """Raise K1 (and K2 at the same damping) so that ``predicted`` (scaling as 1/K1, in ``unit``) meets ``limit``."""
    if not (math.isfinite(predicted) and predicted > limit > 0):
        return ""
    factor = predicted / limit
    K1 = np.atleast_1d(np.asarray(result.design.gains["K1"], dtype=float))
    poles = np.abs(np.asarray(result.design.poles, dtype=complex))
    k1 = f"{quantity(float(K1[0]) * factor, '1/s²')}" if np.all(K1[0] == K1) else \
        "(" + ", ".join(fmt_number(float(k) * factor) for k in K1) + ") 1/s²"
    lo, hi = float(np.min(poles)), float(np.max(poles))
    old = quantity(lo, "1/s") if math.isclose(lo, hi) else f"{fmt_number(lo)} to {quantity(hi, '1/s')}"
    new = quantity(lo * math.sqrt(factor), "1/s") if math.isclose(lo, hi) else \
        f"{fmt_number(lo * math.sqrt(factor))} to {quantity(hi * math.sqrt(factor), '1/s')}"
    return (f"raise K1 by a factor {fmt_number(factor, 3)} or more (K1 = {k1}; K2 by √{fmt_number(factor, 3)} to keep "
            f"the damping): for a fixed model-error torque the error scales as 1/K1, so the predicted "
            f"{quantity(predicted, unit)} {what} falls to the {quantity(limit, unit)} limit; the error poles move from "
            f"|p| = {old} to |p| = {new}, and the commanded torques grow with the gains")


def explain(result: Any, check: Any) -> tuple[str, str] | None:
    """Cause and fix of a tracking check failing under a model mismatch (None when it does not apply; the fix
    ``""`` when the mismatch does not explain the error)."""
    pred = model_error_prediction(result)
    if pred is None:
        return None
    plant, model = result.plant, result.design.plant
    sim = result.simulation
    j = pred.joint
    k = int(np.argmax(pred.measured[:, j]))
    unit = _joint_unit(plant, j)
    tq_unit = _joint_unit(plant, j, "torque")
    kt = np.unravel_index(int(np.argmax(np.abs(pred.torque))), pred.torque.shape)
    payload = _payload_words(plant, model)
    diffs = _differences(plant, model)
    what = payload or ("; ".join(diffs) if diffs else "same parameters")
    names = sim.coordinate_names
    jn = names[j] if len(names) > j else f"q{j + 1}"
    predicted_j = float(np.max(np.abs(pred.predicted[:, j])))
    gap = relative_gap(predicted_j, pred.measured_peak)
    cause = (f"the controller's model differs from the true plant ({what}); the model-error torque "
             f"τ_plant − τ_model it leaves uncancelled reaches {quantity(float(np.abs(pred.torque[kt])), tq_unit)} "
             f"at joint {kt[1] + 1} ({at_time(float(pred.time[kt[0]]))}) and drives "
             "ë + K2 ė + K1 e = M̂⁻¹(τ_plant − τ_model); "
             f"its quasi-static response (M̂ K1)⁻¹(τ_plant − τ_model) predicts a peak |e| of "
             f"{quantity(predicted_j, unit)} at joint {j + 1} against the measured "
             f"{quantity(pred.measured_peak, unit)} "
             f"(|{jn} − {jn}D| at {at_time(float(pred.time[k]))}; {gap}); at rest at the final configuration it is "
             f"(M̂ K1)⁻¹(g − ĝ) = {quantity(float(abs(pred.static_error[j])), unit)} at joint {j + 1} "
             f"(g − ĝ = {quantity(float(pred.gravity_error[j]), tq_unit)} there)")
    explained = pred.measured_peak > 0 and abs(predicted_j / pred.measured_peak - 1) <= PREDICTION_AGREEMENT
    limit = _check_limit(check)
    predicted, what_error = pred.predicted_peak, "error"
    if check.name == "tracking_bounds":
        corner = _corner_prediction(result, check)
        if corner is None:
            return cause, ""
        peaks, j, bound, at, kind = corner
        unit = _joint_unit(plant, j)
        cause += (f"; the worst run of the uncertainty box is at {kind} ({at}; "
                  f"{check.certificate.get('runs', '?')} runs): {quantity(bound, unit)} at joint {j + 1}"
                  f"{_worst_instant(check, j)}, where the "
                  f"model-error torque of that plant along this run predicts {quantity(float(peaks[j]), unit)} "
                  f"({relative_gap(float(peaks[j]), bound)})")
        explained = bound > 0 and abs(float(peaks[j]) / bound - 1) <= PREDICTION_AGREEMENT
        predicted, what_error = float(np.max(peaks)), f"error at {at}"
    if not explained or limit is None:
        return cause, ""
    fixes = [f for f in (_gain_fix(result, predicted, limit, what_error, unit),) if f]
    corrected = _corrected_model(result)
    if corrected is not None:
        fixed, setting = corrected
        if check.name == "tracking_bounds":
            after_corner = _corner_prediction(result, check, model=fixed)
            after = math.nan if after_corner is None else float(np.max(after_corner[0]))
        else:
            after_pred = model_error_prediction(result, model=fixed)
            after = math.nan if after_pred is None else after_pred.predicted_peak
        text = f"give the controller's model the plant's values ({setting})"
        if not math.isfinite(after):
            return cause, "; or ".join(fixes)
        if after <= 1e-9 * limit:
            text += ": the model-error torque then vanishes and so does the predicted error"
        elif after <= limit:
            text += (f": the predicted {what_error} then falls to {quantity(after, unit)}, within the "
                     f"{quantity(limit, unit)} limit")
        else:
            text += (f": the predicted {what_error} then falls to {quantity(after, unit)}, still above the "
                     f"{quantity(limit, unit)} limit, so K1 must then still grow by a factor "
                     f"{fmt_number(after / limit, 3)}")
        fixes.append(text)
    return cause, "; or ".join(fixes)


def _worst_instant(check: Any, j: int) -> str:
    """`` (t = 1.93 s)``: when the worst run's error of joint ``j`` peaks (the check's data), ``""`` if unknown."""
    data = getattr(check, "data", None) or {}
    t, err = data.get("time"), data.get("errors")
    if t is None or err is None:
        return ""
    err = np.abs(np.asarray(err, dtype=float))
    t = np.asarray(t, dtype=float)
    if err.ndim != 2 or err.shape[0] != t.size or j >= err.shape[1] or not np.all(np.isfinite(err[:, j])):
        return ""
    return f" ({at_time(float(t[int(np.argmax(err[:, j]))] - t[0]))})"


def _check_limit(check: Any) -> float | None:
    m = TARGET.match(unit(check.target or ""))
    return float(m.group(2)) if m is not None and m.group(1) in ("<=", "<", "≤") else None


def _corner_prediction(result: Any, check: Any, model: Any = None
                       ) -> tuple[np.ndarray, int, float, str, str] | None:
    """The quasi-static error at the worst parameters of ``tracking_bounds`` along this run.

    Returns
    -------
    (peaks, joint, bound, at, kind) or None
        Predicted peak ``|e|`` per joint (rad or m) on the plant at the certificate's
        ``worst_parameters`` with the controller's ``model`` (default the design's); the 0-based joint of
        the check's bound and that bound; ``"m6 = 2.84"``; ``"a corner"`` or ``"a sample"``.
    """
    cert = check.certificate if hasattr(check.certificate, "get") else {}
    worst = dict(cert.get("worst_parameters") or {})
    bound = cert.get("bound_per_joint_rad")
    path = _run_path(result.simulation)
    if not worst or bound is None or path is None:
        return None
    try:
        corner = result.plant.with_params(**{k: float(v) for k, v in worst.items()})
    except Exception:  # noqa: BLE001 -- parameters the plant does not take: no prediction
        return None
    box = dict(cert.get("box") or {})
    kind = "a corner" if all(float(v) in tuple(map(float, box.get(k, ()))) for k, v in worst.items()) else "a sample"
    _, q, qd, qdd, _ = path
    n = q.shape[1]
    K1 = np.broadcast_to(np.asarray(result.design.gains["K1"], dtype=float), (n,)).copy()
    _, predicted = _quasi_static(corner, result.design.plant if model is None else model, K1, q, qd, qdd)
    bounds = np.asarray(bound, dtype=float)
    j = int(np.argmax(bounds))
    at = ", ".join(f"{k} = {fmt_number(v)}" for k, v in worst.items())
    return np.max(np.abs(predicted), axis=0), j, float(bounds[j]), at, kind
