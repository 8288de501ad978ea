"""The design section: plant parameters, gains, requested against achieved poles and zeros, loop margins
and the formulas typeset.

Nothing is recomputed here but the eigenvalues of the design's own closed loop: the margins are the
``loop_margins`` check's, the zeros :func:`~designkit.verification.loop.achieved_zeros`.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from typing import Any

import numpy as np

from designkit.display.numbers import fmt_number, unit
from designkit.display.typeset import Equation, equation
from designkit.report.rows import ParameterRow, PoleRow
from designkit.verification.loop import achieved_zeros

__all__ = ["SYMBOLS", "equations", "gain_value", "linearization_note", "loop_rows", "plant_rows", "pole_rows",
           "zero_rows"]

SYMBOLS = {"tau": "τ", "tau1": "τ1", "tau2": "τ2"}
"""Plant parameter names written as symbols."""


def plant_rows(plant: Any, spec: Any, lattice: bool = True) -> tuple[ParameterRow, ...]:
    """Nominal plant parameters, then the uncertainty box of the spec (intervals, the lattice's points per axis when
    ``lattice``: a check ran it, samples)."""
    rows = [ParameterRow(SYMBOLS.get(p.name, p.name), fmt_number(p.value, 6), unit(p.unit),
                         f"nominal {p.meaning}".strip()) for p in plant.parameters]
    unc = getattr(spec.plant, "uncertainty", None)
    if unc is not None:
        for name, (lo, hi) in unc.intervals.items():
            par = plant.parameter(name)
            rows.append(ParameterRow(SYMBOLS.get(name, name), f"[{fmt_number(lo, 6)}, {fmt_number(hi, 6)}]",
                                     unit(par.unit), f"uncertainty interval of the {par.meaning}"))
        if lattice:  # only where a check runs the robustness lattice
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


def pole_rows(design: Any) -> tuple[PoleRow, ...]:
    """Requested poles against the achieved ones (per joint loop, then the coupled arm's)."""
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


def linearization_note(design: Any) -> str:
    """What the closed loop of the poles table is, when the linearization contract is not ``exact``."""
    lin = design.linearization
    if lin.kind == "exact":
        return ""
    requested = ", ".join(fmt_number(p, 4) for p in design.poles)
    if lin.kind == "frozen":
        return (f"The closed loop below is the law {lin.describe()} (its initial values): an adaptive law has no "
                "equilibrium of its own in the adapted parameters, so the linear checks judge the loop with them "
                "held; the check of the loop frozen at the final values judges it with the values the run ends with.")
    return (f"No closed-loop poles: {lin.reason}. No linear check is offered"
            + (f"; the requested pole{'s' if len(design.poles) > 1 else ''} {requested} 1/s "
               f"{'are' if len(design.poles) > 1 else 'is'} measured on the run instead." if design.poles else "."))


def zero_rows(design: Any) -> tuple[ParameterRow, ...]:
    """Requested zeros, then the achieved zeros of x1/xD."""
    zeros = achieved_zeros(design)
    rows = [ParameterRow("requested zero", fmt_number(z, 4), "1/s", "zero of x1/xD") for z in design.zeros]
    rows += [ParameterRow("achieved zero", fmt_number(z, 4), "1/s", "zero of x1/xD (closed loop)") for z in zeros]
    return tuple(rows)


def loop_rows(checks: Sequence[Any]) -> tuple[ParameterRow, ...]:
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


def gain_value(value: Any) -> str:
    """A gain (scalar, per-joint vector or matrix) with 6 significant digits."""
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 0:
        return fmt_number(float(arr), 6)
    if arr.ndim == 1:
        return "; ".join(f"joint {j + 1}: {fmt_number(v, 6)}" for j, v in enumerate(arr))
    return "; ".join("[" + ", ".join(fmt_number(v, 6) for v in row) + "]" for row in arr)


_LOOP_NOTE = ("loop broken at the plant input with the reference and the disturbance set to zero: the law above "
              "reads u = −C(s)·(measured output), L(s) = C(s) P(s), the loop of the Bode plot; negative feedback, "
              "the closed-loop poles are the roots of 1 + L(s) = 0")


def equations(design: Any, display: Any, plant: Any) -> tuple[Equation, ...]:
    """Plant, control law, closed loop, design formulas and the loop transfer of the Bode plot, typeset."""
    eqs = [equation("Plant", line) for line in plant.equations()]
    law = display.law_lines(design)
    eqs += [equation("Control law", line) for line in law]
    for line in design.formulas:
        head = line.split("=", 1)[0].strip()
        if head in ("u", "a*") and law:
            continue  # the law, already shown in the family's notation
        kind = "Closed loop" if re.fullmatch(r"[\w']+/[\w']+", head) else "Design formula"  # x1/xD = ...
        eqs.append(equation(kind, line))
    loop = display.loop_line(design)
    if loop:
        eqs.append(equation("Loop transfer (Bode plot)", loop, _LOOP_NOTE))
    return tuple(eqs)
