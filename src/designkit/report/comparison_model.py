"""What a comparison report says, as one frozen value built from a :class:`~designkit.pipeline.ComparisonResult`.

Page 1: the comparison's verdict (verified only when every controller is), the table of metrics (the
same for every controller, units typeset), each check's verdict per controller, and the overlay figures;
then the comparison's sections (:func:`designkit.comparison.answers.comparison_sections`: the generic one and the
comparison studies'), then each
controller's own report (its sections, figures and checks: the single-spec report model, written in a
sub-folder and linked), the spec and the provenance.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from designkit.comparison.answers import comparison_sections
from designkit.display.figure import Figure
from designkit.report.comparison_figures import comparison_figures

__all__ = ["ComparisonReportModel", "MemberRow", "build_comparison_model"]


@dataclass(frozen=True)
class MemberRow:
    """One controller of the comparison as page 1 lists it.

    Parameters
    ----------
    label, controller : str
        Its label and its family in words.
    verdict, verdict_kind : str
        Its own report's verdict and ``verified`` / ``failed`` / ``undecided``.
    summary : str
        How many required and informational checks pass, fail and are undecided, and the name of each that did
        not pass (:func:`~designkit.comparison.verdicts.check_summary`).
    why : tuple of str
        One sentence per required check that did not pass: the check in words, its status and its detail (the
        informational ones are named in ``summary``; their details are in the controller's own report).
    html, pdf : str
        Its own report's files, relative to the comparison report.
    warnings : tuple of str
        Its run's warnings (weak margins, chattering...), one plain sentence each.
    """

    label: str
    controller: str
    verdict: str
    verdict_kind: str
    summary: str
    why: tuple[str, ...]
    html: str
    pdf: str
    warnings: tuple[str, ...] = ()


@dataclass(frozen=True)
class ComparisonReportModel:
    """Everything a comparison report shows; one model drives both the HTML and the PDF.

    Parameters
    ----------
    title, name, description : str
        Report title, spec name (the output folder), the spec's description.
    verdict, verdict_kind, verdict_summary : str
        ``VERIFIED`` when every controller is, else ``FAILED: <labels>``; the banner colour; the counts.
    verified : bool
        Same as ``ComparisonResult.verified``.
    members : tuple of MemberRow
        Each controller's verdict, warnings and its own report.
    header : tuple of str
        The table's header: ``metric``, ``unit`` and the labels.
    rows : tuple of tuple of str
        One row per metric, the values formatted (``—``: does not apply).
    check_header : tuple of str
        ``controller``, ``check``, ``verdict``.
    check_rows : tuple of tuple of str
        Every check of every controller, in words, with its verdict.
    winners : tuple of str
        Who wins on each metric and by how much.
    figures : tuple of Figure
        The overlay figures.
    sections : tuple of ReportSection
        The comparison's sections (generic, then the comparison studies').
    spec_text, spec_sha256, spec_path : str
        The spec echoed verbatim, its SHA-256, where it was read from.
    provenance, versions : tuple of (name, value)
        Where the report comes from; designkit and dependency versions.
    """

    title: str
    name: str
    description: str
    verdict: str
    verdict_kind: str
    verdict_summary: str
    verified: bool
    members: tuple[MemberRow, ...]
    header: tuple[str, ...]
    rows: tuple[tuple[str, ...], ...]
    check_header: tuple[str, ...]
    check_rows: tuple[tuple[str, ...], ...]
    winners: tuple[str, ...]
    figures: tuple[Figure, ...]
    sections: tuple[Any, ...]
    spec_text: str
    spec_sha256: str
    spec_path: str
    provenance: tuple[tuple[str, str], ...] = ()
    versions: tuple[tuple[str, str], ...] = ()

    @property
    def has_warnings(self) -> bool:
        """Whether any controller's run has a warning (page 1 then lists them, labelled by controller)."""
        return any(m.warnings for m in self.members)

    @property
    def figure_anchors(self) -> tuple[str, ...]:
        """HTML anchor of each figure."""
        return tuple(f.anchor for f in self.figures)


def _member(label: str, result: Any) -> MemberRow:
    from designkit.comparison.verdicts import check_lines, check_summary
    from designkit.families import family
    from designkit.report.verdict import verdict_of

    verdict, kind = verdict_of(tuple(result.checks))
    why = tuple(f"{getattr(c, 'label', '') or c.name}: {c.status}" + (f" — {c.detail}" if c.detail else "")
                for c in result.failed)
    return MemberRow(label, family(result.design.kind).display.label,
                     verdict, kind, check_summary(check_lines(result.checks)), why,
                     f"{label}/report.html", f"{label}/report.pdf", tuple(result.warnings))


def build_comparison_model(result: Any, provenance: Sequence[tuple[str, str]] | None = None, *,
                           studies: bool = True) -> ComparisonReportModel:
    """Build the comparison report of ``result`` (pure: reads the result, returns a new value); with ``studies`` its
    comparison studies' sections and figures are laid out after the generic section (run on first access)."""
    table = result.table
    loaded = result.loaded
    spec = loaded.spec
    members = tuple(_member(label, r) for label, r in zip(result.labels, result.results, strict=True))
    failing = [m.label for m in members if m.verdict_kind != "verified"]
    verdict = "VERIFIED" if not failing else "FAILED: " + ", ".join(failing)
    kinds = {m.verdict_kind for m in members}
    verdict_kind = "verified" if not failing else ("failed" if "failed" in kinds else "undecided")
    verified_count = sum(m.verdict_kind == "verified" for m in members)
    summary = f"{verified_count} of {len(members)} controllers verified on the same task"
    rows = tuple((m.label, table.unit_of(m), *(table.cell(m, r.values.get(m.key)).removesuffix(
        " " + table.unit_of(m)) for r in table.rows)) for m in table.metrics)
    checks = tuple((r.label, c.label + ("" if c.required else " (informational)"), c.status)
                   for r in table.rows for c in r.checks)
    if provenance is None:
        from designkit.report.provenance import provenance_rows

        provenance = provenance_rows()
    return ComparisonReportModel(
        title=f"Comparison of {len(members)} controllers — {spec.name}",
        name=spec.name,
        description=re.sub(r"(?<=\w)\*(?=\w)", "·", " ".join(spec.description.split())),
        verdict=verdict, verdict_kind=verdict_kind, verdict_summary=summary, verified=bool(result.verified),
        members=members,
        header=("metric", "unit", *result.labels), rows=rows,
        check_header=("controller", "check", "verdict"), check_rows=checks,
        winners=tuple(w.sentence for w in table.winners()),
        figures=(*comparison_figures(result), *(f for st in (result.studies if studies else ()) for f in st.figures)),
        sections=comparison_sections(result, studies),
        spec_text=loaded.text, spec_sha256=loaded.sha256, spec_path=str(loaded.path),
        provenance=tuple((str(k), str(v)) for k, v in provenance),
        versions=tuple((str(k), str(v)) for k, v in dict(result.versions).items()),
    )
