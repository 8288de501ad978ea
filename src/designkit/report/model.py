"""What a report says, as one frozen value built from a :class:`~designkit.pipeline.PipelineResult`.

:func:`build_report_model` is the only place that decides wording, number formats and order;
the HTML and the PDF renderers only lay the :class:`ReportModel` out, so the two formats
always say the same thing.  Numbers are formatted here (gains with 6 significant digits,
check values and certificates with 4) with the helpers of :mod:`designkit.report.certificates`.
"""

from __future__ import annotations

import dataclasses
import hashlib
import math
import re
import unicodedata
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.analysis.experiment1 import lab_answers
from designkit.families import family
from designkit.report.certificates import (
    CertificateEntry,
    fmt_compact,
    fmt_number,
    fmt_signed,
    human_key,
    render_certificate,
)
from designkit.report.figures import Figure, design_figures
from designkit.verification.loop import achieved_zeros

_SYMBOLS = {"tau": "τ", "tau1": "τ1", "tau2": "τ2"}
_UNIT_STAR = re.compile(r"(?<=[A-Za-z)])\*(?=[A-Za-z(])")  # N*m -> N·m inside sentences


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
    """A check as the report shows it (all values already formatted); ``label`` is its name in words."""

    name: str
    status: str
    target: str
    achieved: str
    margin: str
    unit: str
    detail: str
    certificate: tuple[CertificateEntry, ...]
    label: str = ""
    required: bool = True
    anchor: str = ""


def check_anchor(name: str) -> str:
    """The HTML id and Typst label of a check's details (``check-<name>``, other characters as ``-``)."""
    safe = re.sub(r"[^A-Za-z0-9_-]", "-", name)
    if safe != name:  # distinct names must keep distinct anchors
        safe += "-" + hashlib.sha256(name.encode("utf-8")).hexdigest()[:8]
    return "check-" + safe


@dataclass(frozen=True)
class ComplianceRow:
    """One row of the requirement-compliance table (all cells formatted, units written ``N·m``).

    ``limit`` is the requirement as an inequality (``≤ 5 N·m``) or in words; ``margin`` the signed
    distance to it (positive: met) and ``margin_percent`` that distance relative to the limit
    (``""`` when the limit is not a number).  ``evidence`` is the HTML anchor of the first figure
    that shows this check's evidence (``""``: none) and ``evidence_title`` its title.
    """

    name: str
    label: str
    status: str
    required: bool
    limit: str
    achieved: str
    margin: str
    margin_percent: str
    evidence: str
    evidence_title: str
    detail: str
    anchor: str = ""


@dataclass(frozen=True)
class WhyRow:
    """Why a required check failed or is undecided: the requirement, the achieved value, the
    shortfall (absolute and relative to the limit), the diagnosed cause and the fix."""

    check: str
    label: str
    status: str
    requirement: str
    achieved: str
    shortfall: str
    shortfall_percent: str
    cause: str
    fix: str
    fix_refs: tuple[int, ...] = ()


@dataclass(frozen=True)
class WhyFix:
    """A fix shared by several rows of "why it failed", shown once below the table.

    Parameters
    ----------
    number : int
        1-based; rows refer to it as "fix <number>" (their ``fix_refs``).
    text : str
        The fix, a sentence with its numbers and units.
    checks : tuple of str
        Labels of the rows it applies to, in row order.
    """

    number: int
    text: str
    checks: tuple[str, ...]


@dataclass(frozen=True)
class MetricRow:
    """A metric of the linear model next to the same metric of the nonlinear simulation."""

    metric: str
    unit: str
    linear: str
    nonlinear: str


@dataclass(frozen=True)
class MathToken:
    """A token of a typeset formula: ``kind`` is ``"mi"`` (identifier), ``"mn"`` (number),
    ``"mo"`` (operator), ``"sep"`` (a comma or semicolon between two formulas of one line, set
    with a wide space) or ``"mtext"`` (words); ``sub``/``sup`` are attached sub- and superscripts."""

    kind: str
    text: str
    sub: str = ""
    sup: str = ""


@dataclass(frozen=True)
class MathFrac:
    """A fraction of two token rows."""

    num: tuple[MathToken | MathFrac, ...]
    den: tuple[MathToken | MathFrac, ...]


