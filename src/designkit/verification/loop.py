"""The loop transfer at each plant input, its margins, and the zeros of the closed loop.

The loop is broken where the control enters the plant.  With the design's ``input_loop``
(``A`` the linear closed loop, ``B`` the columns where the plant inputs enter, ``C = -du/dz``),
breaking input ``i`` with the other loops closed gives ``A_i = A + B_i C_i`` and

    L_i(s) = C_i (sI - A_i)^-1 B_i,     1 + L_i(s) = det(sI - A) / det(sI - A_i)

For the PID servo on the link this is ``L(s) = Km (K2 s^2 + K1 s + K3) / (s^2 (tau s + 1))``,
i.e. ``C(s) P(s)`` with ``C(s) = K1 + K2 s + K3/s`` acting on ``x1`` and ``P(s) = Km / (s (tau s + 1))``;
for the tracker the ``x2/Km`` term replaces ``K2`` by ``K2 - 1/Km`` (tested against these closed
forms).  The ``loop_margins`` check reports, per input, the gain and phase margins and the modulus
margin ``min |1 + L(jw)|``, and its data drives the report's Bode plots.  With
``requirements.gain_margin`` (dB), ``phase_margin`` (deg) or ``modulus_margin`` it decides the verdict;
without, it is informational but **flags weak margins** against the defaults a controls engineer
would accept (:data:`WEAK_MARGINS`: gain margin below 6 dB, phase margin below 30 deg, modulus margin
below 0.5), in its detail and in its ``warnings``.

**Numerical resolution.**  A crossover more than :data:`RESOLUTION_DECADES` decades below the
loop's slowest time scale (the smallest non-zero ``|eigenvalue|`` of ``A`` and ``A_i``) is at the
edge of what the polynomial roots resolve -- a double integrator's phase sits at -180 deg as
``w -> 0`` and rounding puts a "crossing" at ``1e-7`` rad/s with ``|L| ~ 1e16`` -- and is read as
no crossover (margin ``inf``).

The crossovers are exact, not read off a grid (:func:`crossovers`): with ``L = n(s)/d(s)``,
``d = det(sI - A_i)`` and ``n = det(sI - A_i + b_i c_i) - d`` (the identity
``det(sI - A + bc) = det(sI - A)(1 + c (sI - A)^-1 b)``), the phase crossovers are the positive
real roots of ``Im(n(jw) conj d(jw))`` where ``Re L(jw) < 0`` and the gain crossovers those of
``|n(jw)|^2 - |d(jw)|^2``; ``L`` itself is evaluated from the state space at those frequencies.
The tests compare the margins with python-control's ``stability_margins`` (same definitions:
the gain margin closest to 1 on a log scale, the phase margin smallest in magnitude).

SciPy is imported lazily, inside the functions that need it.
"""

from __future__ import annotations

import contextlib
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.synthesis.design import loop_matrices
from designkit.verification.check import Check

__all__ = ["RESOLUTION_DECADES", "WEAK_MARGINS", "LoopMargins", "achieved_zeros", "classical_margins", "crossovers",
           "frequency_grid", "loop_frequency_response", "loop_margins",
           "loop_margins_check", "loop_matrices", "siso_zeros"]


RESOLUTION_DECADES = 6
"""Crossovers this many decades below the loop's slowest time scale are numerical artefacts."""

WEAK_MARGINS = {"gain_margin_db": 6.0, "phase_margin_deg": 30.0, "modulus_margin": 0.5}
"""Margins below these are flagged when the spec states no margin requirement (Skogestad & Postlethwaite,
*Multivariable Feedback Control*, 2nd ed., sec. 2.4: GM > 2, PM > 30 deg, and MS < 2, i.e. min |1 + L| > 0.5)."""


@dataclass(frozen=True)
class LoopMargins:
    """Classical margins of the loop broken at one plant input.

    Parameters
    ----------
    gain_margin : float
        Gain margin (ratio; ``inf`` when the phase never crosses -180 deg at a finite frequency;
        below 1 for a conditionally stable loop, where the gain may only be *reduced* by that factor).
    phase_margin : float
        Phase margin (deg), ``inf`` when ``|L|`` never crosses 1.
    w_phase_crossover, w_gain_crossover : float
        Frequencies (rad/s) of the phase and gain crossovers (``nan`` when absent).
    modulus_margin : float
        ``inf |1 + L(jw)|`` over the frequency grid and ``w -> inf`` (dimensionless; at most 1
        because ``L`` is strictly proper).
    """

    gain_margin: float
    phase_margin: float
    w_phase_crossover: float
    w_gain_crossover: float
    modulus_margin: float


