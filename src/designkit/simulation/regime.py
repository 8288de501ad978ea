"""How the closed loop is evaluated in time: held per step, or smooth enough to integrate across the grid.

The one place that decides, from the law, the nonlinear element and the scenario:

* ``held_law``: the law is sampled (a sampling period) or discontinuous (``Law.discontinuous``, e.g. a
  ``sign`` of a sliding function): its command and its state derivative are computed at the samples (every
  step for a discontinuous law) and held (:mod:`designkit.simulation.step`);
* ``per_step``: the chain is evaluated once per integration step and held over it (a held law, a delay line,
  or an element that is not a continuous memoryless map: relay, quantizer);
* ``smooth``: the right-hand side is a smooth function of the state and of time between the grid's
  breakpoints (the instants where a held input jumps: a perturbation, a plant change, a jump of the
  reference), so an adaptive integrator may take steps across grid points and write the output grid from
  its continuous extension (:mod:`designkit.simulation.dopri5`).  It is not when the chain is held per step,
  when the law has discrete memory (updated at every step), an anti-windup gate or clamp (a switch decided
  at each step's start), when measurement noise changes the input at every step, when the law declares how a
  trial's per-step feedforward enters (a learning controller, whose lifted model is the step-by-step map of
  RK4 on the grid: :mod:`designkit.families.ilc.lifted`), or when the plant itself is
  not smooth (Coulomb friction: ``plant.nonsmooth()``) and the law does not cancel its jump (:func:`cancelled`).

A trial's feedforward (:mod:`designkit.simulation.trials`) is a per-step sequence held over each step: every
step where it changes is a breakpoint, so a smooth loop stays smooth between grid points with one.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

__all__ = ["Regime", "regime_of"]


@dataclass(frozen=True)
class Regime:
    """How the loop is evaluated (module docstring).

    Parameters
    ----------
    held_law : bool
        The law's command and state derivative are held between its samples.
    per_step : bool
        The chain (law, element, delay) is evaluated once per step and held over it.
    smooth : bool
        The right-hand side is smooth between breakpoints: an adaptive integrator may cross grid points.
    why : str
        Why the loop is not smooth, in words (empty when it is).
    resets : bool
        A smooth loop whose law's ``project`` resets states now and then (``Law.project_resets``): the adaptive
        pair applies it at the grid instants; the integrators without that (CVODES over the grid) do not run it.
    """

    held_law: bool
    per_step: bool
    smooth: bool
    why: str = ""
    resets: bool = False


def _constant_gate(law: Any) -> bool:
    """True when ``law.gate`` does not depend on its arguments (no anti-windup switch)."""
    gate = law.gate
    args = [ca.SX.sym(f"a{k}", gate.size1_in(k)) for k in range(gate.n_in())]
    out = gate(*args)
    return out.numel() == 0 or not ca.depends_on(out, ca.vertcat(*args))


def _identity_projection(law: Any) -> bool:
    """True when ``law.project`` returns its argument (no clamp of the integral states)."""
    xc = ca.SX.sym("xc", law.project.size1_in(0))
    return xc.numel() == 0 or bool(ca.simplify(law.project(xc) - xc).is_zero())


def regime_of(law: Any, element: Any, *, sampled: bool, delayed: bool, noisy: bool = False,
              plant: Any = None, probe: Any = None, quantized: bool = False) -> Regime:
    """The :class:`Regime` of ``law`` with ``element``.

    Parameters
    ----------
    law : Law
    element : Element
        The nonlinear element at the plant input (:mod:`designkit.simulation.nonlinear`).
    sampled : bool
        The controller has a sampling period.
    delayed : bool
        There is a control delay.
    noisy : bool
        Measurement noise is added (one sample per step, held over the step).
    plant : Plant, optional
        The simulated plant: one with terms that are not differentiable (``plant.nonsmooth()``, e.g. Coulomb
        friction ``Fc sign(q̇)``, which sticks a joint at rest: a sliding motion on ``q̇ = 0`` that no error
        control can follow with steps above ``atol / Fc``) is not smooth, unless ``probe`` shows the law
        cancels those terms.
    probe : (callable, ndarray), optional
        The closed loop's right-hand side ``f(s) -> s_dot`` and the start ``s0``, for :func:`cancelled`.
    quantized : bool
        The measurements are quantised (``implementation.quantization``): the law reads them once per step and is
        held over it, as a discontinuous law.
    """
    held_law = sampled or bool(law.discontinuous) or quantized
    per_step = held_law or delayed or not element.continuous
    reasons = []
    if sampled:
        reasons.append("the controller is sampled")
    elif law.discontinuous:
        reasons.append("the law is discontinuous (held over each step)")
    elif quantized:
        reasons.append("the measurements are quantised (read once per step, the law held over it)")
    if delayed:
        reasons.append("the control is delayed (a delay line of whole steps)")
    if not element.continuous:
        reasons.append(f"the {element.kind.replace('_', ' ')} element is evaluated once per step")
    if law.n_memory or element.n_memory:
        reasons.append("the loop has discrete memory updated at every step")
    identity = _identity_projection(law)
    resets = not identity and bool(getattr(law, "project_resets", False))
    if not _constant_gate(law) or not (identity or resets):
        reasons.append("the anti-windup switches or clamps the integrals at each step")
    if noisy:
        reasons.append("the measurement noise changes at every step")
    if getattr(law, "feedforward", None) is not None:
        reasons.append("the law learns a per-step feedforward from trial to trial (its lifted model is the map of "
                       "the step-by-step integration)")
    rough = plant.nonsmooth() if plant is not None and hasattr(plant, "nonsmooth") else ()
    if rough and probe is not None and cancelled(probe[0], probe[1], getattr(plant, "velocities", ())):
        rough = ()
    if rough:
        reasons.append(f"the plant is not smooth ({'; '.join(rough)}) and the law does not cancel it")
    return Regime(held_law=held_law, per_step=per_step, smooth=not reasons, why="; ".join(reasons),
                  resets=resets and not reasons)


PROBE = 1e-12
"""Velocity offset (rad/s) on either side of rest at which :func:`cancelled` compares the loop's derivative."""
JUMP = 1e-6
"""A derivative that changes by more than this (relative to ``1 + |f|``) across ``q̇ = ±PROBE`` jumps there."""


def cancelled(f: Any, s0: np.ndarray, velocities: Any) -> bool:
    """True when the closed loop ``f(s) -> s_dot`` is continuous across ``q̇_j = 0`` at ``s0``, every joint ``j``.

    A plant's Coulomb friction ``Fc sign(q̇)`` is a jump of ``Fc`` in the torque at ``q̇ = 0``; a law that
    compensates it with the same ``Fc sign(q̇)`` of the measured velocity (computed torque on an exact model)
    cancels the jump, and the closed loop is smooth there.  The jump is structural (the same coefficients at
    every configuration), so one probe at the start (at rest) tells; a partial compensation (another ``Fc``, a
    smoothed sign) leaves a jump of the difference, seen here.
    """
    base = np.asarray(f(s0), dtype=float).ravel()
    scale = 1.0 + np.abs(base)
    for j in velocities:
        up, down = s0.copy(), s0.copy()
        up[j] += PROBE
        down[j] -= PROBE
        jump = np.abs(np.asarray(f(up), dtype=float).ravel() - np.asarray(f(down), dtype=float).ravel())
        if np.any(jump > JUMP * scale) or not np.all(np.isfinite(jump)):
            return False
    return True
