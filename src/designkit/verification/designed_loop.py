"""Is the simulated loop the designed loop?  Check ``designed_loop``.

A linear design is a statement about deviations from a rest point: the closed loop ``A, B, C, D``
(:mod:`designkit.synthesis.closed_loop`) describes how the loop leaves its equilibrium when the
reference moves.  A simulation that starts somewhere else -- an integral at zero while the loop's
rest value is ``K4 q0``, a reference model at zero while the arm is at ``q0``, a feed-forward on the
absolute reference that the initial state does not balance -- simulates another loop, and a
time-domain PASS on it says nothing about the design.  Two tests, both on the designed plant
(``design.plant``, the model the design was computed for) under the designed law:

1. **The designed law.**  The simulated law, linearized where the design was linearized, is the design's
   ``closed_loop`` (to :data:`LAW_MATRIX_REL`): otherwise every linear certificate is about another loop.
2. **At rest at the start.**  With the plant at rest at the run's initial position and the
   controller at the state the run starts from, the loop's state derivative at the reference before
   the motion must vanish: ``max |z_dot| <= REST_TOL (1 + max |z|)``.
3. **Small signal.**  The same run with the reference's motion and the perturbation scaled by
   :data:`SMALL_SIGNAL` (no nonlinear element, noise, delay or sampling and no ``implementation`` -- hold, computation
   delay, quantisation, actuator: the elements a linear design does not contain, and without a plant change: the
   designed plant) must follow the loop linearized at that
   rest point: the largest difference between
   the run's deviations divided by the scale and the linear response, over the positions and the plant
   inputs, relative to the linear response's extent (the largest over the positions, and over the inputs), at
   most :data:`SMALL_SIGNAL_REL`.  The positions' extent is at least the reference's own motion: a loop that
   barely responds (an adaptive law frozen at zero gains) is judged against the size of the command, not against
   its own vanishing response, whose ratio to any integration error says nothing.  The nonlinear
   terms of a smooth plant contribute in proportion to the scale (1e-4), the integrators about 1e-6.
   A plant with non-smooth terms at rest (Coulomb friction, :meth:`~designkit.models.plant.PlantBase.nonsmooth`)
   is not linear however small the signal, so part 3 is not run on it and the check says so.

When the verified run contains such elements, the check's detail and its certificate (``not_in_linear_reference``)
name them: the check is then about the design inside the implementation, not about the implemented loop.

Part 3 compares with the law linearized where the run starts; when that is not the design's operating
point (a decentralized design at ``q*`` simulated from ``q0``) the check says so.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from designkit.verification.check import Check

__all__ = ["SMALL_SIGNAL", "SMALL_SIGNAL_REL", "designed_loop_check"]

SMALL_SIGNAL = 1e-4
"""Scale of the small-signal run: the reference's motion and the perturbation times this."""
SMALL_SIGNAL_REL = 1e-2
"""Largest relative difference between the small-signal run and the linear response (1)."""
LAW_MATRIX_REL = 1e-8
"""Largest relative difference between the design's closed loop and its law linearized at the same point (1)."""


def _law_against_design(plant: Any, law: Any, design: Any) -> float:
    """``max |M_law - M_design| / (1 + max |M_design|)`` over the closed loop's ``A`` and ``B``, with the law
    linearized at the design's operating point."""
    from designkit.synthesis.closed_loop import linearize

    op = design.operating_point
    try:
        closed, _, _ = linearize(plant, law, op["r"], z0=[*op["x"], *op["xc"]])
    except ValueError:
        return float("inf")
    ref = design.closed_loop
    if closed.A.shape != ref.A.shape or closed.B.shape != ref.B.shape:
        return float("inf")
    return max(float(np.max(np.abs(closed.A - ref.A))) / (1.0 + float(np.max(np.abs(ref.A)))),
               float(np.max(np.abs(closed.B - ref.B))) / (1.0 + float(np.max(np.abs(ref.B)))))


def _small_spec(spec: Any, scale: float) -> Any:
    """The spec's scenario without the elements a linear design leaves out, the perturbation scaled."""
    sim = spec.simulation
    pert = sim.perturbation
    if pert is not None:
        value = [scale * v for v in pert.value] if isinstance(pert.value, list | tuple) else scale * pert.value
        pert = pert.model_copy(update={"value": value})
    small = sim.model_copy(update={"nonlinearity": None, "noise": None, "delay": 0.0, "sampling_period": 0.0,
                                   "perturbation": pert, "plant_change": None})
    return spec.model_copy(update={"simulation": small, "implementation": None})


