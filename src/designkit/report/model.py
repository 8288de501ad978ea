"""What a report says, as one frozen value built from a :class:`~designkit.pipeline.PipelineResult`.

:func:`build_report_model` is the only place that decides wording, number formats and order;
the HTML and the PDF renderers only lay the :class:`ReportModel` out, so the two formats
always say the same thing.  Numbers are formatted here (gains with 6 significant digits,
check values and certificates with 4) with the helpers of :mod:`designkit.report.certificates`.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.analysis.experiment1 import lab_answers
from designkit.families import family
from designkit.report.certificates import CertificateEntry, fmt_compact, fmt_number, fmt_signed, render_certificate
from designkit.report.figures import Figure, design_figures
from designkit.verification.loop import achieved_zeros

_SYMBOLS = {"tau": "τ", "tau1": "τ1", "tau2": "τ2"}


def unit(text: str) -> str:
    """A unit as the report writes it (``N*m`` -> ``N·m``)."""
    return text.replace("*", "·")


@dataclass(frozen=True)
class ParameterRow:
    """A named value with its unit and meaning."""

    name: str
    value: str
    unit: str
    meaning: str = ""


@dataclass(frozen=True)
class PoleRow:
    """A requested closed-loop pole next to the achieved one closest to it (``loop``: the joint loop, if any)."""

    loop: str
    requested: str
    achieved: str
    error: str
    damping: str
    natural_frequency: str


@dataclass(frozen=True)
class CheckRow:
    """A check as the report shows it (all values already formatted)."""

    name: str
    status: str
    target: str
    achieved: str
    margin: str
    unit: str
    detail: str
    certificate: tuple[CertificateEntry, ...]


@dataclass(frozen=True)
class LabTable:
    """A table of the lab-questions section: ``caption``, ``header`` and ``rows`` (formatted cells)."""

    caption: str
    header: tuple[str, ...]
    rows: tuple[tuple[str, ...], ...]


@dataclass(frozen=True)
class LabSection:
    """A lab question of the notes' experiment 1 and its answer: ``sentences`` and ``tables`` computed from the run."""

    question: str
    sentences: tuple[str, ...]
    tables: tuple[LabTable, ...] = ()


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
    lab_intro : str
        How the lab questions were answered (empty when they are not: not a robot, or no simulation).
    lab : tuple of LabSection
        The notes' lab questions of experiment 1 answered from this run
        (:func:`designkit.analysis.experiment1.lab_answers`).
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
    lab_intro: str = ""
    lab: tuple[LabSection, ...] = ()


# ----------------------------------------------------------------------------- sections


def verdict_of(checks: Sequence[Any]) -> tuple[str, str]:
    """``(verdict, kind)`` of a list of checks; see :class:`ReportModel`."""
    failed = [c.name for c in checks if c.passed is False and getattr(c, "required", True)]
    undecided = [c.name for c in checks if c.passed is None and getattr(c, "required", True)]
    if failed:
        text = "FAILED: " + ", ".join(failed)
        if undecided:
            text += "; UNDECIDED: " + ", ".join(undecided)
        return text, "failed"
    if undecided:
        return "UNDECIDED: " + ", ".join(undecided), "undecided"
    return "VERIFIED", "verified"


def _verdict_summary(checks: Sequence[Any]) -> str:
    n = len(checks)
    if n == 0:
        return "No checks were run: nothing was verified beyond the synthesis itself."
    counts = [sum(c.passed is v for c in checks) for v in (True, False, None)]
    info = sum(not getattr(c, "required", True) for c in checks)
    extra = f" ({info} informational, not part of the verdict)" if info else ""
    return f"{counts[0]} passed, {counts[1]} failed, {counts[2]} undecided, of {n} check{'s' * (n != 1)}{extra}."