@dataclass(frozen=True)
class Equation:
    """A formula to typeset: ``label`` (what it is), ``nodes`` (tokens and fractions), ``note``
    (words shown next to it) and ``text`` (the plain-text original, for alt text and search)."""

    label: str
    nodes: tuple[MathToken | MathFrac, ...]
    note: str = ""
    text: str = ""


@dataclass(frozen=True)
class Section:
    """A top-level section of the report, for the table of contents (``anchor`` is the HTML id)."""

    anchor: str
    title: str


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
    lab_intro: str = ""
    lab: tuple[LabSection, ...] = ()
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
            requested=fmt_number(req, 4) if req is not None else "—",
            achieved=fmt_number(ach, 4),
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
            rows.append(PoleRow("coupled arm", "—", fmt_number(p, 4), "—", zeta, wn))
        return tuple(rows)
    if design.closed_loop is None:
        return ()
    return tuple(_loop_pole_rows(design, ""))


def _zero_rows(design: Any) -> tuple[ParameterRow, ...]:
    zeros = achieved_zeros(design)
    rows = [ParameterRow("requested zero", fmt_number(z, 4), "1/s", "zero of x1/xD") for z in design.zeros]
    rows += [ParameterRow("achieved zero", fmt_number(z, 4), "1/s", "zero of x1/xD (closed loop)") for z in zeros]
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
        target=unit(check.target) or "—",
        achieved=achieved if isinstance(achieved, str) else fmt_number(achieved, 4),
        margin=fmt_signed(check.margin, 4),
        unit=unit(check.unit),
        detail=_UNIT_STAR.sub("·", check.detail),
        certificate=render_certificate(check.certificate),
        label=check_label(check.name),
        required=bool(getattr(check, "required", True)),
        anchor=check_anchor(check.name),
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


# simulation settings: label and unit of each key (values are formatted by fmt_compact, in words)
_SETTINGS: dict[str, tuple[str, str]] = {
    "integrator": ("Integrator", ""), "integrator_choice": ("Integrator choice", ""),
    "dt": ("Time step", "s"), "dt_source": ("Time step chosen by", ""), "duration": ("Duration", "s"),
    "duration_requested": ("Duration requested", "s"), "duration_source": ("Duration taken from", ""),
    "n_steps": ("Steps", ""), "fastest_rate": ("Fastest closed-loop rate |p|max", "1/s"),
    "slowest_rate": ("Slowest closed-loop rate", "1/s"), "steps_per_sample": ("Steps per controller sample", ""),
    "delay_steps": ("Delay in steps", ""), "evaluation": ("Evaluation", ""), "plant": ("Simulated plant", ""),
    "nominal_plant": ("Nominal plant (design model)", ""), "controller": ("Controller", ""),
    "reference": ("Reference", ""), "nonlinearity": ("Nonlinearity", ""), "delay": ("Delay", "s"),
    "sampling_period": ("Sampling period", "s"), "noise": ("Measurement noise", ""),
    "perturbation": ("Perturbation", ""), "initial_state": ("Initial state", ""),
    "ignored": ("Spec settings ignored", ""), "kind": ("Kind", ""),
}


def _spec_path(text: str) -> str:
    """``simulation.duration`` -> ``simulation › duration`` (a spec path, not an internal key)."""
    return text.replace(".", " › ") if re.fullmatch(r"[A-Za-z_]+(\.[A-Za-z_]+)+", text) else text


def _setting_value(key: str, value: Any, unit_text: str, plant: Any) -> str:
    if key in ("plant", "nominal_plant") and isinstance(value, Mapping):
        parts = []
        for name, v in value.items():
            try:
                u = unit(plant.parameter(name).unit)
            except (KeyError, AttributeError, ValueError, TypeError):
                u = ""
            parts.append(f"{_SYMBOLS.get(name, name)} = {fmt_compact(v, 4)}{' ' + u if u and _is_real(v) else ''}")
        return ", ".join(parts) or "none"
    if key == "ignored" and isinstance(value, Sequence) and not isinstance(value, str):
        return ", ".join(_spec_path(str(v)) for v in value) or "none"
    if value is None:
        return "none"
    text = _spec_path(fmt_compact(value, 4)) if isinstance(value, str) else fmt_compact(value, 4)
    return text + (f" {unit_text}" if unit_text and _is_real(value) else "")


