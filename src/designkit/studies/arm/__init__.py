"""The arm study: how a controller copes with a manipulator, answered from one run of any family on a robot.

The notes ask of a controller on a manipulator (appendix A, the questions of experiment 1 that hold for any law):
how well does it perform and how to characterize performance; what is the influence of the configuration and of
the mass parameters; how effective is it in neutralizing the intercouplings, centripetal and Coriolis forces.
:func:`lab_answers` answers them for a :class:`~designkit.pipeline.PipelineResult` of a robot plant, with numbers
measured on that run and sentences generated from those numbers (whether a coupling is negligible or dominant,
whether an error is static... are decided by the numbers, never written in advance).  What each gain does is the
gain study's (:mod:`designkit.studies.gains`); the classical PID's own questions are experiment 1's
(:mod:`designkit.studies.lab1`).

What is computed (SI units: s, rad or m, N*m or N, kg*m^2 or kg):

1. **Tracking**: per tracked coordinate (joints, or end-effector coordinates of a task-space
   design) the peak, RMS and final ``|e|``, ``e = x - xD``; per joint the peak ``|u|`` commanded;
   for a step run the overshoot and settling time of
   :func:`~designkit.verification.time_domain.response_metrics`.
2. **Configuration**: along the simulated joint path the diagonal ``D_ii(q)`` of the true plant's
   inertia matrix, per joint its range and ratio.  For a design with per-joint loops (designed on
   the simplified link at one configuration ``q*``) the poles of each joint loop at the ends of
   that range (``tau_i = D_ii/f_i`` scales with ``D_ii``); for a model-based design (no loops, an
   ``error_poles`` check) that check's evidence.
3. **Intercoupling**: along the path, with ``qdd`` from finite differences of the simulated
   velocities (``numpy.gradient``), per joint the off-diagonal inertia torque
   ``sum_{j != i} D_ij qdd_j`` plus the Coriolis and centrifugal torque
   ``ID(q, qd, 0) - g(q) - F(qd)`` (the true plant's), against the joint's own inertial torque
   ``D_ii qdd_i``; for a model-based design the **model error torque** ``ID_true(q, qd, qdd) -
   ID_model(q, qd, qdd)`` it does not cancel (zero for an exact model).
4. **Mass parameters**: the evidence of the checks that vary them (``tracking_bounds``,
   ``robust_grid``) and the parameters on which the controller's model differs from the plant.

Everything here is a pure function of the result: the same run gives the same answers.

One module per question: :mod:`~designkit.studies.arm.tracking`,
:mod:`~designkit.studies.arm.configuration`, :mod:`~designkit.studies.arm.coupling` (the torques
themselves in :mod:`designkit.models.torques`) and :mod:`~designkit.studies.arm.mass`;
:mod:`~designkit.studies.arm.run` holds what they all read from the run and
:mod:`~designkit.studies.arm.answers` assembles them.
"""

from typing import Any

from designkit.studies.arm.answers import LabAnswers, lab_answers
from designkit.studies.core.study import Study, StudyContext, StudyResult

__all__ = ["STUDY", "LabAnswers", "lab_answers"]


def _applies(result: Any, family: Any) -> bool:
    plant = result.plant if result.plant is not None else result.design.plant
    return result.simulation is not None and getattr(plant, "kind", None) == "robot"


def _run(ctx: StudyContext) -> StudyResult | None:
    from designkit.studies.arm.section import lab_section

    section = lab_section(ctx.result)
    return None if section is None else StudyResult("arm", section.title, (), section)


STUDY = Study(name="arm", title="The arm: tracking, configuration, mass parameters and coupling", order=10,
              applies=_applies, run=_run)
"""The arm study (module docstring): no variant is run, every answer is measured on the spec's own run."""

