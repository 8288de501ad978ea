"""The lab questions of the notes' simulation experiment 1 (appendix A), answered from one run.

The notes ask, for a controller on a manipulator: how well does it perform and how to
characterize performance; what does each gain do and how do gain variations influence
performance; what is the influence of the configuration and of the mass parameters; how
effective is it in neutralizing the intercouplings, centripetal and Coriolis forces.
:func:`lab_answers` answers them for a :class:`~designkit.pipeline.PipelineResult` of a robot
plant, with numbers measured on that run and sentences generated from those numbers (which
gain matters most, whether a coupling is negligible or dominant, whether an error is static...
are decided by the numbers, never written in advance).

What is computed (SI units: s, rad or m, N*m or N, kg*m^2 or kg):

1. **Tracking**: per tracked coordinate (joints, or end-effector coordinates of a task-space
   design) the peak, RMS and final ``|e|``, ``e = x - xD``; per joint the peak ``|u|`` commanded;
   for a step run the overshoot and settling time of
   :func:`~designkit.verification.time_domain.response_metrics`.
2. **Gains**: every gain of ``design.gains`` scaled by 0.5 and 2 (all joints at once), everything
   else equal, re-simulated on the true plant (``build(spec, replace(design, gains=...))``; the
   family's law reads the gains from the design).  The error measure is the peak ``|e|`` for a
   trajectory (the departure from the commanded motion) and the RMS ``|e|`` for a step (the peak
   of a step run is the step itself); with several coordinates each is taken relative to its move.
   Each scaled loop is also linearized on the true plant at the design's operating point (its
   slowest pole).  A run whose state is not finite, whose linearized loop has a pole with
   ``Re > 0``, or whose error over its last :data:`~designkit.analysis.lab.gains.TAIL_FRACTION`
   exceeds :data:`~designkit.analysis.lab.gains.DIVERGENCE_FACTOR` times the nominal peak error or
   the move, is reported as destabilizing the loop.  Bounded: skipped (and said so) above
   :data:`~designkit.analysis.lab.gains.MAX_JOINTS` joints or when the re-simulations are estimated
   above :data:`~designkit.analysis.lab.gains.STUDY_BUDGET_S` s of interpreted evaluation (the
   simulator's own estimate,
   :mod:`designkit.simulation.run`; each scaled law is a new step function run once, so it is
   evaluated interpreted when ``numerics.compile`` is ``auto``).
3. **Configuration**: along the simulated joint path the diagonal ``D_ii(q)`` of the true plant's
   inertia matrix, per joint its range and ratio.  For a design with per-joint loops (designed on
   the simplified link at one configuration ``q*``) the poles of each joint loop at the ends of
   that range (``tau_i = D_ii/f_i`` scales with ``D_ii``); for a model-based design (no loops, an
   ``error_poles`` check) that check's evidence.
4. **Intercoupling**: along the path, with ``qdd`` from finite differences of the simulated
   velocities (``numpy.gradient``), per joint the off-diagonal inertia torque
   ``sum_{j != i} D_ij qdd_j`` plus the Coriolis and centrifugal torque
   ``ID(q, qd, 0) - g(q) - F(qd)`` (the true plant's), against the joint's own inertial torque
   ``D_ii qdd_i``; for a model-based design the **model error torque** ``ID_true(q, qd, qdd) -
   ID_model(q, qd, qdd)`` it does not cancel (zero for an exact model).
5. **Mass parameters**: the evidence of the checks that vary them (``tracking_bounds``,
   ``robust_grid``) and the parameters on which the controller's model differs from the plant.

Everything here is a pure function of the result: the re-simulations are deterministic, so the
same run gives the same answers.

One module per question: :mod:`~designkit.analysis.lab.tracking`, :mod:`~designkit.analysis.lab.gains`,
:mod:`~designkit.analysis.lab.configuration`, :mod:`~designkit.analysis.lab.coupling` (the torques
themselves in :mod:`designkit.models.torques`) and :mod:`~designkit.analysis.lab.mass`;
:mod:`~designkit.analysis.lab.run` holds what they all read from the run and
:mod:`~designkit.analysis.lab.answers` assembles them.
"""

from designkit.analysis.lab.answers import LabAnswers, lab_answers

__all__ = ["LabAnswers", "lab_answers"]