def _left_out(spec: Any) -> str:
    """The parts of the run the small-signal comparison leaves out, in words (empty when none)."""
    parts = []
    impl = getattr(spec, "implementation", None)
    if impl is not None:
        what = [w for w, on in (("the sampling and hold", impl.sampling_period is not None),
                                ("the computation delay", impl.delay > 0),
                                ("the measurement quantisation", impl.quantization is not None),
                                ("the actuator's saturation and lag", impl.actuator is not None)) if on]
        parts.append("the controller as implemented (" + (", ".join(what) or "as designed") + ")")
    sim = spec.simulation
    for words, on in (("the nonlinear element", sim.nonlinearity is not None), ("the noise", sim.noise is not None),
                      ("the sampling", sim.sampling_period > 0), ("the delay", sim.delay > 0)):
        if on:
            parts.append(words)
    return ", ".join(parts)


def _scaled_reference(ref: Any, scale: float) -> Any:
    """``before + scale (ref - before)``, same settings (``before`` the reference's positions before the motion)."""
    from designkit.simulation.reference import Reference

    before = np.asarray(ref.before, dtype=float)

    def evaluate(t: np.ndarray) -> np.ndarray:
        out = np.array(ref.evaluate(t), dtype=float)
        out[:, :, 0] = before[None, :] + scale * (out[:, :, 0] - before[None, :])
        out[:, :, 1:] *= scale
        return out

    return Reference(evaluate, ref.n, ref.horizon, ref.rate, ref.settings, ref.start, ref.before,
                     ref.piecewise_constant)


