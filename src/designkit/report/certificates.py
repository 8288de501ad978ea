"""The compact rendering of check certificates, and of any value, in words rather than Python notation.

Numbers are written by :mod:`designkit.display.numbers` (:func:`~designkit.display.numbers.fmt_number`);
:func:`fmt_compact` writes any value on one line and :func:`render_certificate` turns a check's
certificate (nested mappings, matrices, lists of records, ``[re, im]`` pairs, robustness grids) into
:class:`CertificateEntry` rows that the HTML and PDF renderers lay out as they are.
"""

from __future__ import annotations

import contextlib
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.display.heatmap import robustness_grid
from designkit.display.numbers import fmt_number, plain_complex, sentence_units

# certificate keys whose [re, im] pairs are complex numbers (poles, zeros, eigenvalues)
_COMPLEX_KEYS = re.compile(r"eig|pole|zero", re.IGNORECASE)
_SINGLE_KEYS = re.compile(r"^(eigenvalue|pole|zero)$", re.IGNORECASE)
_MATRIX_MAX = 8  # rows/columns of a certificate matrix shown before eliding
_LIST_MAX = 12  # items of a certificate vector shown before eliding
_RECORDS_MAX = 24  # rows of a certificate table (list of mappings) shown before eliding


@dataclass(frozen=True)
class CertificateEntry:
    """One item of a check's certificate.

    Either compact ``text`` (one line), or a ``matrix`` of formatted numbers (``header`` None,
    shown in brackets), or a small table (``matrix`` rows under the column names ``header``,
    from a list of mappings such as Routh conditions).
    """

    key: str
    text: str = ""
    matrix: tuple[tuple[str, ...], ...] | None = None
    header: tuple[str, ...] | None = None
    label: str = ""

    def __post_init__(self) -> None:
        if not self.label:
            object.__setattr__(self, "label", human_key(self.key))


# Certificate and settings keys in words (the report never shows an internal key with underscores or dots).
LABELS: dict[str, str] = {
    "P": "P", "Pb": "balanced P (Pb)", "D": "balancing scale D", "t": "decay-rate bound t", "eps": "strictness ε",
    "A_scale": "scale of A", "eig_P": "eigenvalues of P", "eig_Pb": "eigenvalues of Pb",
    "eig_AtP_PA": "eigenvalues of AᵀP + PA", "eig_A": "eigenvalues of A", "solver": "solver",
    "solver_status": "solver status", "normalisation": "normalisation", "status": "status",
    "poles": "achieved poles", "requested_poles": "requested poles", "pole_scale": "pole scale",
    "pole_matching": "pole matching", "coefficient_error": "coefficient error", "tolerance": "tolerance",
    "zeros": "achieved zeros", "requested_zeros": "requested zeros", "zero_matching": "zero matching",
    "infinite_zeros_discarded": "zeros at infinity discarded", "dc_gain": "DC gain", "dc_gain_error": "DC-gain error",
    "reference_transfer": "reference transfer", "disturbance_zeros": "zeros of the disturbance transfer",
    "error_over_tolerance": "error over tolerance",
    "coefficients": "characteristic coefficients", "labels": "coefficient names", "frequency_scale": "frequency scale",
    "first_column": "Routh first column", "first_column_tolerance": "first-column tolerance",
    "right_half_plane_roots": "right-half-plane roots", "decided_by_shift": "decided by a shift", "shift": "shift",
    "plant": "plant", "coefficient_conditions": "coefficient conditions", "conditions": "conditions",
    "loops": "loops", "convention": "sign convention", "input": "plant input",
    "gain_crossover_rad_s": "gain crossover (rad/s)", "phase_crossover_rad_s": "phase crossover (rad/s)",
    "phase_margin_deg": "phase margin (deg)", "gain_margin": "gain margin", "modulus_margin": "modulus margin",
    "kind": "kind", "amplitude": "amplitude", "duration": "duration", "settling_band": "settling band",
    "overshoot_percent": "overshoot (%)", "rise_time": "rise time", "settling_time": "settling time",
    "steady_state_error": "steady-state error", "max_tracking_error": "largest tracking error",
    "peak_u_command": "peak commanded |u|", "peak_u_applied": "peak applied |u|",
    "steady_state_window": "steady-state window", "parameters": "parameters", "A": "A", "b": "b",
    "box": "parameter box", "vertices": "corners", "points_per_axis": "points per axis",
    "lattice_plants": "lattice plants", "random_samples": "random samples", "seed": "seed", "plants": "plants",
    "stable": "stable", "unstable": "unstable", "undecided": "undecided", "worst_abscissa": "slowest pole (Re)",
    "failing_points": "failing points", "grid": "robustness grid", "condition": "condition", "value": "value",
    "threshold": "threshold", "margin": "margin", "unit": "unit", "requested": "requested", "achieved": "achieved",
    "error": "error", "largest_deviation_from_decoupled_form": "largest deviation from the decoupled form",
}
_SUFFIX_UNITS = {"rad_s": " (rad/s)", "deg": " (deg)", "percent": " (%)", "rad": " (rad)", "s": " (s)"}