def _simulation_rows(simulation, plant: Any = None) -> tuple[ParameterRow, ...]:
    """Simulation settings with labels in words, values formatted (4 significant digits) and units."""
    if simulation is None:
        return ()
    rows = [ParameterRow("Kind", str(simulation.kind), "")]
    t = np.asarray(simulation.time, float)
    if t.size:
        rows.append(ParameterRow("Samples", f"{t.size} over {fmt_number(t[0])} s to {fmt_number(t[-1])} s", ""))
    for key, value in dict(simulation.settings).items():
        name, unit_text = _SETTINGS.get(str(key), (human_key(str(key)).capitalize(), ""))
        rows.append(ParameterRow(name, unit(_setting_value(str(key), value, unit_text, plant)), ""))
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


# ----------------------------------------------------------------------------- compliance

# check names in words; an unknown name is shown with its underscores as spaces
CHECK_LABELS: dict[str, str] = {
    "pole_placement": "Closed-loop poles and zeros as requested",
    "routh_hurwitz": "Stability of the nominal loop (Routh–Hurwitz)",
    "lyapunov": "Lyapunov stability certificate",
    "common_lyapunov": "Common Lyapunov function over the parameter box",
    "loop_margins": "Stability margins at the plant input",
    "overshoot": "Overshoot",
    "settling_time": "Settling time (2 % band)",
    "rise_time": "Rise time",
    "steady_state_error": "Steady-state error",
    "max_control": "Peak control effort |u|",
    "robust_box": "Robust stability over the whole parameter box",
    "robust_vertices": "Stability at the corners of the parameter box",
    "robust_grid": "Stability on the parameter lattice",
    "robust_stability": "Robust stability over the parameter box",
    "error_poles": "Error dynamics poles as requested",
    "positive_real": "Positive-real condition",
    "coupling": "Decoupling of the joints",
    "singularity": "Distance from singular configurations",
    "torque_limits": "Joint torques within limits",
    "tracking_bounds": "Tracking error within bounds",
    "workspace": "Path inside the workspace",
}

GLOSSARY: tuple[tuple[str, str], ...] = (
    ("limit", "the requirement as written in the spec, or the threshold a stability test must clear"),
    ("achieved", "the value measured on the design or the simulation, in the unit of the limit"),
    ("margin", "the signed distance from the achieved value to the limit: positive means the requirement holds "
               "with that much to spare, negative that it is missed by that much; % is relative to the limit"),
    ("shortfall", "how far a failed requirement is missed, in the unit of the limit and in % of the limit"),
    ("scaled", "a dimensionless value after the problem was rescaled (poles by their largest magnitude, "
               "matrices balanced) so that one tolerance applies whatever the units"),
    ("normalised", "a dimensionless value divided by a reference size (e.g. P scaled so that P ≤ I)"),
    ("informational", "a check reported with its status that does not decide the verdict (e.g. the common "
                      "Lyapunov function of a box, sufficient but not necessary for robust stability)"),
    ("UNDECIDED", "the check could not decide (solver not converged, undefined metric): never counted as a pass"),
    ("certificate", "the evidence a check leaves behind (matrices, tables) so that the result can be re-checked"),
)

_COMPARISON = re.compile(r"^\s*(<=|>=|<|>|≤|≥)\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*)$")
_SYMBOL = {"<=": "≤", ">=": "≥", "<": "<", ">": ">", "≤": "≤", "≥": "≥"}


def check_label(name: str) -> str:
    """A check's name in words."""
    return CHECK_LABELS.get(name, name.replace("_", " ").capitalize())


def _unit_suffix(text: str) -> str:
    """`` unit`` to append to a number (empty for a dimensionless ``1``)."""
    u = unit(text).strip()
    if u in ("", "1", "—"):
        return ""
    if u.startswith("1 (") and u.endswith(")"):
        return " " + u[3:-1]
    return " " + u


