"""Robust stability of a design over a box of plant parameters ``Km x tau``.

Three checks, each answering a different question:

``robust_vertices``
    Is the closed loop stable at the four corners of the box?  (Routh test of the family's
    characteristic polynomial at each corner.)
``robust_grid``
    Is it stable on a ``grid x grid`` lattice of the box (corners included)?  The Routh arrays of
    all lattice plants are built at once on coefficient arrays (:func:`routh_batch`), with no
    Python loop per plant.  Reports the worst (smallest) scaled Routh margin and where it occurs,
    and the worst spectral abscissa ``max Re(pole)`` (1/s).  The checks' ``margin`` is minus the
    worst spectral abscissa: the decay rate (1/s) of the slowest mode over the corners / grid.
``common_lyapunov``
    Is there one quadratic Lyapunov function for the four corner closed loops?  For the link
    families the closed-loop matrix is *affine* in ``(1/tau, Km/tau)``, and the image of the box
    in those coordinates is the quadrilateral with the corners' images as vertices (it is bounded
    by ``a = 1/tau_hi``, ``a = 1/tau_lo``, ``b = Km_lo a`` and ``b = Km_hi a``, hence convex).  So
    every plant of the box has its ``A`` in the convex hull of the corner ``A``'s, and a common
    ``P`` proves stability of the *whole continuum* of the box, even for parameters varying in
    time inside it -- something no grid can.  Meaning of the outcome:

    - ``True``: common ``P`` found and re-checked: quadratic stability over the box;
    - ``False``: some corner is itself unstable (eigenvalue evidence), so no common ``P`` exists;
    - ``None`` (undecided): the corners are stable but no common ``P`` was found.  This is *not*
      instability: the box may still be stable (see ``robust_grid``), only not provably so by a
      single quadratic function.

A missing axis of the uncertainty (``Km`` or ``tau`` not given) is held at its nominal value.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from designkit.models.link import LinkPlant
from designkit.verification.check import Check
from designkit.verification.lyapunov import common_lyapunov
from designkit.verification.routh import MARGINAL, STABLE, UNSTABLE, routh_batch
from designkit.verification.tolerances import LMI_EPS

MAX_LISTED_POINTS = 10
"""At most this many failing grid points are listed in a certificate."""


@dataclass(frozen=True)
class Box:
    """Plant parameter box.

    Parameters
    ----------
    Km : (float, float)
        Link gain interval ((rad/s)/(N*m)).
    tau : (float, float)
        Time-constant interval (s).
    grid : int
        Points per axis of the lattice.
    """

    Km: tuple[float, float]
    tau: tuple[float, float]
    grid: int = 21

    @property
    def vertices(self) -> tuple[tuple[float, float], ...]:
        """Distinct corners ``(Km, tau)``, in the order (lo, lo), (lo, hi), (hi, lo), (hi, hi)."""
        out: list[tuple[float, float]] = []
        for k in self.Km:
            for t in self.tau:
                if (k, t) not in out:
                    out.append((float(k), float(t)))
        return tuple(out)


def box_from_uncertainty(design: Any, uncertainty: Any) -> Box:
    """The box of a spec's ``plant.uncertainty``; a missing axis is held at the design's nominal value."""
    Km0, tau0 = float(design.plant.Km), float(design.plant.tau)
    Km = tuple(float(x) for x in uncertainty.Km) if uncertainty.Km is not None else (Km0, Km0)
    tau = tuple(float(x) for x in uncertainty.tau) if uncertainty.tau is not None else (tau0, tau0)
    return Box(Km=Km, tau=tau, grid=int(uncertainty.grid))


def stable_fraction(design: Any, family: Any, Km_samples: np.ndarray, tau_samples: np.ndarray) -> np.ndarray:
    """Which sampled plants the design stabilises, decided by a vectorised Routh test.

    Parameters
    ----------
    design : Design
    family : ControllerFamily
        Supplies the vectorised characteristic polynomial.
    Km_samples : array_like
        Link gains ((rad/s)/(N*m)).
    tau_samples : array_like
        Time constants (s), broadcastable with ``Km_samples``.

    Returns
    -------
    ndarray of bool, broadcast shape of the inputs
        True where the closed loop is asymptotically stable (a marginal plant counts as not
        stable); ``result.mean()`` is the stable fraction.

    Examples
    --------
    >>> from designkit.models.link import LinkPlant
    >>> from designkit.synthesis.pid import design_servo
    >>> from designkit.synthesis.registry import family
    >>> d = design_servo(LinkPlant(2.0, 0.5), [-4, -5, -20], -3.0)
    >>> stable_fraction(d, family("pid_servo"), [1.0, 2.0, 4.0], 0.5).tolist()
    [True, True, True]
    """
    Km, tau = np.broadcast_arrays(np.asarray(Km_samples, float), np.asarray(tau_samples, float))
    coeffs = family.characteristic(design, Km, tau)
    return (routh_batch(coeffs).status == STABLE).reshape(Km.shape)


@dataclass(frozen=True)
class GridSweep:
    """Routh test on a lattice of the box.

    Parameters
    ----------
    Km, tau : ndarray, shape (g,)
        Axes of the lattice.
    status : ndarray of int8, shape (g, g)
        ``[i, j]`` for ``(Km[i], tau[j])``: 1 stable, 0 marginal, -1 unstable.
    margin : ndarray, shape (g, g)
        Smallest scaled Routh first-column entry (dimensionless, > 0 iff stable).
    abscissa : ndarray, shape (g, g)
        Spectral abscissa ``max Re(root)`` of the characteristic polynomial (1/s).
    """

    Km: np.ndarray
    tau: np.ndarray
    status: np.ndarray
    margin: np.ndarray
    abscissa: np.ndarray


def _abscissa(coeffs: tuple[np.ndarray, ...]) -> np.ndarray:
    """``max Re(root)`` of many polynomials, via batched eigenvalues of companion matrices."""
    arrays = np.broadcast_arrays(*[np.asarray(c, float) for c in coeffs])
    a = np.stack([x.ravel() for x in arrays], axis=-1)
    n = a.shape[1] - 1
    comp = np.zeros((a.shape[0], n, n))
    comp[:, 0, :] = -a[:, 1:] / a[:, :1]
    comp[:, np.arange(1, n), np.arange(n - 1)] = 1.0
    return np.linalg.eigvals(comp).real.max(axis=1).reshape(arrays[0].shape)


def grid_sweep(design: Any, family: Any, box: Box) -> GridSweep:
    """Routh status, margin and spectral abscissa on the ``grid x grid`` lattice of ``box``."""
    Km = np.linspace(box.Km[0], box.Km[1], box.grid)
    tau = np.linspace(box.tau[0], box.tau[1], box.grid)
    KK, TT = np.meshgrid(Km, tau, indexing="ij")
    coeffs = family.characteristic(design, KK, TT)
    rb = routh_batch(coeffs)
    shape = KK.shape
    return GridSweep(
        Km=Km, tau=tau, status=rb.status.reshape(shape), margin=rb.margin.reshape(shape),
        abscissa=_abscissa(coeffs),
    )


def _verdict(status: np.ndarray) -> bool | None:
    if np.any(status == UNSTABLE):
        return False
    if np.any(status == MARGINAL):
        return None
    return True


def _consistent(verdict: bool | None, abscissa: np.ndarray) -> bool | None:
    """A Routh "all stable" whose eigenvalues say otherwise (possible only within rounding of the
    boundary) is downgraded to undecided, so that ``margin > 0`` whenever ``passed`` is True."""
    if verdict is True and not np.all(abscissa < 0):
        return None
    return verdict


def _word(code: int) -> str:
    return {STABLE: "stable", MARGINAL: "marginal", UNSTABLE: "unstable"}[int(code)]


def vertex_check(design: Any, family: Any, box: Box) -> Check:
    """Check ``"robust_vertices"``: Routh test at the corners of the box."""
    Km = np.array([v[0] for v in box.vertices])
    tau = np.array([v[1] for v in box.vertices])
    coeffs = family.characteristic(design, Km, tau)
    rb = routh_batch(coeffs)
    absc = _abscissa(coeffs)
    rows = [
        {"Km": float(k), "tau": float(t), "status": _word(s), "routh_margin": float(m), "spectral_abscissa": float(a)}
        for k, t, s, m, a in zip(Km, tau, rb.status, rb.margin, absc, strict=True)
    ]
    passed = _consistent(_verdict(rb.status), absc)
    worst = int(np.argmax(absc))
    bad = [r for r in rows if r["status"] != "stable"]
    if passed:
        detail = (
            f"all {len(rows)} corners stable; slowest pole Re = {absc[worst]:.4g} 1/s at "
            f"Km={Km[worst]:g}, tau={tau[worst]:g}"
        )
    elif bad:
        detail = "corner(s) not stable: " + ", ".join(f"(Km={r['Km']:g}, tau={r['tau']:g}) {r['status']}" for r in bad)
    else:
        detail = "Routh test and eigenvalues disagree within rounding at a corner: undecided"
    return Check(
        name="robust_vertices", passed=passed, target="stable at every corner of Km x tau",
        achieved=float(absc[worst]), margin=float(-absc[worst]), unit="1/s", detail=detail,
        certificate={"box": {"Km": list(box.Km), "tau": list(box.tau)}, "vertices": rows},
    )


def grid_check(design: Any, family: Any, box: Box) -> Check:
    """Check ``"robust_grid"``: vectorised Routh test on the ``grid x grid`` lattice."""
    g = grid_sweep(design, family, box)
    i, j = np.unravel_index(int(np.argmin(g.margin)), g.margin.shape)
    ia, ja = np.unravel_index(int(np.argmax(g.abscissa)), g.abscissa.shape)
    n_unstable = int(np.count_nonzero(g.status == UNSTABLE))
    n_marginal = int(np.count_nonzero(g.status == MARGINAL))
    bad_i, bad_j = np.nonzero(g.status != STABLE)
    listed = [
        {"Km": float(g.Km[a]), "tau": float(g.tau[b]), "status": _word(g.status[a, b])}
        for a, b in list(zip(bad_i, bad_j, strict=True))[:MAX_LISTED_POINTS]
    ]
    passed = _consistent(_verdict(g.status), g.abscissa)
    total = g.status.size
    worst = {"Km": float(g.Km[i]), "tau": float(g.tau[j]), "routh_margin": float(g.margin[i, j])}
    slowest = {"Km": float(g.Km[ia]), "tau": float(g.tau[ja]), "spectral_abscissa": float(g.abscissa[ia, ja])}
    if passed:
        detail = (
            f"{total} plants stable; slowest pole Re = {g.abscissa[ia, ja]:.4g} 1/s at Km={g.Km[ia]:g}, "
            f"tau={g.tau[ja]:g}; worst Routh margin {g.margin[i, j]:.3g} at Km={g.Km[i]:g}, tau={g.tau[j]:g}"
        )
    elif listed:
        detail = f"{n_unstable} unstable and {n_marginal} marginal of {total} grid plants; e.g. " + ", ".join(
            f"(Km={p['Km']:g}, tau={p['tau']:g})" for p in listed[:3]
        )
    else:
        detail = "Routh test and eigenvalues disagree within rounding on the grid: undecided"
    return Check(
        name="robust_grid", passed=passed, target=f"stable on the {box.grid} x {box.grid} grid of Km x tau",
        achieved=float(g.abscissa[ia, ja]), margin=float(-g.abscissa[ia, ja]), unit="1/s", detail=detail,
        certificate={
            "box": {"Km": list(box.Km), "tau": list(box.tau)}, "points_per_axis": box.grid, "plants": total,
            "grid": {
                "Km": [float(k) for k in g.Km], "tau": [float(t) for t in g.tau],
                "values": (-np.asarray(g.abscissa, dtype=float)).T.tolist(),
                "label": "stability margin -max Re(pole) (1/s); > 0 is stable",
            },
            "stable": int(total - n_unstable - n_marginal), "unstable": n_unstable, "marginal": n_marginal,
            "worst_margin": worst, "worst_abscissa": slowest, "failing_points": listed,
        },
    )


def lyapunov_vertex_check(
    design: Any, family: Any, box: Box, *, eps: float = LMI_EPS, solver: str = "CLARABEL"
) -> Check:
    """Check ``"common_lyapunov"``: one ``P`` for the corner closed loops (see module docstring)."""
    As = [family.closed_loop(design, LinkPlant(Km=k, tau=t)).A for k, t in box.vertices]
    c = common_lyapunov(As, eps=eps, solver=solver)
    cert = dict(c.certificate)
    cert["vertices"] = [{"Km": k, "tau": t} for k, t in box.vertices]
    cert["covers_box"] = (
        "A is affine in (1/tau, Km/tau) and the box maps onto the hull of its corners: "
        "a common P proves quadratic stability of every plant in the box"
    )
    meaning = {
        True: " -> quadratic stability over the whole box",
        False: "",
        None: " (corners stable; robust stability of the box rests on the grid check, not proven for the continuum)",
    }[c.passed]
    # Informational: a common quadratic Lyapunov function is sufficient, not necessary, for
    # robust stability, so not finding one must not make a design unverified.
    return replace(c, detail=c.detail + meaning + " [informational]", certificate=cert, required=False)


def robustness_checks(
    design: Any, family: Any, uncertainty: Any, *, eps: float = LMI_EPS, solver: str = "CLARABEL"
) -> tuple[Check, Check, Check]:
    """``robust_vertices``, ``robust_grid`` and ``common_lyapunov`` for a spec's ``plant.uncertainty``."""
    box = box_from_uncertainty(design, uncertainty)
    return (
        vertex_check(design, family, box),
        grid_check(design, family, box),
        lyapunov_vertex_check(design, family, box, eps=eps, solver=solver),
    )