def siso_zeros(A: np.ndarray, b: np.ndarray, c: np.ndarray, d: float) -> np.ndarray:
    """Finite transmission zeros (1/s) of a SISO state-space system, ascending: those of
    :func:`designkit.verification.pole_zero.finite_zeros` (Rosenbrock pencil, infinite ones dropped)."""
    from designkit.verification.pole_zero import Siso, finite_zeros

    n = A.shape[0]
    z, _ = finite_zeros(Siso(A, np.reshape(b, (n, 1)), np.reshape(c, (1, n)), np.array([[d]], dtype=float)))
    return np.sort_complex(z)


def achieved_zeros(design: Any) -> np.ndarray:
    """Zeros of the first joint's ``xD -> x1`` channel of the closed loop (empty when the design requests none)."""
    cl = design.closed_loop
    if not design.zeros or cl is None:
        return np.array([], dtype=complex)
    return siso_zeros(cl.A, cl.B[:, 0], cl.C[0], float(cl.D[0, 0]))


def loop_frequency_response(design: Any, w: np.ndarray, channel: int = 0) -> np.ndarray | None:
    """``L_i(jw)`` at the frequencies ``w`` (rad/s)."""
    mats = loop_matrices(design, channel)
    if mats is None:
        return None
    A, b, c = mats
    return _response(A, b, c, w)


def frequency_grid(design: Any) -> np.ndarray:
    """600 log-spaced frequencies (rad/s), one decade beyond the slowest and fastest pole magnitudes."""
    poles = list(np.linalg.eigvals(design.closed_loop.A)) if design.closed_loop is not None else []
    mags = [abs(p) for p in (*poles, *design.poles) if abs(p) > 1e-9]
    lo, hi = (min(mags), max(mags)) if mags else (1.0, 1.0)
    return np.logspace(math.floor(math.log10(lo)) - 1, math.ceil(math.log10(hi)) + 1, 600)


def _real_roots(coeffs: np.ndarray, *, include_zero: bool) -> np.ndarray:
    """Real roots ``w > 0`` (``w >= 0`` with ``include_zero``) of a real polynomial (highest power first), ascending."""
    coeffs = np.trim_zeros(np.asarray(coeffs, dtype=float), "f")
    if coeffs.size < 2:
        return np.array([])
    roots = np.roots(coeffs)
    scale = max(float(np.max(np.abs(roots))), 1.0)
    w = roots[np.abs(roots.imag) <= 1e-9 * np.maximum(np.abs(roots), 1.0)].real
    w = np.where(np.abs(w) <= 1e-12 * scale, 0.0, w)  # a root at the origin, as computed
    return np.sort(w[w >= 0] if include_zero else w[w > 0])


def _at_jw(poly: np.ndarray) -> np.ndarray:
    """Coefficients (in ``w``, highest power first, complex) of ``p(jw)`` for a polynomial ``p(s)``."""
    poly = np.asarray(poly, dtype=float)
    return poly * (1j) ** np.arange(poly.size - 1, -1, -1)


