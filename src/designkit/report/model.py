"""What a report says, as one frozen value built from a :class:`~designkit.pipeline.PipelineResult`.

:func:`build_report_model` assembles the :class:`ReportModel` from the section modules of this
package, which decide wording, number formats and order: :mod:`~designkit.report.verdict`,
:mod:`~designkit.report.compliance`, :mod:`~designkit.report.why`, :mod:`~designkit.report.design_section`,
:mod:`~designkit.report.check_rows`, :mod:`~designkit.report.simulation_rows`,
the studies' sections (:mod:`designkit.studies`) and the figures of :mod:`designkit.report.figures`.  The HTML and
the PDF renderers only lay the model out, so the two formats always say the same thing.  Numbers are
formatted with :mod:`designkit.display.numbers` (gains with 6 significant digits, check values and
certificates with 4).
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from designkit.display.figure import Figure
from designkit.display.numbers import plain_complex, sentence_units, unit
from designkit.display.typeset import Equation
from designkit.families import check_rules, family
from designkit.report.check_rows import check_rows
from designkit.report.compliance import compliance_row
from designkit.report.design_section import (
    equations,
    gain_value,
    linearization_note,
    loop_rows,
    plant_rows,
    pole_rows,
    zero_rows,
)
from designkit.report.figures import design_figures
from designkit.report.labels import glossary
from designkit.report.rows import (
    CheckRow,
    ComplianceRow,
    MetricRow,
    ParameterRow,
    PoleRow,
    Section,
    WhyFix,
    WhyRow,
)
from designkit.report.simulation_rows import simulation_rows
from designkit.report.verdict import verdict_of, verdict_summary
from designkit.report.why import diagnose_run, metric_rows, why_section

__all__ = ["ReportModel", "build_report_model"]


@dataclass(frozen=True)
class ReportModel:
    """Everything a report shows; one model drives both the HTML and the PDF.

    Parameters
    ----------
    title, name, description : str
        Report title, spec name (also the output folder) and the spec's description.
    verdict : str
        ``"VERIFIED"``, ``"FAILED: <failed checks>"`` (plus ``"; UNDECIDED: ..."`` when some are
        undecided too) or ``"UNDECIDED: <undecided checks>"``.
    verdict_kind : str
        ``"verified"``, ``"failed"`` or ``"undecided"`` (drives the banner colour).
    verdict_summary : str
        Counts of passed, failed and undecided checks.
    verified : bool
        Same as ``PipelineResult.verified``.
    spec_text, spec_sha256, spec_path : str
        The spec echoed verbatim, its SHA-256 and where it was read from.
    versions : tuple of (name, version)
        designkit and dependency versions.
    controller : str
        Controller family in words and its ``kind``.
    plant_equation : str
        Plant model in plain text.
    plant_parameters : tuple of ParameterRow
        Nominal plant parameters and the uncertainty box, with units.
    formulas : tuple of str
        Design equations (plain text).
    gains : tuple of ParameterRow
        Gains with units.
    poles : tuple of PoleRow
        Requested against achieved closed-loop poles.
    zeros : tuple of ParameterRow
        Requested against achieved zeros of ``x1/xD``.
    loop : tuple of ParameterRow
        Margins of the loop broken at the plant input.
    notes : tuple of str
        Choices made on the user's behalf.
    checks : tuple of CheckRow
        Verification checks in report order.
    simulation : tuple of ParameterRow
        Simulation settings (empty when no simulation ran).
    figures : tuple of Figure
        Figures in report order.
    sections : tuple of ReportSection
        Sections contributed by the modules that own them, laid out after the figures: the family's own
        (``Family.sections``: e.g. the MRAC simulator's questions), then the studies' (:mod:`designkit.studies`:
        the arm's questions, the gain study, the boundary, the lab experiments), in report order.
    linearization : str
        What the design's closed loop is, when it is not simply the law linearized (``frozen``: with the
        adaptation held at its initial values; ``none``: no linear loop, and why), with the requested poles.
    why : tuple of WhyRow
        One row per required check that failed or is undecided (empty for a verified design).  A fix
        shared by several rows is in ``why_fixes`` and the rows refer to it (``fix_refs``).
    why_fixes : tuple of WhyFix
        Fixes shared by several rows, numbered, shown once below the table.
    why_note : str
        Where the causes come from (or why there are none).
    divergence, limit_cycle : str
        Sentences of the diagnosis: the nonlinear loop diverged; a limit cycle was measured (and predicted).
    linear_vs_nonlinear : tuple of MetricRow
        The same metrics on the linear model and in the nonlinear simulation.
    compliance, informational : tuple of ComplianceRow
        Verdict-deciding checks, and checks reported for information only (``required=False``).
    glossary : tuple of (term, meaning)
        Words of the compliance table and the certificates.
    equations : tuple of Equation
        Plant, control law, closed loop, design formulas and the loop transfer of the Bode plot, typeset.
    provenance : tuple of (name, value)
        Where the report comes from (:func:`designkit.report.provenance.provenance_rows`).
    figure_anchors : tuple of str
        HTML anchor of each figure (``fig-<filename stem>``), in figure order.
    contents : tuple of Section
        Table of contents.
    """

    title: str
    name: str
    description: str
    verdict: str
    verdict_kind: str
    verdict_summary: str
    verified: bool
    spec_text: str
    spec_sha256: str
    spec_path: str
    versions: tuple[tuple[str, str], ...]
    controller: str
    plant_equation: str
    plant_parameters: tuple[ParameterRow, ...]
    formulas: tuple[str, ...]
    gains: tuple[ParameterRow, ...]
    poles: tuple[PoleRow, ...]
    zeros: tuple[ParameterRow, ...]
    loop: tuple[ParameterRow, ...]
    notes: tuple[str, ...]
    checks: tuple[CheckRow, ...]
    simulation: tuple[ParameterRow, ...]
    figures: tuple[Figure, ...]
    sections: tuple[Any, ...] = ()
    linearization: str = ""
    why: tuple[WhyRow, ...] = ()
    why_note: str = ""
    why_fixes: tuple[WhyFix, ...] = ()
    divergence: str = ""
    limit_cycle: str = ""
    linear_vs_nonlinear: tuple[MetricRow, ...] = ()
    compliance: tuple[ComplianceRow, ...] = ()
    informational: tuple[ComplianceRow, ...] = ()
    glossary: tuple[tuple[str, str], ...] = ()
    equations: tuple[Equation, ...] = ()
    provenance: tuple[tuple[str, str], ...] = ()
    figure_anchors: tuple[str, ...] = ()
    contents: tuple[Section, ...] = ()
    warnings: tuple[str, ...] = ()


# ----------------------------------------------------------------------------- contents


def _contents(model_parts: Mapping[str, Any]) -> tuple[Section, ...]:
    sections = []
    if model_parts["why"]:
        sections.append(Section("why", "Why it failed"))
    sections.append(Section("compliance", "Requirement compliance"))
    if model_parts["linear_vs_nonlinear"] or model_parts["limit_cycle"]:
        sections.append(Section("engineering", "Linear model against the nonlinear simulation"))
    sections += [Section("design", "Design"), Section("figures", "Figures")]
    sections += [Section(s.anchor, s.title) for s in model_parts["sections"]]
    if model_parts["simulation"]:
        sections.append(Section("simulation", "Simulation settings"))
    sections += [Section("certificates", "Appendix A: check details and certificates"),
                 Section("glossary", "Appendix B: glossary"),
                 Section("spec", "Appendix C: spec"),
                 Section("provenance", "Appendix D: provenance and versions")]
    return tuple(sections)


def _divergence(diagnosis: Any) -> str:
    """The lead of "why it failed": the root cause first, then how the run diverged."""
    if diagnosis is None or isinstance(diagnosis, Exception):
        return ""
    parts = [getattr(diagnosis, "root_cause", "")]
    if diagnosis.diverged:
        parts.append(diagnosis.divergence)
    return unit(" ".join(p for p in parts if p))


def _with_study_fixes(why: tuple[WhyRow, ...], fixes: tuple[WhyFix, ...], result: Any,
                      studies: tuple[Any, ...]) -> tuple[WhyFix, ...]:
    """The shared fixes of "why it failed", then the studies' recommendations that change a spec setting (each
    already run with every required check passing, with its neighbourhood), numbered after them."""
    if not why:
        return fixes
    from designkit.studies import study_fixes

    extra = study_fixes(result, studies)
    labels = tuple(r.label for r in why)
    return (*fixes, *(WhyFix(len(fixes) + k + 1, unit(f.text), labels) for k, f in enumerate(extra)))


def _studies(result: Any) -> tuple[Any, ...]:
    """The run's studies: those the pipeline's result carries (computed once for the report and ``--json``), or run
    here for a result that does not carry them."""
    studies = getattr(result, "studies", None)
    if studies is None:
        from designkit.studies import run_studies

        studies = run_studies(result)
    return tuple(studies)


def _scope_sentence(result: Any) -> str:
    """What the verdict is on, one sentence: the controller as implemented (``implementation``), or, for a switching
    law run without it, that the verdict holds for a continuous-time switch (the simulator's settings)."""
    settings = dict(getattr(getattr(result, "simulation", None), "settings", None) or {})
    if settings.get("implementation"):
        return sentence_units(f"The verdict is on the controller {settings['implementation']}.")
    scope = str(settings.get("scope") or "")
    return sentence_units(scope[:1].upper() + scope[1:] + ".") if scope else ""


def build_report_model(result: Any, provenance: Sequence[tuple[str, str]] | None = None, *,
                       processes: int = 1, studies: bool = True) -> ReportModel:
    """Build the report of a pipeline result (pure: reads ``result``, returns a new value).

    Parameters
    ----------
    result : designkit.pipeline.PipelineResult
        Spec, design, checks, simulation and versions of one run.
    provenance : sequence of (str, str), optional
        The provenance rows (default: :func:`designkit.report.provenance.provenance_rows`).
    processes : int
        2 draws the figures on two cores (:func:`designkit.report.parallel.run_tasks`: a forked child,
        only when this process runs no other thread); the report is the same.
    studies : bool
        Lay out the run's studies (:mod:`designkit.studies`: run on first access, the result keeps them); False
        leaves them out.

    Returns
    -------
    ReportModel
        Every section of the report, formatted, with the figures as SVG text.
    """
    loaded, design = result.loaded, result.design
    spec = loaded.spec
    checks = tuple(result.checks)
    verdict, kind = verdict_of(checks)  # same rule as PipelineResult.verified: undecided is no pass
    display = family(design.kind).display
    label = display.label
    plant = design.plant
    fam = family(design.kind)
    studies = _studies(result) if studies else ()
    sections = tuple(s for s in (*(make(result) for make in fam.sections), *(st.section for st in studies))
                     if s is not None)
    figures = design_figures(result, processes=processes)
    figures = (*figures, *(f for st in studies for f in st.figures))
    diagnosis = diagnose_run(result) if checks else None
    why, why_note, why_fixes = why_section(result, diagnosis)
    why_fixes = _with_study_fixes(why, why_fixes, result, studies)
    if isinstance(diagnosis, Exception):
        diagnosis = None
    rows = [compliance_row(c, figures) for c in checks]
    simulation = simulation_rows(result.simulation, plant)
    if provenance is None:
        from designkit.report.provenance import provenance_rows

        provenance = provenance_rows()
    limit_cycle = getattr(diagnosis, "limit_cycle", None)
    parts = {
        "why": why, "linear_vs_nonlinear": metric_rows(diagnosis),
        "limit_cycle": limit_cycle.sentence if limit_cycle is not None else "", "sections": sections,
        "simulation": simulation,
    }
    return ReportModel(
        title=f"{label} — {spec.name}",
        name=spec.name,
        description=re.sub(r"(?<=\w)\*(?=\w)", "·", " ".join(spec.description.split())),
        verdict=verdict,
        verdict_kind=kind,
        verdict_summary=" ".join(filter(None, (verdict_summary(checks), _scope_sentence(result)))),
        warnings=tuple(getattr(result, "warnings", ())),
        verified=bool(result.verified),
        spec_text=loaded.text,
        spec_sha256=loaded.sha256,
        spec_path=str(loaded.path),
        versions=tuple((str(k), str(v)) for k, v in dict(result.versions).items()),
        controller=f"{label} ({design.kind})",
        plant_equation="\n".join(plant.equations()) + "   (" + ", ".join(
            f"{s.name} {unit(s.unit)}" for s in (*plant.states, *plant.inputs)) + ")",
        plant_parameters=plant_rows(plant, spec, lattice=any(c.name == "robust_grid" for c in checks)),
        formulas=(*display.law_lines(design), *design.formulas),
        gains=tuple(ParameterRow(k, gain_value(v), unit(design.gains.unit(k)), design.gains.meaning(k))
                    for k, v in design.gains.items()),
        poles=pole_rows(design),
        zeros=zero_rows(design),
        loop=loop_rows(checks),
        notes=tuple(plain_complex(sentence_units(n)) for n in design.notes),
        checks=check_rows(checks),
        simulation=simulation,
        figures=figures,
        sections=sections,
        linearization=linearization_note(design),
        why=why,
        why_note=why_note,
        why_fixes=why_fixes,
        divergence=_divergence(diagnosis),
        limit_cycle=parts["limit_cycle"],
        linear_vs_nonlinear=parts["linear_vs_nonlinear"],
        compliance=tuple(r for r in rows if r.required),
        informational=tuple(r for r in rows if not r.required),
        glossary=glossary(check_rules(design.kind)),
        equations=equations(design, display, plant),
        provenance=tuple((str(k), str(v)) for k, v in provenance),
        figure_anchors=tuple(f.anchor for f in figures),
        contents=_contents(parts),
    )