def _limit_of(check: Any) -> tuple[str, float | None]:
    """The requirement as text (``≤ 5 N·m``) and its numeric limit (None when not a number)."""
    target = unit(str(check.target or "")).strip()
    found = _COMPARISON.match(target)
    if found is None:
        return (target.replace("<=", "≤").replace(">=", "≥") or "—"), None
    op, number, rest = found.groups()
    return f"{_SYMBOL[op]} {fmt_number(float(number))} {rest}".strip(), float(number)


def _achieved_text(check: Any) -> str:
    achieved = check.achieved
    if achieved is None:
        return "undefined"
    if isinstance(achieved, str):
        return achieved
    return fmt_number(achieved, 4) + _unit_suffix(check.unit)


def _percent_of(value: float | None, limit: float | None) -> str:
    """``value`` in % of ``|limit|`` with 3 significant digits (never in exponent notation), signed."""
    if value is None or limit is None or limit == 0 or not math.isfinite(value):
        return ""
    x = 100 * value / abs(limit)
    text = f"{x:+.0f}" if abs(x) >= 100 else fmt_signed(float(f"{x:.3g}"), 3)
    return f"{text} %"


def _figure_anchor(fig: Any) -> str:
    return fig.anchor


def _compliance_row(check: Any, figures: Sequence[Any]) -> ComplianceRow:
    limit, number = _limit_of(check)
    margin = check.margin if _is_real(check.margin) else None
    evidence = next((f for f in figures if check.name in tuple(getattr(f, "evidence", ()) or ())), None)
    return ComplianceRow(
        name=check.name, label=check_label(check.name), status=check.status,
        required=bool(getattr(check, "required", True)), limit=limit, achieved=_achieved_text(check),
        margin=(fmt_signed(margin, 4) + _unit_suffix(check.unit)) if margin is not None else "—",
        margin_percent=_percent_of(margin, number),
        evidence=_figure_anchor(evidence) if evidence is not None else "",
        evidence_title=evidence.title if evidence is not None else "",
        detail=_UNIT_STAR.sub("·", check.detail),
        anchor=check_anchor(check.name),
    )


def _is_real(x: Any) -> bool:
    return isinstance(x, int | float | np.integer | np.floating) and not isinstance(x, bool) and math.isfinite(x)


# ----------------------------------------------------------------------------- why it failed


def _why_from_check(check: Any) -> WhyRow:
    """Requirement, achieved value and shortfall of a failing check, from the check alone."""
    limit, number = _limit_of(check)
    margin = check.margin if _is_real(check.margin) else None
    if margin is not None and margin < 0:
        shortfall, percent = fmt_number(-margin, 4) + _unit_suffix(check.unit), _percent_of(-margin, number)
    elif check.passed is None:
        shortfall, percent = "not decided", ""
    else:
        shortfall, percent = "not measurable", ""
    return WhyRow(check.name, check_label(check.name), check.status, limit, _achieved_text(check), shortfall,
                  percent.lstrip("+"), "", "")


def _diagnose(result: Any) -> Any:
    """``designkit.analysis.diagnosis.diagnose(result)``; None when that module is not installed,
    the exception itself when the diagnosis failed (the report then says so instead of failing)."""
    try:
        from designkit.analysis.diagnosis import diagnose
    except ImportError:
        return None
    try:
        return diagnose(result)
    except Exception as exc:  # noqa: BLE001 - a failed diagnosis must not cost the user the report
        return exc