def _plant_rows(plant: Any, spec: Any) -> tuple[ParameterRow, ...]:
    rows = [ParameterRow(_SYMBOLS.get(p.name, p.name), fmt_number(p.value, 6), unit(p.unit),
                         f"nominal {p.meaning}".strip()) for p in plant.parameters]
    unc = getattr(spec.plant, "uncertainty", None)
    if unc is not None:
        for name, (lo, hi) in unc.intervals.items():
            par = plant.parameter(name)
            rows.append(ParameterRow(_SYMBOLS.get(name, name), f"[{fmt_number(lo, 6)}, {fmt_number(hi, 6)}]",
                                     unit(par.unit), f"uncertainty interval of the {par.meaning}"))
        rows.append(ParameterRow("grid", str(unc.grid), "points/axis", "robustness lattice resolution"))
        if unc.samples:
            rows.append(ParameterRow("samples", str(unc.samples), "plants", f"seeded random samples (seed {unc.seed})"))
    return tuple(rows)


def _match_poles(requested: Sequence[complex], achieved: np.ndarray) -> list[tuple[complex | None, complex]]:
    remaining = [complex(p) for p in achieved]
    pairs: list[tuple[complex | None, complex]] = []
    for r in requested:
        if not remaining:
            break
        k = min(range(len(remaining)), key=lambda i: abs(remaining[i] - r))
        pairs.append((complex(r), remaining.pop(k)))
    pairs.extend((None, p) for p in remaining)
    return pairs


def _damping(p: complex) -> tuple[str, str]:
    wn = abs(p)
    if wn == 0:
        return "—", "0"
    return fmt_number(-p.real / wn, 4), fmt_number(wn, 4)


def _loop_pole_rows(design: Any, loop: str) -> list[PoleRow]:
    achieved = np.linalg.eigvals(np.asarray(design.closed_loop.A, float))
    achieved = sorted(achieved, key=lambda z: (z.real, z.imag))
    requested = sorted(design.poles, key=lambda z: (z.real, z.imag))
    rows = []
    for req, ach in _match_poles(requested, np.asarray(achieved)):
        zeta, wn = _damping(ach)
        rows.append(PoleRow(
            loop=loop,
            requested=fmt_number(req, 6) if req is not None else "—",
            achieved=fmt_number(ach, 6),
            error=fmt_number(abs(ach - req), 2) if req is not None else "—",
            damping=zeta, natural_frequency=wn,
        ))
    return rows


def _pole_rows(design: Any) -> tuple[PoleRow, ...]:
    if design.loops:
        rows = []
        for name, loop in zip(design.loop_names, design.loops, strict=True):
            rows += _loop_pole_rows(loop, f"{name} (simplified link)")
        coupled = sorted(np.linalg.eigvals(np.asarray(design.closed_loop.A, float)), key=lambda z: (z.real, z.imag))
        for p in coupled:
            zeta, wn = _damping(p)
            rows.append(PoleRow("coupled arm", "—", fmt_number(p, 6), "—", zeta, wn))
        return tuple(rows)
    if design.closed_loop is None:
        return ()
    return tuple(_loop_pole_rows(design, ""))


def _zero_rows(design: Any) -> tuple[ParameterRow, ...]:
    zeros = achieved_zeros(design)
    rows = [ParameterRow("requested zero", fmt_number(z, 6), "1/s", "zero of x1/xD") for z in design.zeros]
    rows += [ParameterRow("achieved zero", fmt_number(z, 6), "1/s", "zero of x1/xD (closed loop)") for z in zeros]
    return tuple(rows)