def crossovers(A: np.ndarray, b: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Phase and gain crossover frequencies (rad/s) of ``L(s) = c (sI - A)^-1 b`` (module docstring).

    Returns
    -------
    w_phase : ndarray
        ``w >= 0`` where ``L(jw)`` is finite, real and negative (the Nyquist curve crosses the negative real axis;
        ``w = 0`` counts when ``L(0)`` is finite and negative).
    w_gain : ndarray
        ``w > 0`` where ``|L(jw)| = 1``.
    """
    den = np.poly(A)
    num = np.poly(A - b @ c) - den  # the leading coefficients cancel exactly (both monic)
    n_iw, d_iw = _at_jw(num), _at_jw(den)
    im_part = np.polysub(np.polymul(n_iw.imag, d_iw.real), np.polymul(n_iw.real, d_iw.imag))
    mag = np.polysub(np.real(np.polymul(n_iw, n_iw.conj())), np.real(np.polymul(d_iw, d_iw.conj())))
    w_phase = _real_roots(im_part, include_zero=True)
    if w_phase.size:
        with np.errstate(all="ignore"):
            resp = _response(A, b, c, w_phase)
        w_phase = w_phase[np.isfinite(resp) & (resp.real < 0)]
    w_gain = _real_roots(mag, include_zero=False)
    floor = _resolution(A, b, c)
    return w_phase[(w_phase == 0) | (w_phase >= floor)], w_gain[w_gain >= floor]


def _resolution(A: np.ndarray, b: np.ndarray, c: np.ndarray) -> float:
    """Frequencies (rad/s) below which a crossover is a numerical artefact (module docstring)."""
    lam = np.abs(np.concatenate([np.linalg.eigvals(A), np.linalg.eigvals(A - b @ c)]))
    nonzero = lam[lam > 1e-12 * max(float(lam.max(initial=0.0)), 1e-300)]
    return float(nonzero.min()) * 10.0 ** -RESOLUTION_DECADES if nonzero.size else 0.0


def _response(A: np.ndarray, b: np.ndarray, c: np.ndarray, w: np.ndarray) -> np.ndarray:
    """``c (jw I - A)^-1 b`` at the frequencies ``w`` (rad/s), batched."""
    w = np.asarray(w, dtype=float)
    n = A.shape[0]
    Ms = 1j * w[:, None, None] * np.eye(n)[None, :, :] - A[None, :, :]
    bc = b.astype(complex)
    with contextlib.suppress(np.linalg.LinAlgError):  # one batched solve, unless some frequency is singular
        return (c @ np.linalg.solve(Ms, np.broadcast_to(bc, (w.size, n, 1))))[:, 0, 0]
    out = np.full(w.size, complex(np.inf, 0.0))
    for k, M in enumerate(Ms):
        with contextlib.suppress(np.linalg.LinAlgError):  # singular: an imaginary-axis pole of L, L = inf
            out[k] = (c @ np.linalg.solve(M, bc))[0, 0]
    return out


def classical_margins(A: np.ndarray, b: np.ndarray, c: np.ndarray) -> tuple[float, float, float, float]:
    """Gain margin, phase margin (deg) and their crossover frequencies (rad/s) of ``L(s) = c (sI - A)^-1 b``.

    Of several crossovers, the gain margin is the one closest to 1 on a log scale and the phase
    margin the one smallest in magnitude (python-control's ``stability_margins`` convention); a
    margin without a crossover is ``inf`` and its frequency ``nan``.

    Returns
    -------
    gain_margin, phase_margin, w_phase_crossover, w_gain_crossover : float
    """
    A, b, c = (np.atleast_2d(np.asarray(m, dtype=float)) for m in (A, b, c))
    b, c = b.reshape(-1, 1), c.reshape(1, -1)
    w_phase, w_gain = crossovers(A, b, c)
    gm, wpc = math.inf, math.nan
    if w_phase.size:
        with np.errstate(divide="ignore"):
            gms = 1.0 / np.abs(_response(A, b, c, w_phase))
            k = int(np.argmin(np.abs(np.log(gms))))
        gm, wpc = float(gms[k]), float(w_phase[k])
    pm, wgc = math.inf, math.nan
    if w_gain.size:
        pms = np.remainder(np.angle(_response(A, b, c, w_gain), deg=True), 360.0) - 180.0
        k = int(np.argmin(np.abs(pms)))
        pm, wgc = float(pms[k]), float(w_gain[k])
    return gm, pm, wpc, wgc


def loop_margins(design: Any, channel: int = 0) -> LoopMargins | None:
    """Margins (:func:`classical_margins`) of the loop broken at plant input ``channel`` and its modulus
    margin ``inf |1 + L(jw)|`` over :func:`frequency_grid`."""
    mats = loop_matrices(design, channel)
    if mats is None:
        return None
    gm, pm, wpc, wgc = classical_margins(*mats)
    resp = loop_frequency_response(design, frequency_grid(design), channel)
    return LoopMargins(
        gain_margin=gm, phase_margin=pm, w_phase_crossover=wpc, w_gain_crossover=wgc,
        # L is strictly proper, so |1 + L(jw)| -> 1 as w -> inf: the infimum is at most 1
        modulus_margin=min(float(np.min(np.abs(1.0 + resp))), 1.0),
    )


def _finite(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def _requirements(spec: Any) -> dict[str, float]:
    req = getattr(spec, "requirements", None) if spec is not None else None
    given = {"gain_margin_db": getattr(req, "gain_margin", None),
             "phase_margin_deg": getattr(req, "phase_margin", None),
             "modulus_margin": getattr(req, "modulus_margin", None)}
    return {k: float(v) for k, v in given.items() if v is not None}


def _db(ratio: float | None) -> float | None:
    return None if ratio is None else (math.inf if not math.isfinite(ratio) else 20.0 * math.log10(ratio))


def _shortfalls(row: dict[str, Any], limits: dict[str, float]) -> list[tuple[str, float, float]]:
    """``(what, value, limit)`` of each margin of ``row`` below its limit."""
    # a gain margin below 1 (conditionally stable loop) is how far the gain may *fall*: its size is |dB|
    values = {"gain_margin_db": abs(_db(row["gain_margin"])) if row["gain_margin"] is not None else math.inf,
              "phase_margin_deg": row["phase_margin_deg"] if row["phase_margin_deg"] is not None else math.inf,
              "modulus_margin": row["modulus_margin"]}
    return [(k, values[k], v) for k, v in limits.items() if values[k] < v]


_WORDS = {"gain_margin_db": ("gain margin", "dB"), "phase_margin_deg": ("phase margin", "°"),
          "modulus_margin": ("modulus margin min |1 + L|", "")}


def _sentence(name: str, what: str, value: float, limit: float) -> str:
    words, unit = _WORDS[what]
    sep = "" if unit in ("°", "") else " "
    return f"{name}: {words} {value:.3g}{sep}{unit}, below {limit:.3g}{sep}{unit}"


def loop_margins_check(design: Any, spec: Any = None) -> Check:
    """Check ``"loop_margins"``: margins of the loop broken at each plant input.

    Decides the verdict when the spec's requirements give ``gain_margin`` (dB; a gain margin below 1, of a
    conditionally stable loop, counts by its size ``|20 log10 GM|``: how far the gain may fall),
    ``phase_margin`` (deg) or ``modulus_margin``; otherwise informational, with a warning for every margin below
    :data:`WEAK_MARGINS`.  ``achieved`` is the smallest modulus margin over the inputs (the distance of the
    Nyquist curve to -1); the certificate lists every input's margins and crossovers and the limits applied;
    ``data`` holds the frequency responses for the report's Bode plots.
    """
    inputs = list(design.input_loop.inputs) if design.input_loop is not None else []
    rows, data = [], {"frequency": frequency_grid(design).tolist(), "channels": []}
    for i, name in enumerate(inputs):
        m = loop_margins(design, i)
        if m is None:
            continue
        resp = loop_frequency_response(design, np.asarray(data["frequency"]), i)
        rows.append({
            "input": name, "gain_margin": _finite(m.gain_margin), "gain_margin_db": _finite(_db(m.gain_margin)),
            "phase_margin_deg": _finite(m.phase_margin), "phase_crossover_rad_s": _finite(m.w_phase_crossover),
            "gain_crossover_rad_s": _finite(m.w_gain_crossover), "modulus_margin": m.modulus_margin,
        })
        data["channels"].append({"input": name, "margins": m, "response": resp})
    if not rows:
        return Check(name="loop_margins", passed=None, detail="no loop at the plant input to break", required=False)
    worst = min(rows, key=lambda r: r["modulus_margin"])
    stable = bool(np.all(np.linalg.eigvals(design.input_loop.A).real < 0))
    parts = []
    for r in rows:
        pm = f"PM {r['phase_margin_deg']:.3g}°" if r["phase_margin_deg"] is not None else "PM ∞"
        gm = (f"GM {r['gain_margin']:.3g} ({r['gain_margin_db']:.3g} dB)" if r["gain_margin"] is not None
              else "GM ∞")
        parts.append(f"{r['input']}: {pm}, {gm}, min|1+L| {r['modulus_margin']:.3g}")
    required = _requirements(spec)
    limits = required or dict(WEAK_MARGINS)
    short = [(r["input"], *s) for r in rows for s in _shortfalls(r, limits)]
    sentences = [_sentence(*s) for s in short]
    certificate = {"loops": rows, "convention": "L_i(s) = C_i (sI - A - B_i C_i)^-1 B_i, C = -du/dz; "
                   "negative feedback: the loop is -L in the feedback path",
                   "limits": limits, "limits_source": "requirements" if required else "weak-margin defaults",
                   "resolution": f"crossovers more than {RESOLUTION_DECADES} decades below the loop's slowest time "
                                 "scale are read as none (numerical artefacts)"}
    detail = "loop broken at each plant input, the others closed: " + "; ".join(parts)
    if required:
        passed = stable and not short
        target = ", ".join(f"{_WORDS[k][0]} ≥ {v:g}{'' if _WORDS[k][1] in ('°', '') else ' '}{_WORDS[k][1]}"
                           for k, v in required.items())
        if short:
            detail += ". Below the requirement: " + "; ".join(sentences)
        return Check(name="loop_margins", passed=passed, target=target, achieved=worst["modulus_margin"],
                     margin=None, unit="1 (min |1 + L|)", detail=detail, certificate=certificate, data=data)
    warnings = tuple(f"Weak stability margin at {s} (no margin requirement in the spec; the default a controls "
                     "engineer would accept)" for s in sentences)
    detail += " [informational" + (": weak margins flagged]" if warnings else "]")
    return Check(
        name="loop_margins", passed=stable, target="reported (no margin requirement in the spec; weak below 6 dB, "
        "30°, min |1 + L| 0.5)", achieved=worst["modulus_margin"], margin=None, unit="1 (min |1 + L|)",
        detail=detail, certificate=certificate, required=False, data=data, warnings=warnings,
    )