def _why_section(result: Any, diagnosis: Any) -> tuple[tuple[WhyRow, ...], str, tuple[WhyFix, ...]]:
    """The rows of "why it failed", where their causes come from, and the fixes shared by several rows."""
    failing = [c for c in result.checks if getattr(c, "required", True) and c.passed is not True]
    if not failing:
        return (), "", ()
    if isinstance(diagnosis, Exception):
        rows = tuple(_why_from_check(c) for c in failing)
        return rows, (f"The diagnosis of this run failed ({type(diagnosis).__name__}: {diagnosis}); the rows give "
                      "the requirement, the achieved value and the shortfall only."), ()
    by_name = {f.check: f for f in (diagnosis.findings if diagnosis is not None else ())}
    rows, parts = [], []
    for check in failing:
        row = _why_from_check(check)
        found = by_name.get(check.name)
        parts.append(_fix_parts(found) if found is not None else ())
        if found is not None:
            cause = unit(found.cause)
            if diagnosis.diverged and diagnosis.divergence and cause.strip() == diagnosis.divergence.strip():
                cause = "The nonlinear loop diverges (see above)."
            row = dataclasses.replace(
                row, cause=cause, fix=unit(found.fix),
                # the check's own numbers first (same format as the compliance table); the diagnosis' when it has none
                achieved=row.achieved if row.achieved != "undefined" else (unit(found.achieved) or row.achieved),
                shortfall=row.shortfall if row.shortfall_percent or row.shortfall.endswith(unit(check.unit))
                and row.shortfall[:1].isdigit() else (unit(found.shortfall) or row.shortfall),
                shortfall_percent=row.shortfall_percent or found.shortfall_percent)
        rows.append(row)
    if diagnosis is None:
        note = ("No diagnosis was available (designkit.analysis.diagnosis is not installed): the rows give the "
                "requirement, the achieved value and the shortfall only.")
    elif not any(r.cause for r in rows):
        note = "The run shows no specific cause for these shortfalls beyond the values themselves."
    else:
        note = ("Causes are diagnosed from this run (the simulation, the linear analysis of the design and the "
                "checks' certificates); the fixes are computed from the same run.")
    rows = _share_causes(rows)
    shared_rows, fixes = _share_fixes(rows, parts)
    if fixes:
        note += " A fix that applies to several rows is given once, numbered, below the table."
    return shared_rows, note, fixes


REPEATED_CAUSE_MIN = 120
"""A cause at least this long (characters) that an earlier row's cause already states in full is
replaced by a reference to that row; a shorter one is clearer repeated."""


def _share_causes(rows: Sequence[WhyRow]) -> list[WhyRow]:
    """Rows whose long cause is contained in an earlier row's cause say "Same cause as <row> (above)." instead."""
    out: list[WhyRow] = []
    for row in rows:
        text = row.cause.strip().rstrip(".")
        earlier = next((r for r in out if len(text) >= REPEATED_CAUSE_MIN and text in r.cause), None)
        same = f"Same cause as {earlier.label} (above)." if earlier is not None else ""
        out.append(dataclasses.replace(row, cause=same) if same else row)
    return out


def _fix_parts(finding: Any) -> tuple[str, ...]:
    """The distinct fixes of a finding (``fixes``; its whole ``fix`` when it does not list them)."""
    parts = tuple(getattr(finding, "fixes", ()) or ())
    if not parts and getattr(finding, "fix", ""):
        parts = (finding.fix,)
    return tuple(dict.fromkeys(unit(p) for p in parts if p.strip()))


def _refs_text(numbers: Sequence[int]) -> str:
    """``"See fix 1 below."``, ``"See fixes 1 and 2 below."``."""
    if len(numbers) == 1:
        return f"See fix {numbers[0]} below."
    return "See fixes " + ", ".join(map(str, numbers[:-1])) + f" and {numbers[-1]} below."


def _share_fixes(rows: Sequence[WhyRow], parts: Sequence[tuple[str, ...]]
                 ) -> tuple[tuple[WhyRow, ...], tuple[WhyFix, ...]]:
    """Fixes found under several rows numbered once; those rows keep their own fixes and refer to the shared ones.

    Parameters
    ----------
    rows : sequence of WhyRow
        The rows, their ``fix`` the finding's whole fix.
    parts : sequence of tuple of str
        Each row's distinct fixes.

    Returns
    -------
    rows, fixes : tuple of WhyRow, tuple of WhyFix
        A row with no shared fix is returned as is.
    """
    count: dict[str, int] = {}
    for row_parts in parts:
        for part in row_parts:
            count[part] = count.get(part, 0) + 1
    numbers: dict[str, int] = {}
    for row_parts in parts:
        for part in row_parts:
            if count[part] > 1 and part not in numbers:
                numbers[part] = len(numbers) + 1
    if not numbers:
        return tuple(rows), ()
    out = []
    for row, row_parts in zip(rows, parts, strict=True):
        refs = tuple(dict.fromkeys(numbers[p] for p in row_parts if p in numbers))
        if not refs:
            out.append(row)
            continue
        own = " ".join(p for p in row_parts if p not in numbers)
        out.append(dataclasses.replace(row, fix=(own + " " if own else "") + _refs_text(refs), fix_refs=refs))
    fixes = tuple(WhyFix(k, text, tuple(r.label for r, rp in zip(rows, parts, strict=True) if text in rp))
                  for text, k in numbers.items())
    return tuple(out), fixes


