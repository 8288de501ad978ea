"""PID trajectory tracking of any single-input linear plant: the servo's gains and the plant's inverse as feedforward.

Plant ``x' = A x + b (u + xi)``, ``y = c x`` with ``G(s) = N(s)/D(s)`` (nominal), relative degree ``rho``.  Law, with
``e = y - xD``, the integral ``x_I' = e`` and the rate row ``r = c A`` (:mod:`designkit.synthesis.linear_servo`)::

    u = u_ff - K1 e - K2 (r x - rho_D) - K3 x_I,     u_ff = G^-1(s) xD,     rho_D = xD' - (c b) u_ff

**Feedforward.**  ``G^-1 = D/N`` is split by polynomial division into ``Q(s) + R(s)/N(s)``, ``deg Q = rho``:
``u_ff = q_0 xD + q_1 xD' + q_2 xD'' + w`` with ``w = (R/N) xD`` the output of a filter with ``deg N`` states (the
controllable canonical form of ``R/N``, poles at the plant's zeros), started at rest.  A trajectory gives ``xD``,
``xD'`` and ``xD''``, so ``rho <= 2`` is needed, and the filter is stable only when every plant zero is in the open
left half plane (minimum phase); other plants are refused at ``controller.kind`` with the reason (the servo
``pid_servo`` takes them).

**Exact tracking on the nominal plant.**  ``rho_D`` is the rate row on the nominal trajectory: ``r x = y' - (c b) u``
(``c b = 0`` at relative degree 2).  If ``y = xD`` and ``u = u_ff`` then ``e = 0``, ``x_I`` is constant (at rest) and
``r x = rho_D``: every feedback term vanishes, so the nominal trajectory is a solution and ``y/xD = 1``
identically.  The error obeys the servo's homogeneous loop, whose poles the gains place
(:func:`~designkit.synthesis.linear_servo.place`: 2 on a first-order plant, 3 otherwise with the others stated);
the filter's poles (the plant's zeros) are poles of the loop too, uncontrollable from the error, and
``xi -> y`` has the zeros ``0`` (integral action), the plant's zeros and the filter's modes it does not reach
(``design.extra["disturbance_zeros"]``, read by the ``pole_placement`` check).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.errors import SpecError
from designkit.synthesis.closed_loop import with_closed_loop
from designkit.synthesis.design import Design, FamilyData, Gain, Gains
from designkit.synthesis.law import Law, State, dynamic_law, integral_law
from designkit.synthesis.linear_servo import place

__all__ = ["Inverse", "linear_tracking_design", "linear_tracking_law", "plant_inverse"]

ZERO_TOL = 1e-12
"""Relative size below which a transfer-function coefficient is taken as 0 (relative degree, ``N(0)``)."""


@dataclass(frozen=True)
class Inverse(FamilyData):
    """``G^-1(s) = D(s)/N(s) = Q(s) + R(s)/N(s)`` realised as a feedforward of ``xD``, ``xD'``, ``xD''`` (the design's
    :attr:`~designkit.synthesis.design.Design.data` on a linear plant).

    Attributes
    ----------
    q : tuple of float
        ``(q_0, q_1, q_2)``: the coefficients of ``xD``, ``xD'``, ``xD''`` (input unit per output unit, times s, s^2).
    F : tuple of tuple of float
        The filter's ``m x m`` matrix (1/s), controllable canonical form of ``1/N`` (``N`` made monic).
    g : tuple of float
        Its input column (the last state driven by ``xD``).
    h : tuple of float
        Its output row: ``w = h z``.
    zeros : tuple of complex
        The plant's zeros (1/s): the filter's poles.
    relative_degree : int
        ``deg D - deg N``.
    """

    q: tuple[float, float, float]
    F: tuple[tuple[float, ...], ...]
    g: tuple[float, ...]
    h: tuple[float, ...]
    zeros: tuple[complex, ...]
    relative_degree: int


def _trim(p: np.ndarray, scale: float) -> np.ndarray:
    p = np.asarray(p, float)
    k = 0
    while k < len(p) - 1 and abs(p[k]) <= ZERO_TOL * scale:
        k += 1
    return p[k:]


def plant_inverse(A: np.ndarray, b: np.ndarray, c: np.ndarray) -> Inverse:
    """The feedforward realising ``G^-1`` (module docstring, "Feedforward").

    ``D(s) = det(sI - A)`` and ``N(s) = det(sI - A + b c) - det(sI - A)`` (the matrix determinant lemma:
    ``c adj(sI - A) b``), both by ``numpy.poly``.

    Raises
    ------
    SpecError
        At ``controller.kind``: relative degree above 2, or a zero in the closed right half plane.
    """
    A = np.asarray(A, float)
    b, c = np.asarray(b, float).ravel(), np.asarray(c, float).ravel()
    D = np.real(np.poly(A))
    N = np.real(np.poly(A - np.outer(b, c))) - D
    N = _trim(N, float(np.max(np.abs(D))) * max(float(np.max(np.abs(b))) * float(np.max(np.abs(c))), 1e-300))
    if np.all(N == 0):
        raise SpecError("controller.kind", "pid_tracking: the input does not reach the output (G(s) = 0)")
    rho = len(D) - len(N)
    if rho > 2:
        raise SpecError("controller.kind", f"pid_tracking makes y follow xD through the plant's inverse, which needs "
                        f"the reference's first {rho} derivatives on this plant of relative degree {rho}; a trajectory "
                        "gives xD, xD' and xD'' (relative degree 1 or 2 only): use pid_servo")
    zeros = tuple(complex(z) for z in np.roots(N)) if len(N) > 1 else ()
    bad = [z for z in zeros if z.real >= 0]
    if bad:
        raise SpecError("controller.kind", "pid_tracking's inverse feedforward has its poles at the plant's zeros; "
                        "this plant has the zero(s) " + ", ".join(f"{z.real:.4g}{z.imag:+.4g}j" for z in bad)
                        + " 1/s in the closed right half plane (not minimum phase), so the inverse diverges: use "
                        "pid_servo")
    lead = N[0]
    Qp, Rp = np.polydiv(D / lead, N / lead)  # D/N = Q + R/N with N monic
    m = len(N) - 1
    Qp = np.atleast_1d(Qp)
    q = np.zeros(3)
    q[:len(Qp)] = Qp[::-1]
    Nm = N / lead
    F = np.zeros((m, m))
    if m:
        F[:-1, 1:] = np.eye(m - 1)
        F[-1, :] = -Nm[1:][::-1]
    g = np.zeros(m)
    if m:
        g[-1] = 1.0
    R = np.atleast_1d(Rp)
    R = np.concatenate([np.zeros(max(m - len(R), 0)), R[-m:]]) if m else np.zeros(0)
    h = R[::-1].copy()  # R(s) = h_(m-1) s^(m-1) + ... + h_0 over the controllable form of 1/N
    return Inverse(tuple(float(v) for v in q), tuple(tuple(float(v) for v in row) for row in F),
                   tuple(float(v) for v in g), tuple(float(v) for v in h), zeros, rho)


def linear_tracking_design(plant: Any, poles: Sequence[complex], *, kind: str, notes: tuple[str, ...] = (),
                           extra: dict | None = None) -> Design:
    """The PID tracker of a single-input linear ``plant`` whose error loop has ``poles`` (module docstring).

    Parameters
    ----------
    plant : LinearPlant
        A ``transfer_function`` or ``state_space`` plant with one input, relative degree 1 or 2, minimum phase.
    poles : sequence of complex
        The error loop's poles (1/s): 2 on a first-order plant, else 3.
    kind : str
        The design's controller kind.
    notes : tuple of str
        Notes to carry.
    extra : dict or None
        Entries generic layers read by name.

    Raises
    ------
    SpecError
        At ``plant.B`` (inputs), ``controller.kind`` (:func:`plant_inverse`) or ``controller.poles``
        (:func:`~designkit.synthesis.linear_servo.place`).
    """
    A, B, _, _ = plant.matrices()
    n = A.shape[0]
    if B.shape[1] != 1:
        raise SpecError("plant.B", f"the PID tracker drives a single-input plant; this one has {B.shape[1]} inputs")
    b, pos = B[:, 0], plant.positions[0]
    c = np.eye(n)[pos]
    inv = plant_inverse(A, b, c)
    pl = place(A, b, c, c @ A, poles)
    u = plant.inputs[0].unit
    y = plant.states[pos].unit
    gains = [Gain("K1", pl.K1, f"{u}/({y})", "proportional"),
             Gain("K2", pl.K2, f"{u}/({y}/s)", "rate feedback on r x - rho_D"
                  + (" (0: a multiple of y on a first-order plant)" if n == 1 else "")),
             Gain("K3", pl.K3, f"{u}/({y}*s)", "integral")]
    gains += [Gain(f"q{k}", inv.q[k], f"{u}/({y})" + ("" if k == 0 else f"*s^{k}" if k > 1 else "*s"),
                   f"feedforward of xD{chr(39) * k}" if k else "feedforward of xD") for k in range(3)]
    fmt = ", ".join(f"{z.real:.4g}" if abs(z.imag) < 1e-12 else f"{z:.4g}" for z in inv.zeros)
    notes_out = [*notes, pl.statement,
                 f"Feedforward u_ff = G^-1(s) xD: q = ({', '.join(f'{v:.6g}' for v in inv.q)}) on (xD, xD', xD'')"
                 + (f" plus a filter of {len(inv.zeros)} state(s) whose poles are the plant's zeros {fmt} 1/s "
                    "(poles of the loop too, not moved by the gains)." if inv.zeros else
                    "; the plant has no finite zero, so no filter: G^-1 is a polynomial.")]
    formulas = (
        "u = u_ff − K1 e − K2 (r x − ρ_D) − K3 ∫e dt,  e = y − xD,  r x = c A x,  ρ_D = xD' − (c b) u_ff",
        "u_ff = G⁻¹(s) xD = Q(s) xD + (R(s)/N(s)) xD,  G⁻¹ = D/N = Q + R/N (deg Q = relative degree ≤ 2)",
        "on the nominal plant y = xD is a solution with every feedback term 0: y/xD = 1; the error loop is the "
        "servo's, its gains placed as there",
    )
    d = Design(kind=kind, plant=plant, gains=Gains.of(gains), poles=(*pl.poles, *inv.zeros), zeros=(),
               reference="trajectory", formulas=formulas, notes=tuple(notes_out),
               extra={**(extra or {}), "disturbance_zeros": (*inv.zeros, *inv.zeros)}, data=inv)
    return with_closed_loop(d, linear_tracking_law(d), [0.0, 0.0, 0.0], field="controller.poles")


def linear_tracking_law(design: Design, anti_windup: Any = None) -> Law:
    """``u = u_ff - K1 e - K2 (c A x - rho_D) - K3 x_I`` (module docstring), in the plant's input unit.

    Raises
    ------
    SpecError
        At ``simulation.anti_windup`` on a plant with zeros (the law with a feedforward filter has no anti-windup).
    """
    import casadi as ca

    K1, K2, K3 = (float(design.gains[k]) for k in ("K1", "K2", "K3"))
    inv: Inverse = design.data
    plant = design.plant
    A, B, _, _ = plant.matrices()
    pos = plant.positions[0]
    rrow = ca.DM(np.asarray(plant.rate_row(), float))
    cb = float(B[pos, 0])
    q0, q1, q2 = inv.q
    h = np.asarray(inv.h, float)
    settings = {"gains": design.gains.to_json()}

    def command(y: Any, r: Any, xI: Any, z: Any) -> Any:
        uff = q0 * r[0] + q1 * r[1] + q2 * r[2] + (ca.dot(ca.DM(h), z) if len(h) else 0.0)
        rate_ref = r[1] - cb * uff
        return uff - K1 * (y[pos] - r[0]) - K2 * (ca.dot(rrow, y) - rate_ref) - K3 * xI

    if not inv.zeros:
        return integral_law(design.kind, plant, [K3], anti_windup,
                            lambda y, xc, r, e: command(y, r, xc[0], None), settings)
    if anti_windup is not None:
        raise SpecError("simulation.anti_windup", "the PID tracker of a plant with zeros carries a feedforward filter "
                        "and takes no anti-windup")
    F, g = np.asarray(inv.F, float), np.asarray(inv.g, float)
    m = len(g)
    names = [f"w{k + 1}" for k in range(m)]

    def filt(s: Any) -> Any:
        return ca.vertcat(*[s.state(nm) for nm in names])

    states = [State("x3", lambda s: s.q[0] - s.qD[0], integral=True)]
    states += [State(nm, lambda s, k=k: ca.dot(ca.DM(F[k]), filt(s)) + g[k] * s.qD[0]) for k, nm in enumerate(names)]
    return dynamic_law(design.kind, plant, states=states, settings=settings,
                       command=lambda s: command(s.y, s.r, s.state("x3"), filt(s)))