def _loop_rows(checks: Sequence[Any]) -> tuple[ParameterRow, ...]:
    """Margins as the ``loop_margins`` check measured them (nothing is recomputed here)."""
    check = next((c for c in checks if c.name == "loop_margins"), None)
    if check is None:
        return ()
    rows = []
    for r in check.certificate.get("loops", []):
        where = f" at {r['input']}" if len(check.certificate.get("loops", [])) > 1 else ""
        wgc, wpc, gm = r["gain_crossover_rad_s"], r["phase_crossover_rad_s"], r["gain_margin"]
        pm_note = f"at gain crossover ω = {fmt_number(wgc)} rad/s" if wgc is not None else "no gain crossover"
        if wpc is not None and gm is not None:
            gm_note = ("below 1: conditionally stable, the loop gain may only be reduced by this factor; "
                       if gm < 1 else "factor by which the loop gain may grow; ")
            gm_note += f"phase crossover ω = {fmt_number(wpc)} rad/s"
            gm_text = fmt_number(gm, 4) + (f" ({20 * math.log10(gm):+.3g} dB)" if gm > 0 else "")
        else:
            gm_note, gm_text = "no phase crossover: the phase never reaches -180° at a finite frequency", "∞"
        pm = r["phase_margin_deg"]
        rows += [
            ParameterRow(f"phase margin{where}", fmt_number(pm, 4) if pm is not None else "∞", "deg", pm_note),
            ParameterRow(f"gain margin{where}", gm_text, "ratio", gm_note),
            ParameterRow(f"min |1 + L(jω)|{where}", fmt_number(r["modulus_margin"], 4), "—",
                         "modulus (vector) margin on the frequency grid"),
        ]
    return tuple(rows)


def _gain_value(value: Any) -> str:
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 0:
        return fmt_number(float(arr), 6)
    if arr.ndim == 1:
        return "; ".join(f"joint {j + 1}: {fmt_number(v, 6)}" for j, v in enumerate(arr))
    return "; ".join("[" + ", ".join(fmt_number(v, 6) for v in row) + "]" for row in arr)


def _check_row(check) -> CheckRow:
    achieved = check.achieved
    return CheckRow(
        name=check.name,
        status=check.status,
        target=check.target or "—",
        achieved=achieved if isinstance(achieved, str) else fmt_number(achieved, 4),
        margin=fmt_signed(check.margin, 4),
        unit=check.unit,
        detail=check.detail,
        certificate=render_certificate(check.certificate),
    )


def _same(a: Mapping[str, Any], b: Mapping[str, Any]) -> bool:
    try:
        return bool(a == b)
    except (ValueError, TypeError):  # e.g. arrays in a certificate: compare no further
        return False


def _check_rows(checks: Sequence[Any]) -> tuple[CheckRow, ...]:
    """Rows of the checks table; a certificate identical to an earlier check's is not repeated."""
    rows: list[CheckRow] = []
    for k, check in enumerate(checks):
        row = _check_row(check)
        earlier = next((c for c in checks[:k] if check.certificate and _same(c.certificate, check.certificate)),
                       None)
        if earlier is not None:
            row = dataclasses.replace(row, certificate=(CertificateEntry("certificate", f"same as {earlier.name}"),))
        rows.append(row)
    return tuple(rows)


def _simulation_rows(simulation) -> tuple[ParameterRow, ...]:
    if simulation is None:
        return ()
    rows = [ParameterRow("kind", str(simulation.kind), "")]
    t = np.asarray(simulation.time, float)
    if t.size:
        rows.append(ParameterRow("samples", f"{t.size} over [{fmt_number(t[0])}, {fmt_number(t[-1])}]", "s"))
    for key, value in dict(simulation.settings).items():
        rows.append(ParameterRow(str(key), fmt_compact(value, 6), ""))
    return tuple(rows)