def _metric_rows(diagnosis: Any) -> tuple[MetricRow, ...]:
    if diagnosis is None:
        return ()
    return tuple(MetricRow(m.metric, unit(m.unit), m.linear or "undefined", m.nonlinear or "undefined")
                 for m in getattr(diagnosis, "linear_vs_nonlinear", ()))


# ----------------------------------------------------------------------------- typeset formulas

_WORDS = {"tau": "τ", "xi": "ξ", "qd": "q̇", "qdd": "q̈", "Jdot": "J̇"}
_FUNCTIONS = frozenset({"sin", "cos", "tan", "sign", "exp", "diag", "max", "min", "sat", "dt", "d"})
_SUPERSCRIPTS = {"²": "2", "³": "3", "⁻": "−", "¹": "1", "⁴": "4", "ᵀ": "T"}
_TOKEN = re.compile(
    r"(?P<space>\s+)"
    r"|(?P<num>\d+(?:\.\d+)?(?:[eE][-+]?\d+)?)"
    r"|(?P<sup>[²³⁻¹⁴ᵀ]+)"
    r"|(?P<ident>[^\W\d_][\u0300-\u036f]*(?:[A-Za-z]*)(?:\d+)?(?:_[A-Za-z0-9]+)?[\u0300-\u036f]*)"
    r"|(?P<prime>'+)"
    r"|(?P<op>.)",
    re.S,
)
_PROSE = re.compile(r"\s(?=(?:(?!(?:sin|cos|sign|dt)\b)[a-z]{2,}'?s?\s+){1,}[a-z]{2,}\b)")


def _ident(word: str) -> list[MathToken]:
    """An identifier as tokens: ``K1`` -> K_1, ``xD`` -> x_D, ``Km_i`` -> K_{m,i}, ``mgl`` -> m g l."""
    word = _WORDS.get(word, word)
    sub_i = ""
    if "_" in word:
        word, sub_i = word.split("_", 1)
        word = _WORDS.get(word, word)
    if word in _FUNCTIONS:
        return [MathToken("mi", word, sub_i)]
    base, rest = word[0], word[1:]
    while rest and unicodedata.combining(rest[0]):
        base, rest = base + rest[0], rest[1:]
    if re.fullmatch(r"[A-Za-z]?\d*", rest):
        return [MathToken("mi", base, ",".join(x for x in (rest, sub_i) if x))]
    if word.isascii() and word.isalpha() and word.islower() and len(word) <= 3:  # a product: mgl
        return [*(MathToken("mi", c) for c in word[:-1]), MathToken("mi", word[-1], sub_i)]
    return [MathToken("mi", word, sub_i)]


def _lex(text: str) -> list[MathToken]:
    tokens: list[MathToken] = []
    text = unicodedata.normalize("NFD", text)
    depth = 0
    for m in _TOKEN.finditer(text):
        kind, value = m.lastgroup, m.group()
        if kind == "space":
            continue
        if kind == "num":
            tokens.append(MathToken("mn", value))
        elif kind == "ident" and value.startswith("Δ") and len(value) > 1:  # Δx1: the increment of x1
            tokens += [MathToken("mi", "Δ"), *_ident(value[1:])]
        elif kind == "ident":
            tokens += _ident(unicodedata.normalize("NFC", value) if not _needs_nfd(value) else value)
        elif kind == "op" and value in ",;" and depth == 0:  # between formulas of one line
            tokens.append(MathToken("sep", value))
        elif (kind == "op" and value == "*" and tokens and tokens[-1].kind == "mi" and m.start() > 0
              and not text[m.start() - 1].isspace()):  # a*, q*: a starred symbol
            tokens[-1] = dataclasses.replace(tokens[-1], sup=tokens[-1].sup + "∗")
        elif kind in ("prime", "sup") and tokens and tokens[-1].kind in ("mi", "mn", "mo"):
            add = "′" * len(value) if kind == "prime" else "".join(_SUPERSCRIPTS.get(c, c) for c in value)
            last = tokens[-1]
            tokens[-1] = dataclasses.replace(last, sup=last.sup + add)
        else:
            depth += (value == "(") - (value == ")")
            tokens.append(MathToken("mo", "−" if value == "-" else value))
    return tokens


