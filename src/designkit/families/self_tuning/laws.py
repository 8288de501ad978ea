"""The self-tuning regulator as one sampled CasADi law: recursive least squares, then a certainty-equivalence
design, then the command, once per sample (notes section 4.3 and the SELFTUNE simulator).  This module builds the
link's forms; the ARX form's law is :mod:`designkit.families.self_tuning.arx_law`, chosen by
:func:`self_tuning_law`.

Discrete memory (:class:`~designkit.synthesis.law.Memory`), updated at each sample ``k`` from the
measured position ``y(k)`` (and speed ``v(k)``) and the reference ``r(k)``:

* ``th1 .. thn`` the estimates ``theta``, ``P11 .. Pnn`` the covariance (row-major), ``phi1 .. phin`` the
  regressor of this sample, ``eps`` its a-priori prediction error;
* the past data: ``y1``, ``y2`` (``y(k-1)``, ``y(k-2)``, rad), ``v1`` (``v(k-1)``, rad/s), ``u1``, ``u2``
  (``u(k-1)``, ``u(k-2)``, N*m), ``r1`` (``r(k-1)``, rad), ``k`` (samples taken).  Before the first sample
  the link is taken at rest with zero input (``y(-1) = y(0)``, ``u(-1) = 0``), so the regressors are
  exact from the first sample on;
* the controller's coefficients (pole placement ``R1, S0, S1, T0``; PID ``K1, K2, K3`` and the integral
  ``I``), ``u`` the command of this sample, and the flags ``held`` (the design was refused at this
  sample and the previous coefficients kept) and ``bounded`` (the covariance bound fired).

**RLS with forgetting** (the standard form; the notes' ``P`` is this ``P / lambda``, see
docs/families/self_tuning.md)::

    eps = out - phi' theta,  K = P phi / (lambda + phi' P phi)
    theta <- theta + K eps,  P <- (P - K phi' P) / lambda   (then symmetrised)

**Ad hoc modifications** (``safeguards``, on by default): (1) a covariance bound: when ``trace P``
exceeds ``max_trace`` after an update, ``P`` is scaled down to that trace -- it fires when forgetting
inflates ``P`` along directions the data no longer excites; (2) the controller is held: an estimate
that gives a non-admissible model (``A22`` outside ``(0, 1)``, a static gain ``B(1) <= 0`` or a
Sylvester determinant below :data:`MIN_DETERMINANT` relative to ``b0^2``) leaves the previous
coefficients in use.  Without safeguards the raw estimate is used whatever it is.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import casadi as ca

from designkit.families.self_tuning.arx_law import arx_controller_names, arx_law, arx_memory_names, initial_arx
from designkit.families.self_tuning.model import desired_polynomial, diophantine, position_model
from designkit.families.self_tuning.rls import rls_step
from designkit.synthesis.law import Law, LawSymbols, Memory, dynamic_law
from designkit.synthesis.pid import servo_pid_gains

__all__ = ["KIND", "MIN_DETERMINANT", "Settings", "controller_names", "memory_names", "self_tuning_law"]

KIND = "self_tuning"
"""The controller kind of this family (the spec's ``controller.kind``)."""
MIN_DETERMINANT = 1e-9
"""A design is refused when ``|det Sylvester| < MIN_DETERMINANT b0^2 |A(1 + ...)|`` (see :func:`_design`)."""
A22_CLAMP = (1e-9, 1.0 - 1e-12)
"""``A22`` is clamped into this interval before ``ln A22`` (the speed form's conversion), never used unclamped."""


@dataclass(frozen=True)
class Settings:
    """What the law is made of (all SI).

    Parameters
    ----------
    form : {"speed", "position", "arx"}
        Estimator form: the link's two (speed measured, position differences) or the ARX model of general orders
        (:mod:`designkit.families.self_tuning.arx`).
    Ts : float
        Sampling period (s).
    forgetting : float
        ``lambda`` in (0, 1].
    P0 : float
        Initial covariance ``P(0) = P0 I``.
    theta0 : tuple of float
        Initial estimates.
    max_trace : float
        Covariance bound (trace), used with ``safeguards``.
    safeguards : bool
        The ad hoc modifications (module docstring).
    design : {"pole_placement", "pid"}
        The certainty-equivalence design.
    poles : tuple of complex
        Requested continuous poles (1/s): two (pole placement) or three (PID).
    observer : float
        Observer pole (1/s, real, negative), pole placement only.
    estimate : bool
        ``False`` switches the estimator off (the controller stays designed on ``theta0``): the
        non-adaptive comparison of the report.
    orders : tuple of int
        ``(na, nb, d)`` of the ARX form (empty for the link's forms).
    am, ao : tuple of float
        ARX form: the desired polynomial ``Am(z)`` and the observer polynomial ``Ao(z)``, monic, highest power first.
    cancel : bool
        ARX form: the estimated zeros are cancelled (``B+ = B/b0``), else kept.
    """

    form: str
    Ts: float
    forgetting: float
    P0: float
    theta0: tuple[float, ...]
    max_trace: float
    safeguards: bool
    design: str
    poles: tuple[complex, ...]
    observer: float = 0.0
    estimate: bool = True
    orders: tuple[int, ...] = ()
    am: tuple[float, ...] = ()
    ao: tuple[float, ...] = ()
    cancel: bool = False

    @property
    def n(self) -> int:
        """Number of estimated parameters."""
        return len(self.theta0)

    def desired(self) -> tuple[float, ...]:
        """``(c1, c2, c3)`` of the requested discrete characteristic polynomial (pole placement); ARX form: the
        coefficients of ``Am Ao`` after the leading one."""
        if self.form == "arx":
            import numpy as np

            return tuple(float(v) for v in np.polymul(self.am, self.ao)[1:])
        return desired_polynomial(self.poles, self.observer, self.Ts)


def controller_names(design: str, st: Settings | None = None) -> tuple[str, ...]:
    """The controller coefficients kept in memory for ``design`` (the ARX form's from its settings ``st``)."""
    if st is not None and st.form == "arx":
        return arx_controller_names(st)
    return ("R1", "S0", "S1", "T0") if design == "pole_placement" else ("K1", "K2", "K3", "I")


def memory_names(st: Settings) -> tuple[str, ...]:
    """Every memory entry of the law, in order (module docstring)."""
    if st.form == "arx":
        return arx_memory_names(st)
    n = st.n
    return (*(f"th{i + 1}" for i in range(n)), *(f"P{i + 1}{j + 1}" for i in range(n) for j in range(n)),
            *(f"phi{i + 1}" for i in range(n)), "eps", "y1", "y2", "v1", "u1", "u2", "r1", "k",
            *controller_names(st.design), "u", "held", "bounded")


def initial_controller(st: Settings) -> tuple[float, ...]:
    """The controller coefficients designed on ``theta0`` (NumPy): used before any estimate is admissible."""
    if st.form == "arx":
        return initial_arx(st)
    model = position_model(st.theta0, st.Ts, st.form)
    if st.design == "pole_placement":
        c = st.desired()
        r1, s0, s1 = diophantine(model, c)
        zo = float(ca.exp(st.observer * st.Ts))
        am1 = (1.0 + c[0] + c[1] + c[2]) / (1.0 - zo)  # Acl(1) / (1 - zo) = Am(1)
        return r1, s0, s1, am1 / (model[2] + model[3])
    a22 = st.theta0[0]
    Km, tau = _link_numeric(model, a22, st.Ts)
    K1, K2, K3 = servo_pid_gains(Km, tau, st.poles)
    return K1, K2, K3, 0.0


def _link_numeric(model: Sequence[float], a22: float, Ts: float) -> tuple[float, float]:
    import math

    tau = -Ts / math.log(a22)
    return (model[2] + model[3]) / (Ts * (1.0 - a22)), tau


def _model(st: Settings, theta: ca.SX) -> tuple[ca.SX, ...]:
    """``(a1, a2, b0, b1, A22)`` of the position model from ``theta`` (symbolic :func:`position_model`)."""
    A22 = theta[0]
    if st.form == "speed":
        a = ca.fmin(ca.fmax(A22, A22_CLAMP[0]), A22_CLAMP[1])
        B2 = theta[1]
        A12 = -st.Ts * (1 - a) / ca.log(a)
        B1 = B2 / (1 - a) * (st.Ts - A12)
        b0, b1 = B1, A12 * B2 - a * B1
    else:
        b0, b1 = theta[1], theta[2]
    return -(1 + A22), A22, b0, b1, A22


def _design(st: Settings, theta: ca.SX, old: Sequence[ca.SX]) -> tuple[list[ca.SX], ca.SX]:
    """The controller coefficients from ``theta`` and the flag ``held`` (the old ones kept)."""
    a1, a2, b0, b1, A22 = _model(st, theta)
    gain = b0 + b1
    admissible = ca.logic_and(ca.logic_and(A22 > 0, A22 < 1), gain > 0)
    if st.design == "pole_placement":
        c1, c2, c3 = st.desired()
        det = b1 * b1 - a1 * b0 * b1 + a2 * b0 * b0
        admissible = ca.logic_and(admissible, ca.fabs(det) > MIN_DETERMINANT * b0 * b0)
        g1, g2, g3 = c1 - a1, c2 - a2, c3
        # Cramer's rule on the Sylvester system (model docstring)
        r1 = (g1 * b1 * b1 - b0 * (g2 * b1 - b0 * g3)) / det
        s0 = (1 * (g2 * b1 - b0 * g3) - g1 * (a1 * b1 - b0 * a2)) / det
        s1 = (1 * (b1 * g3 - 0 * g2) - b0 * (a1 * g3 - g2 * a2) + g1 * (a1 * 0 - b1 * a2)) / det
        zo = float(ca.exp(st.observer * st.Ts))
        t0 = (1 + c1 + c2 + c3) / (1 - zo) / gain
        new = [r1, s0, s1, t0]
    else:
        a = ca.fmin(ca.fmax(A22, A22_CLAMP[0]), A22_CLAMP[1])
        tau = -st.Ts / ca.log(a)
        Km = gain / (st.Ts * (1 - a))
        c = [float(v) for v in _poly3(st.poles)]
        new = [tau * c[2] / Km, (tau * c[1] - 1) / Km, tau * c[3] / Km]
    if st.safeguards:
        coefs = [ca.if_else(admissible, n_, o_) for n_, o_ in zip(new, old, strict=False)]
        held = 1 - admissible
    else:
        coefs, held = list(new), ca.SX(0)
    return coefs, held


def _poly3(poles: Sequence[complex]) -> list[float]:
    import numpy as np

    return list(np.real(np.poly([complex(p) for p in poles])))


def _pole_words(p: complex) -> str:
    p = complex(p)
    return f"{p.real:g}" if p.imag == 0 else f"{p.real:g} ± {abs(p.imag):g}j"


def self_tuning_law(nominal: Any, st: Settings) -> Law:
    """The sampled self-tuning law (module docstring) for the link layout of ``nominal`` (the ARX form: any plant's,
    :func:`~designkit.families.self_tuning.arx_law.arx_law`)."""
    if st.form == "arx":
        return arx_law(KIND, nominal, st)
    n = st.n
    names = memory_names(st)
    ctrl = controller_names(st.design)
    memo: dict[int, dict[str, ca.SX]] = {}

    def parts(s: LawSymbols) -> dict[str, ca.SX]:
        key = id(s)
        if key in memo:
            return memo[key]
        mem = s.memory
        k = mem("k")
        y, v, r = s.q[0], s.qd[0], s.qD[0]
        first = k < 0.5
        y1 = ca.if_else(first, y, mem("y1"))
        y2 = ca.if_else(first, y, mem("y2"))
        v1 = ca.if_else(first, v, mem("v1"))
        r1 = ca.if_else(first, r, mem("r1"))
        u1, u2 = mem("u1"), mem("u2")
        theta = ca.vertcat(*[mem(f"th{i + 1}") for i in range(n)])
        P = ca.reshape(ca.vertcat(*[mem(f"P{i + 1}{j + 1}") for i in range(n) for j in range(n)]), n, n).T
        if st.form == "speed":
            phi, out = ca.vertcat(v1, u1), v
        else:
            phi, out = ca.vertcat(y1 - y2, u1, u2), y - y1
        est = rls_step(st, theta, P, phi, out, ca.logic_not(first) if st.estimate else ca.SX(0))
        old = [mem(c) for c in ctrl]
        coefs, held = _design(st, est["theta"], old)
        if st.design == "pole_placement":
            R1, S0, S1, T0 = coefs
            zo = float(ca.exp(st.observer * st.Ts))
            u = -R1 * u1 + T0 * (r - zo * r1) - S0 * y - S1 * y1
            ctrl_next = [R1, S0, S1, T0]
        else:
            K1, K2, K3 = coefs
            speed = v if st.form == "speed" else (y - y1) / st.Ts
            integral = mem("I") + st.Ts * (y - r)
            u = -K1 * (y - r) - K2 * speed - K3 * integral
            ctrl_next = [K1, K2, K3, integral]
        Pn = est["P"]
        values = {
            **{f"th{i + 1}": est["theta"][i] for i in range(n)},
            **{f"P{i + 1}{j + 1}": Pn[i, j] for i in range(n) for j in range(n)},
            **{f"phi{i + 1}": phi[i] for i in range(n)}, "eps": est["eps"],
            "y1": y, "y2": y1, "v1": v, "u1": u, "u2": u1, "r1": r, "k": k + 1,
            **dict(zip(ctrl, ctrl_next, strict=True)), "u": u, "held": held, "bounded": est["bounded"],
        }
        memo[key] = values
        return values

    def entry(name: str):
        return lambda s: parts(s)[name]

    initial = {name: 0.0 for name in names}
    initial.update({f"th{i + 1}": float(st.theta0[i]) for i in range(n)})
    initial.update({f"P{i + 1}{i + 1}": float(st.P0) for i in range(n)})
    initial.update(dict(zip(ctrl, initial_controller(st), strict=True)))
    units = {"y1": "rad", "y2": "rad", "v1": "rad/s", "u1": "N*m", "u2": "N*m", "r1": "rad", "u": "N*m"}
    memory = [Memory(name, entry(name), initial[name], units.get(name, "")) for name in names]
    recorded = (*(f"th{i + 1}" for i in range(n)), *(f"phi{i + 1}" for i in range(n)), "eps", *ctrl, "held",
                "bounded", "k", *(f"P{i + 1}{i + 1}" for i in range(n)))
    return dynamic_law(
        KIND, nominal, memory=memory, command=lambda s: s.memory("u"),
        signals={name: (lambda nm: (lambda s: s.memory(nm)))(name) for name in recorded},
        settings={"estimator": "speed measured" if st.form == "speed" else "position differences",
                  "sampling_period": st.Ts, "forgetting": st.forgetting, "initial_covariance": st.P0,
                  "initial_estimates": list(st.theta0), "max_trace": st.max_trace, "safeguards": st.safeguards,
                  "design": "pole placement" if st.design == "pole_placement" else "PID",
                  "requested_poles": ", ".join(_pole_words(p) for p in st.poles if complex(p).imag >= 0) + " 1/s",
                  "observer": st.observer, "estimating": st.estimate},
        sampling_period=st.Ts, sampling_period_source="controller.sampling_period",
    )
