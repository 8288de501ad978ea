"""The arm's section of a report: tracking, configuration, mass parameters and coupling answered from the run.

:func:`lab_section` turns :class:`~designkit.studies.arm.LabAnswers` into a
:class:`~designkit.display.section.ReportSection`, which the report lays out as it lays out the sections the
families contribute.
"""

from __future__ import annotations

import math
from typing import Any

from designkit.display.numbers import fmt_number, fmt_poles, unit
from designkit.display.section import Question as LabSection
from designkit.display.section import ReportSection
from designkit.display.section import Table as LabTable

__all__ = ["lab_section"]


def lab_section(result: Any) -> ReportSection | None:
    """The arm's section of a run (None when the run has none: not a robot, or no simulation)."""
    from designkit.studies.arm import lab_answers

    answers = lab_answers(result)
    if answers is None:
        return None
    f = fmt_number
    tr = answers.tracking
    tables = []
    if tr.coordinates:
        tables.append(LabTable("Tracking error e = x − xD per tracked coordinate",
                               ("Coordinate", "Move", "Peak |e|", "at t (s)", "RMS |e|", "Final |e|", "Unit"),
                               tuple((c.name, f(c.move), f(c.peak), f(c.peak_at), f(c.rms), f(c.final), unit(c.unit))
                                     for c in tr.coordinates)))
    if tr.torques:
        tables.append(LabTable("Peak commanded torque per joint", ("Input", "Peak |u|", "at t (s)", "Unit"),
                               tuple((q.name, f(q.peak), f(q.at), unit(q.unit)) for q in tr.torques)))
    sections = [LabSection("How well does the controller perform? How to characterize its performance?",
                           tr.sentences, tuple(tables))]

    cf = answers.configuration
    loops = any(j.design_value is not None for j in cf.joints)
    header = ("Joint", "min D_ii", "at t (s)", "max D_ii", "at t (s)", "max/min", "Unit",
              *(("D_ii(q*)", "loop poles at min D_ii (1/s)", "at max D_ii (1/s)") if loops else ()))
    rows = tuple((str(j.joint), f(j.low), f(j.low_at), f(j.high), f(j.high_at), f(j.ratio), unit(j.unit),
                  *((f(j.design_value), fmt_poles(j.poles_at_low, 4), fmt_poles(j.poles_at_high, 4)) if loops else ()))
                 for j in cf.joints)
    sections.append(LabSection(
        "What is the influence of the working configuration?", cf.sentences,
        (LabTable("Diagonal of the true plant's inertia matrix along the simulated path", header, rows),)
        if rows else ()))
    sections.append(LabSection("What is the influence of the mass parameters?", answers.mass))

    cp = answers.coupling
    model_based = any(j.model_error is not None for j in cp.joints)
    header = ("Joint", "Off-diagonal Σ D_ij q̈_j", "Coriolis and centrifugal", "Coupling (sum)", "at t (s)",
              "Own D_ii q̈_i", "Coupling/own", *(("Model error ID_plant − ID_model",) if model_based else ()),
              "Unit")
    rows = tuple((str(j.joint), f(j.off_diagonal), f(j.coriolis), f(j.coupling), f(j.coupling_at), f(j.own_inertial),
                  f"{f(100 * j.ratio, 3)} %" if math.isfinite(j.ratio) else "∞",
                  *((f(j.model_error),) if model_based else ()), unit(j.unit)) for j in cp.joints)
    stride = f", one instant in {cp.stride}" if cp.stride > 1 else ""
    sections.append(LabSection(
        "How effective is the controller in neutralizing intercouplings, centripetal and Coriolis forces?",
        cp.sentences,
        (LabTable(f"Peak torques along the simulated path (q̈ by finite differences of the simulated velocities"
                  f"{stride})", header, rows),) if rows else ()))
    intro = (f"How this design ({answers.controller}) copes with the arm, answered from the simulation above: its "
             "tracking, the configuration it moves through, its mass parameters and the couplings between joints. "
             "Every number is measured on this run and every sentence is written from those numbers.")
    return ReportSection("arm", "The arm: tracking, configuration, mass parameters and coupling", intro,
                         tuple(sections))