def _needs_nfd(value: str) -> bool:
    return any(unicodedata.combining(c) for c in value)


def _strip_parens(nodes: list[Any]) -> list[Any]:
    if (len(nodes) >= 2 and isinstance(nodes[0], MathToken) and nodes[0].text == "("
            and isinstance(nodes[-1], MathToken) and nodes[-1].text == ")" and not nodes[-1].sup):
        depth = 0
        for k, n in enumerate(nodes):
            if isinstance(n, MathToken) and n.text == "(":
                depth += 1
            elif isinstance(n, MathToken) and n.text == ")":
                depth -= 1
                if depth == 0 and k < len(nodes) - 1:
                    return nodes
        return nodes[1:-1]
    return nodes


def _fractions(tokens: list[MathToken], text: str) -> tuple[Any, ...]:
    """Fractions: ``a / b`` at the top level of each side of ``=`` (written with spaces), and
    ``x1/xD`` between two identifiers."""
    out: list[Any] = []
    k = 0
    while k < len(tokens):  # identifier/identifier
        t = tokens[k]
        if (t.kind == "mo" and t.text == "/" and out and isinstance(out[-1], MathToken) and out[-1].kind in ("mi", "mn")
                and k + 1 < len(tokens) and tokens[k + 1].kind == "mi"
                and (k + 2 >= len(tokens) or tokens[k + 2].text != "(")):
            num = (out.pop(),)
            if out and isinstance(out[-1], MathToken) and out[-1].text == "Δ":  # Δx1/ξ: the increment over ξ
                num = (out.pop(), *num)
            out.append(MathFrac(num, (tokens[k + 1],)))
            k += 2
            continue
        out.append(t)
        k += 1
    if " / " not in text:
        return tuple(out)
    sides: list[list[Any]] = [[]]
    for n in out:
        if isinstance(n, MathToken) and (n.text == "=" or n.kind == "sep"):
            sides.append([n])
            sides.append([])
        else:
            sides[-1].append(n)
    result: list[Any] = []
    for side in sides:
        depth, split = 0, None
        for k, n in enumerate(side):
            if isinstance(n, MathToken) and n.text == "(":
                depth += 1
            elif isinstance(n, MathToken) and n.text == ")":
                depth -= 1
            elif isinstance(n, MathToken) and n.text == "/" and depth == 0 and split is None:
                split = k
        if split is None or split == 0 or split == len(side) - 1:
            result += side
        else:
            result.append(MathFrac(tuple(_strip_parens(side[:split])), tuple(_strip_parens(side[split + 1:]))))
    return tuple(result)


def _balanced(text: str) -> bool:
    depth = 0
    for ch in text:
        depth += (ch == "(") - (ch == ")")
        if depth < 0:
            return False
    return depth == 0


def equation(label: str, text: str, note: str = "") -> Equation:
    """A plain-text formula (``x1/xD = Km(...) / (τ s³ + ...)``) as an :class:`Equation`.

    Trailing words (a parenthesised remark, or prose after the formula) become the ``note``;
    identifiers get their subscripts (``K1`` -> K₁, ``xD`` -> x_D), superscripts and primes are
    attached, and ``a / b`` at the top level of a side of ``=`` becomes a fraction.
    """
    math_part, notes = text.strip(), [note] if note else []
    paren = re.search(r"\s+\(([^()]*[a-z]{3,}\s+[a-z]{2,}[^()]*)\)\s*$", math_part)
    if paren is not None:
        math_part, notes = math_part[: paren.start()], [paren.group(1), *notes]
    prose = _PROSE.search(math_part)
    if prose is not None and _balanced(math_part[: prose.start()]):
        notes = [math_part[prose.start():].strip(" ;,"), *notes]
        math_part = math_part[: prose.start()].rstrip(" ;,")
    if "=" not in math_part:  # no formula: words only
        return Equation(label, (), "; ".join([text.strip()]), text)
    return Equation(label, _fractions(_lex(math_part), math_part), "; ".join(n for n in notes if n), text)