def designed_loop_check(spec: Any, design: Any) -> Check:
    """Check ``designed_loop`` (module docstring): ``design`` in the scenario of ``spec``, started as the simulator
    starts it (:func:`designkit.simulation.run.build`)."""
    from designkit.simulation.linear import forced_response
    from designkit.simulation.reference import reference_of
    from designkit.simulation.run import build
    from designkit.synthesis.closed_loop import REST_TOL, linearize, loop_functions

    plant, law = design.plant, design.linear_law
    ref = reference_of(spec, design)
    start = np.asarray(ref.start, dtype=float)
    before = ref.rest()
    simulator = build(_small_spec(spec, SMALL_SIGNAL), design, plant=plant, law=law,
                      reference=_scaled_reference(ref, SMALL_SIGNAL))
    nx = len(plant.states)
    z0 = np.asarray(simulator.z0[:nx + law.n_state], dtype=float)  # where the simulator starts the loop
    xc0 = z0[nx:]
    fns = loop_functions(plant, law)
    p = np.asarray(plant.parameter_vector, dtype=float)
    z_dot = np.asarray(fns.jacobians(z0, before, np.zeros(len(plant.disturbances)), p)[0], dtype=float).ravel()
    residual = float(np.max(np.abs(z_dot))) if z_dot.size else 0.0
    scale = 1.0 + float(np.max(np.abs(z0))) if z0.size else 1.0
    at_rest = bool(np.isfinite(residual) and residual <= REST_TOL * scale)
    names = [*(s.name for s in plant.states), *law.state_names]
    cert: dict[str, Any] = {"start": start.tolist(), "controller_start": xc0.tolist(), "rest_residual": residual,
                            "rest_tolerance": REST_TOL * scale}
    left_out = _left_out(spec)
    if left_out:
        cert["not_in_linear_reference"] = (f"{left_out}: part of the verified run, not of the designed linear loop; "
                                           "this check compares the run without them with the design")
    target = "the simulated loop starts at rest and follows its linearization in the small"
    if not at_rest:
        k = int(np.argmax(np.abs(z_dot)))
        detail = (f"the run does not start at rest on the designed loop: d{names[k]}/dt = {z_dot[k]:.4g} at t = 0 with "
                  f"the plant at rest at {np.array2string(start, precision=4)} and the controller at "
                  f"{np.array2string(xc0, precision=4)}; the simulation is of another loop than the one designed")
        return Check("designed_loop", False, target, residual, REST_TOL * scale - residual, "1/s", detail, cert)
    op = design.operating_point
    if op and design.closed_loop is not None:
        mismatch = _law_against_design(plant, law, design)
        cert["law_against_design"] = mismatch
        if mismatch > LAW_MATRIX_REL:
            detail = (f"the simulated law is not the designed loop: linearized where the design was, its closed-loop "
                      f"matrices differ from the design's by {mismatch:.3g} of their size (tolerance "
                      f"{LAW_MATRIX_REL:g}); the checks of the linear design are about another loop")
            return Check("designed_loop", False, target, mismatch, LAW_MATRIX_REL - mismatch, "1 (relative)", detail,
                         cert)
    rough = plant.nonsmooth()
    if rough:
        detail = (f"starts at rest (max |dz/dt| = {residual:.2g} at t = 0); the small-signal comparison does not "
                  f"apply: the plant's {'; '.join(rough)} is not smooth at rest, so a small motion is not linear")
        cert["small_signal"] = "not applicable: " + "; ".join(rough)
        return Check("designed_loop", True, target, residual, REST_TOL * scale - residual, "1/s", detail, cert)
    small = simulator.run()
    same = bool(op) and np.allclose(op.get("x", []), z0[:nx], rtol=1e-9, atol=1e-12) and np.allclose(
        op.get("r", []), before, rtol=1e-9, atol=1e-12)
    closed, _, point = linearize(plant, law, before, z0=z0)
    t = np.asarray(small.time)
    flat = ref.flat(t) - before[None, :]
    pert = np.asarray(small.perturbation, dtype=float) / SMALL_SIGNAL
    inputs = np.hstack([flat, pert]).T
    held = np.r_[np.full(flat.shape[1], ref.piecewise_constant), np.ones(pert.shape[1], dtype=bool)]
    y_lin = forced_response(closed.A, closed.B, closed.C, closed.D, t, inputs, held=held)  # held as the simulator does
    pos = np.asarray(small.state, dtype=float)[:, list(plant.positions)] - np.asarray(point["x"])[list(plant.positions)]
    u = np.asarray(small.u_command, dtype=float) - np.asarray(point["u"])[None, :]
    y_run = np.hstack([pos, u]).T / SMALL_SIGNAL
    n_pos = pos.shape[1]
    extent = np.empty((y_lin.shape[0], 1))  # one scale per kind of output: the positions together, the inputs together
    for rows in (slice(0, n_pos), slice(n_pos, None)):
        extent[rows] = float(np.max(np.abs(y_lin[rows]))) if y_lin[rows].size else 1.0
    motion = float(np.max(np.abs(flat))) if flat.size else 0.0  # the reference's own motion, per unit of scale
    weak = bool(extent[0, 0] < 0.5 * motion) if n_pos else False
    if n_pos:
        extent[:n_pos] = max(float(extent[0, 0]), motion)
    extent[extent == 0] = 1.0
    rel = np.abs(y_run - y_lin) / extent
    worst = float(np.max(rel)) if np.all(np.isfinite(rel)) else np.inf
    row, k = np.unravel_index(int(np.argmax(np.nan_to_num(rel, nan=np.inf))), rel.shape)
    outputs = list(closed.outputs)
    moved = "" if same else (" (the run does not start at the design's operating point: compared with the loop "
                             "linearized where it starts)")
    cert.update(small_signal_scale=SMALL_SIGNAL, largest_relative_difference=worst, tolerance=SMALL_SIGNAL_REL,
                worst_output=outputs[row], worst_at_s=float(t[k]), position_scale=float(extent[0, 0]) if n_pos
                else None, reference_motion=motion)
    ok = bool(worst <= SMALL_SIGNAL_REL)
    what = (f"starts at rest (max |dz/dt| = {residual:.2g}) and, with the motion scaled by {SMALL_SIGNAL:g}, "
            f"follows its linearization to {worst:.2g} of the response (largest on {outputs[row]} at "
            f"t = {t[k]:.3g} s){moved}")
    if not ok:
        what = (f"the small-signal run leaves the linear closed loop by {worst:.3g} of the response on {outputs[row]} "
                f"at t = {t[k]:.3g} s (tolerance {SMALL_SIGNAL_REL:g}){moved}: the simulated loop is not the "
                "designed one -- a state, reference or feed-forward the design does not contain")
    if weak:
        what += (f"; the positions are judged against the reference's motion ({motion:.3g} per unit of scale), larger "
                 "than the linear loop's response")
    if left_out:
        what += (f"; the small-signal run leaves out {left_out}, which the verified run contains and the linear "
                 "design does not model")
    return Check("designed_loop", ok, target, worst, SMALL_SIGNAL_REL - worst, "1 (relative)", what, cert)