def _lab_sections(answers: Any) -> tuple[str, tuple[LabSection, ...]]:
    """The lab questions' section from :class:`~designkit.analysis.experiment1.LabAnswers` (None: no section)."""
    if answers is None:
        return "", ()
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

    st = answers.gains
    gain_tables = []
    if st.effects:
        step = any(r.overshoot is not None for e in st.effects for r in e.runs)
        first = next(r for r in st.effects[0].runs if r.scale == 1.0)
        kind = "RMS |e|" if st.measure.startswith("RMS") else "peak |e|"
        poles = any(r.abscissa is not None for e in st.effects for r in e.runs)
        header = ("Gain", "Scale", "Loop", *(("max Re(pole) (1/s)",) if poles else ()),
                  *(f"{kind} {c} ({unit(u)})" for c, u in zip(st.coordinates, st.units, strict=True)),
                  f"peak |{first.peak_torque_input}| ({unit(first.peak_torque_unit)})",
                  *(("Overshoot (%)", "Settling (s)") if step else ()))
        rows = []
        for e in st.effects:
            for r in e.runs:
                values = r.rms_error if kind == "RMS |e|" else r.peak_error
                cells = [f(v) for v in values] if r.ok else ["—"] * len(st.coordinates)
                status = "as designed" if r.scale == 1.0 else ("stable" if r.ok else r.status)
                rows.append((e.name, f"× {r.scale:g}", status, *((f(r.abscissa),) if poles else ()), *cells,
                             f(r.peak_torque) if r.ok else "—",
                             *((f(r.overshoot), f(r.settling_time)) if step else ())))
        gain_tables.append(LabTable("Each gain scaled on every joint, everything else equal, on the true plant "
                                    "(the × 1 rows are the run above)", header, tuple(rows)))
    sections.append(LabSection("What is the function of each gain? How do gain variations influence performance?",
                               (*st.sentences, *(e.sentence for e in st.effects)), tuple(gain_tables)))

    cf = answers.configuration
    loops = any(j.design_value is not None for j in cf.joints)
    header = ("Joint", "min D_ii", "at t (s)", "max D_ii", "at t (s)", "max/min", "Unit",
              *(("D_ii(q*)", "loop poles at min D_ii (1/s)", "at max D_ii (1/s)") if loops else ()))
    rows = tuple((str(j.joint), f(j.low), f(j.low_at), f(j.high), f(j.high_at), f(j.ratio), unit(j.unit),
                  *((f(j.design_value), ", ".join(f(p) for p in sorted(j.poles_at_low, key=_pole_key)),
                     ", ".join(f(p) for p in sorted(j.poles_at_high, key=_pole_key))) if loops else ()))
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
    intro = (f"The questions of the notes' simulation experiment 1 (appendix A), answered for this design "
             f"({answers.controller}) from the simulation above: every number is measured on this run and every "
             "sentence is written from those numbers; the gain study re-simulates the same scenario with one gain "
             "scaled at a time.")
    return intro, tuple(sections)


def _pole_key(p: complex) -> tuple[float, float]:
    return (p.real, p.imag)


def build_report_model(result: Any) -> ReportModel:
    """Build the report of a pipeline result (pure: reads ``result``, returns a new value).

    Parameters
    ----------
    result : designkit.pipeline.PipelineResult
        Spec, design, checks, simulation and versions of one run.

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
    lab_intro, lab = _lab_sections(lab_answers(result))
    return ReportModel(
        title=f"{label} — {spec.name}",
        name=spec.name,
        description=" ".join(spec.description.split()),
        verdict=verdict,
        verdict_kind=kind,
        verdict_summary=_verdict_summary(checks),
        verified=bool(result.verified),
        spec_text=loaded.text,
        spec_sha256=loaded.sha256,
        spec_path=str(loaded.path),
        versions=tuple((str(k), str(v)) for k, v in dict(result.versions).items()),
        controller=f"{label} ({design.kind})",
        plant_equation="\n".join(plant.equations()) + "   (" + ", ".join(
            f"{s.name} {unit(s.unit)}" for s in (*plant.states, *plant.inputs)) + ")",
        plant_parameters=_plant_rows(plant, spec),
        formulas=(*display.law, *design.formulas),
        gains=tuple(ParameterRow(k, _gain_value(v), unit(design.gains.unit(k)), design.gains.meaning(k))
                    for k, v in design.gains.items()),
        poles=_pole_rows(design),
        zeros=_zero_rows(design),
        loop=_loop_rows(checks),
        notes=tuple(design.notes),
        checks=_check_rows(checks),
        simulation=_simulation_rows(result.simulation),
        figures=design_figures(result),
        lab_intro=lab_intro,
        lab=lab,
    )


__all__ = [
    "CertificateEntry",
    "CheckRow",
    "Figure",
    "LabSection",
    "LabTable",
    "ParameterRow",
    "PoleRow",
    "ReportModel",
    "build_report_model",
    "unit",
    "verdict_of",
]