def human_key(key: str) -> str:
    """An internal key (``gain_crossover_rad_s``, ``loops.0.gain_margin``) in words, without dots or underscores."""
    parts = []
    for seg in str(key).split("."):
        if seg in LABELS:
            parts.append(LABELS[seg])
        elif seg.isdigit():
            parts.append(f"no. {int(seg) + 1}")
        else:
            words, suffix = seg, ""
            for tail, text in _SUFFIX_UNITS.items():
                if words.endswith("_" + tail) and len(words) > len(tail) + 1:
                    words, suffix = words[: -len(tail) - 1], text
                    break
            parts.append(re.sub(r"\s+", " ", words.replace("_", " ")).strip() + suffix)
    return " › ".join(p for p in parts if p)


def _is_number(x: Any) -> bool:
    return isinstance(x, int | float | np.integer | np.floating) and not isinstance(x, bool)


def _is_matrix(value: Any) -> bool:
    if not isinstance(value, Sequence | np.ndarray) or isinstance(value, str) or len(value) == 0:
        return False
    rows = list(value)
    if not all(isinstance(r, Sequence | np.ndarray) and not isinstance(r, str) for r in rows):
        return False
    width = len(rows[0])
    return width > 0 and all(len(r) == width and all(_is_number(x) for x in r) for r in rows)


def _is_records(value: Any) -> bool:
    return (isinstance(value, Sequence) and not isinstance(value, str) and len(value) > 0
            and all(isinstance(v, Mapping) for v in value))


def _as_complex(value: Any, *, single: bool = False) -> Any:
    """Lists of ``[re, im]`` pairs (any nesting) as complex numbers, or ``None``.

    A bare ``[re, im]`` is read as one complex number only when ``single`` (an ``eigenvalue``
    key); otherwise a 2-vector of reals stays a vector.
    """
    if not isinstance(value, Sequence) or isinstance(value, str):
        return None
    try:
        num = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        return None
    if num.ndim == 0 or num.shape[-1] != 2 or (num.ndim == 1 and not single):
        return None
    z = num[..., 0] + 1j * num[..., 1]
    return complex(z) if z.ndim == 0 else z.tolist()


def _elide(items: list[str], limit: int) -> list[str]:
    return items if len(items) <= limit else [*items[: limit - 1], "…"]


def format_matrix(value: Any, digits: int = 4) -> tuple[tuple[str, ...], ...]:
    """A numeric matrix as strings with ``digits`` significant digits; rows and columns beyond
    :data:`_MATRIX_MAX` are elided with ``…``."""
    rows = [list(r) for r in value]
    shown_rows = rows if len(rows) <= _MATRIX_MAX else [*rows[: _MATRIX_MAX - 1], None]
    out = []
    for r in shown_rows:
        if r is None:
            out.append(tuple("⋮" for _ in range(min(len(rows[0]), _MATRIX_MAX))))
        else:
            out.append(tuple(_elide([fmt_number(x, digits) for x in r], _MATRIX_MAX)))
    return tuple(out)


