"""Why a run failed: shortfalls, divergence, limit cycles, linear instability, solver failures.

:func:`diagnose` (:mod:`~designkit.analysis.diagnosis.framework`) reads a
:class:`~designkit.pipeline.PipelineResult` and returns a frozen :class:`Diagnosis` that the report renders
at the top ("why it failed").  Every sentence is generated from numbers computed here from the run; nothing
is written in advance.  Numbers are formatted with :func:`designkit.display.numbers.fmt_number` (four
significant digits), so they match the rest of the report; torques are written ``N·m``.

What is diagnosed (SI units: s, rad, rad/s, N·m; derivations in ``docs/diagnosis.md``):

* **Shortfall** of every failing or undecided *required* check: from its ``target`` (``"<= 5 %"``) and
  signed ``margin`` (negative when violated by ``|margin|``), absolute and relative to the limit.
* **Divergence** of the nonlinear run (:func:`~designkit.analysis.diagnosis.divergence.divergence_of`):
  non-finite samples, an integrator failure, or an error envelope that keeps growing -- the largest ``|x -
  xD|`` over the last :data:`~designkit.analysis.diagnosis.divergence.TAIL_FRACTION` of the run exceeds
  :data:`~designkit.analysis.diagnosis.divergence.GROWTH_FACTOR` times the error scale (the commanded step,
  the move, or the initial error) and the one over the preceding quarter.  Its onset is when ``|x - xD|``
  first exceeds that scale.  With a saturation element: from when ``|u_command|`` exceeds the limit, for
  which fraction of the run, and from when the saturation's gain ``|u_applied / u_command|`` stays below the
  loop's lower gain margin (a conditionally stable loop goes unstable when its gain drops below it); whether
  the integrator has an anti-windup.
* **The settling time the actuator limit allows** on the link ``Km / (s (tau s + 1))`` under ``|u| <= U``
  (:func:`~designkit.analysis.elements.saturation.minimum_settling_time`, time-optimal bang-bang bound) and
  the limit a required settling time needs
  (:func:`~designkit.analysis.elements.saturation.limit_for_settling_time`).
* **Limit cycle** (:func:`~designkit.analysis.diagnosis.divergence.measure_oscillation`,
  :func:`~designkit.analysis.elements.relay.predict_cycle`): a sustained, regular oscillation of the
  position over the last :data:`~designkit.analysis.diagnosis.divergence.CYCLE_WINDOW` of the run; for a
  relay with hysteresis its describing-function prediction
  (:func:`~designkit.analysis.elements.relay.relay_describing_function`,
  :func:`~designkit.analysis.elements.relay.relay_harmonic_balance`) on the loop transfer ``L(s)`` seen by
  the element (the design's loop broken at the plant input,
  :func:`designkit.verification.loop.loop_frequency_response`), and the exact symmetric periodic solution of
  the relay loop (:func:`~designkit.analysis.elements.relay.relay_periodic_solution`, the Tsypkin/Hamel
  switching condition), which tells how much of the gap is the describing function's approximation.
* **Instability of the linear loop**: closed-loop poles with ``Re >= 0``.
* **A solver that did not converge**: an undecided or failed check whose certificate holds a
  ``solver_status`` other than ``"optimal"``.
* **A model mismatch of a model-based law**
  (:func:`~designkit.families.computed_torque.model_error.model_error_prediction`; gains ``K1``, ``K2``, an
  ``error_poles`` check, joints tracked, a controller model that differs from the true plant): the
  model-error torque ``tau_plant - tau_model`` along the run
  (:func:`designkit.models.torques.model_error_torque`) drives ``e'' + K2 e' + K1 e = M^^-1 (tau_plant -
  tau_model)``; its quasi-static response ``(M^ K1)^-1 (tau_plant - tau_model)`` against the measured error
  (joint and instant of the worst), ``(M^ K1)^-1 (g - g^)`` at rest at the final configuration
  (:func:`~designkit.families.computed_torque.model_error.static_model_error`), the worst corner or sample of
  ``tracking_bounds`` (its certificate); fixes: the factor on ``K1`` that brings the predicted error to the
  limit (the error scales as ``1/K1``; poles scale as its square root at the same damping), or the plant's
  payload or parameter values in ``controller.model``.
* **A path near a singular configuration** (``singularity`` check, from its certificate): condition number,
  instant, configuration, the joint whose motion raises ``1/kappa`` fastest; fixes: damped least squares
  with ``lambda = sigma_max / (2 kappa_max)``
  (:func:`~designkit.verification.diagnoses.singularity.damping_for_condition`: the check's bound ``1/(2
  lambda)`` is then the ``1/sigma_min`` the exact inverse has at the allowed condition number), or the
  first-order move of that joint that brings the condition to the limit.
* **Linear versus nonlinear**: the metrics of :func:`~designkit.verification.time_domain.response_metrics`
  on the ideal linear response (:func:`~designkit.simulation.linear.linear_response`, same instants,
  reference and perturbation, no nonlinear element, noise, delay or sampling) and on the simulation.

* **Every proposed fix re-simulated** (:func:`~designkit.analysis.diagnosis.fixes.check_fixes`): each fix
  sentence the findings give that reads as a change of the spec
  (:mod:`~designkit.analysis.diagnosis.remedies`) is re-run through the pipeline
  (:mod:`~designkit.analysis.diagnosis.resimulate`: design, checks, simulation on the true plant, at most
  :data:`~designkit.analysis.diagnosis.resimulate.MAX_FIX_RUNS` runs); ``Diagnosis.proposed`` says per fix the
  changed values, each previously failing requirement measured against its limit, the loop margins and whether
  every required check passes.  The report numbers only those that pass.

Each concept lives with what it explains: an element's analysis in its module of
:mod:`designkit.analysis.elements` (:mod:`~designkit.analysis.elements.saturation`,
:mod:`~designkit.analysis.elements.relay`), a family's in the family
(:mod:`designkit.families.computed_torque.model_error`, named in ``Family.diagnoses``), a check's beside
the check (:mod:`designkit.verification.diagnoses.singularity`, named in the rule's ``diagnose``); what is
generic stays here: :mod:`~designkit.analysis.diagnosis.divergence` (measuring the run) and
:mod:`~designkit.analysis.diagnosis.comparison` (linear against nonlinear).  The values of a diagnosis are in
:mod:`~designkit.analysis.diagnosis.findings`, and :mod:`~designkit.analysis.diagnosis.framework` asks the
owners; it names no element, check or family.
"""

from designkit.analysis.diagnosis.findings import Diagnosis, Finding, LimitCycle
from designkit.analysis.diagnosis.framework import diagnose

__all__ = ["Diagnosis", "Finding", "LimitCycle", "diagnose"]