_LOOP_NOTE = ("loop broken at the plant input with the reference and the disturbance set to zero: the law above "
              "reads u = −C(s)·(measured output), L(s) = C(s) P(s), the loop of the Bode plot; negative feedback, "
              "the closed-loop poles are the roots of 1 + L(s) = 0")


def _equations(design: Any, display: Any, plant: Any) -> tuple[Equation, ...]:
    eqs = [equation("Plant", line) for line in plant.equations()]
    eqs += [equation("Control law", line) for line in display.law]
    for line in design.formulas:
        head = line.split("=", 1)[0].strip()
        if head in ("u", "a*") and display.law:
            continue  # the law, already shown in the family's notation
        kind = "Closed loop" if "/" in head else "Design formula"
        eqs.append(equation(kind, line))
    if display.loop_transfer:
        eqs.append(equation("Loop transfer (Bode plot)", display.loop_transfer, _LOOP_NOTE))
    return tuple(eqs)


# ----------------------------------------------------------------------------- contents


def _contents(model_parts: Mapping[str, Any]) -> tuple[Section, ...]:
    sections = []
    if model_parts["why"]:
        sections.append(Section("why", "Why it failed"))
    sections.append(Section("compliance", "Requirement compliance"))
    if model_parts["linear_vs_nonlinear"] or model_parts["limit_cycle"]:
        sections.append(Section("engineering", "Linear model against the nonlinear simulation"))
    sections += [Section("design", "Design"), Section("figures", "Figures")]
    if model_parts["lab"]:
        sections.append(Section("lab", "Lab questions (notes, experiment 1)"))
    if model_parts["simulation"]:
        sections.append(Section("simulation", "Simulation settings"))
    sections += [Section("certificates", "Appendix A: check details and certificates"),
                 Section("glossary", "Appendix B: glossary"),
                 Section("spec", "Appendix C: spec"),
                 Section("provenance", "Appendix D: provenance and versions")]
    return tuple(sections)


def build_report_model(result: Any, provenance: Sequence[tuple[str, str]] | None = None, *,
                       processes: int = 1) -> ReportModel:
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
    figures = design_figures(result, processes=processes)
    diagnosis = _diagnose(result) if checks else None
    why, why_note, why_fixes = _why_section(result, diagnosis)
    if isinstance(diagnosis, Exception):
        diagnosis = None
    rows = [_compliance_row(c, figures) for c in checks]
    simulation = _simulation_rows(result.simulation, plant)
    if provenance is None:
        from designkit.report.provenance import provenance_rows

        provenance = provenance_rows()
    limit_cycle = getattr(diagnosis, "limit_cycle", None)
    parts = {
        "why": why, "linear_vs_nonlinear": _metric_rows(diagnosis),
        "limit_cycle": limit_cycle.sentence if limit_cycle is not None else "", "lab": lab, "simulation": simulation,
    }
    return ReportModel(
        title=f"{label} — {spec.name}",
        name=spec.name,
        description=re.sub(r"(?<=\w)\*(?=\w)", "·", " ".join(spec.description.split())),
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
        simulation=simulation,
        figures=figures,
        lab_intro=lab_intro,
        lab=lab,
        why=why,
        why_note=why_note,
        why_fixes=why_fixes,
        divergence=(unit(diagnosis.divergence) if diagnosis is not None and diagnosis.diverged else ""),
        limit_cycle=parts["limit_cycle"],
        linear_vs_nonlinear=parts["linear_vs_nonlinear"],
        compliance=tuple(r for r in rows if r.required),
        informational=tuple(r for r in rows if not r.required),
        glossary=GLOSSARY,
        equations=_equations(design, display, plant),
        provenance=tuple((str(k), str(v)) for k, v in provenance),
        figure_anchors=tuple(_figure_anchor(f) for f in figures),
        contents=_contents(parts),
    )


__all__ = [
    "CertificateEntry",
    "CheckRow",
    "ComplianceRow",
    "Equation",
    "MathFrac",
    "MathToken",
    "MetricRow",
    "Section",
    "WhyFix",
    "WhyRow",
    "check_label",
    "equation",
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