def fmt_compact(value: Any, digits: int = 4) -> str:
    """``value`` on one line, in words rather than Python notation.

    Numbers as :func:`fmt_number`; an empty mapping or sequence as ``"none"``; a mapping as
    ``"name = value, ..."`` with its keys in words (:func:`human_key`), nested ones in parentheses;
    a sequence as its items separated by commas (rows of a nested sequence in parentheses,
    separated by ``;``), cut after :data:`_LIST_MAX` items with their count.
    """
    if isinstance(value, str):
        return plain_complex(sentence_units(value))  # units written one way (N·m, not N*m), no Python complex
    if isinstance(value, bool | np.bool_):
        return "yes" if value else "no"
    if _is_number(value) or isinstance(value, complex | np.complexfloating) or value is None:
        return fmt_number(value, digits)
    if isinstance(value, Mapping):
        if not value:
            return "none"
        items = []
        for k, v in value.items():
            text = fmt_compact(v, digits)
            if isinstance(v, Mapping) and v or (isinstance(v, Sequence | np.ndarray) and not isinstance(v, str)
                                                and len(v) > 1):
                text = f"({text})"
            items.append(f"{human_key(str(k))} = {text}")
        return ", ".join(items)
    if isinstance(value, Sequence | np.ndarray):
        seq = list(value)
        if not seq:
            return "none"
        nested = [v for v in seq if isinstance(v, Sequence | np.ndarray | Mapping) and not isinstance(v, str)]
        if len(seq) == 1 and nested:
            return fmt_compact(seq[0], digits)
        items = [fmt_compact(v, digits) for v in seq]
        if nested:
            items = [f"({t})" for t in items]
        shown = _elide(items, _LIST_MAX)
        return ("; " if nested else ", ").join(shown) + (f" ({len(items)} items)" if len(items) > _LIST_MAX else "")
    return str(value)


def render_certificate(certificate: Mapping[str, Any], digits: int = 4) -> tuple[CertificateEntry, ...]:
    """A certificate as compact entries: matrices as string grids, everything else as one line.

    Nested mappings are flattened to dotted keys (``key``; ``label`` says it in words); a ``grid``
    entry (robustness sweep) is summarised (its full data goes to a figure).
    """
    out: list[CertificateEntry] = []

    def visit(prefix: str, value: Any) -> None:
        leaf = prefix.rsplit(".", 1)[-1]
        if leaf == "grid" and isinstance(value, Mapping):
            figure = robustness_grid({"grid": value}) is not None
            out.append(CertificateEntry(prefix, _grid_summary(value, digits, figure=figure)))
        elif isinstance(value, Mapping) and value:
            for k, v in value.items():
                visit(f"{prefix}.{k}" if prefix else str(k), v)
        elif _is_records(value):
            header = tuple(dict.fromkeys(k for rec in value for k in rec))
            pairs = _COMPLEX_KEYS.search(leaf) is not None  # e.g. pole_matching: [re, im] cells

            def cell(v: Any) -> str:
                z = _as_complex(v, single=True) if pairs else None
                return fmt_compact(v if z is None else z, digits)

            shown = value[:_RECORDS_MAX]
            rows = tuple(tuple(cell(rec.get(h)) for h in header) for rec in shown)
            if len(value) > len(shown):
                rows += (tuple("…" for _ in header),)
            out.append(CertificateEntry(prefix, f"{len(value)} rows", rows, tuple(human_key(str(h)) for h in header)))
        elif _COMPLEX_KEYS.search(leaf) and _as_complex(value, single=_SINGLE_KEYS.search(leaf) is not None):
            z = _as_complex(value, single=_SINGLE_KEYS.search(leaf) is not None)
            out.append(CertificateEntry(prefix, fmt_compact(z, digits)))
        elif _is_matrix(value) and len(value) > 1:
            out.append(CertificateEntry(prefix, f"{len(value)}×{len(value[0])}", format_matrix(value, digits)))
        else:
            out.append(CertificateEntry(prefix, fmt_compact(value, digits)))

    for key, value in certificate.items():
        visit(str(key), value)
    return tuple(out)


def _grid_summary(grid: Mapping[str, Any], digits: int, *, figure: bool) -> str:
    parts = []
    for axis in grid.get("axes", []) if isinstance(grid.get("axes"), list | tuple) else []:
        try:
            arr = np.asarray(axis["values"], dtype=float).ravel()
        except (TypeError, ValueError, KeyError):
            continue
        if arr.size:
            unit = sentence_units(f" {axis.get('unit', '')}".rstrip())
            parts.append(f"{axis.get('name', '?')} ∈ [{fmt_number(arr.min(), digits)}, {fmt_number(arr.max(), digits)}]"
                         f"{unit} ({arr.size} points)")
    with contextlib.suppress(TypeError, ValueError):  # values that are not numbers are simply not summarised
        arr = np.asarray(grid.get("values"), dtype=float)
        if arr.size > 1:
            parts.append(f"margin: min {fmt_number(np.nanmin(arr), digits)}, max {fmt_number(np.nanmax(arr), digits)}")
    if "label" in grid:
        parts.append(str(grid["label"]))
    return "; ".join(parts) + (" (see the robustness figure)" if figure else "")
