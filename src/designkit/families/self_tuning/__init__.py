"""Self-tuning regulator of one link (notes section 4.3, the SELFTUNE simulator, figures 4.1 and 4.2) or of any SISO
linear plant (Astrom and Wittenmark, *Adaptive Control*, 2nd ed., chapter 3, the indirect self-tuner): ``self_tuning``.

Plant: the link ``x1' = x2``, ``x2' = -x2/tau + (Km/tau)(u + xi)``, or a ``transfer_function`` or single-input
``state_space`` plant (the ARX form, ``estimator: arx``, :mod:`designkit.families.self_tuning.arx`: orders ``na``,
``nb``, delay ``d``; pole placement with a given observer polynomial, the zeros kept or cancelled).  Controller: a
sampled law
(period ``controller.sampling_period``) that at each sample

1. estimates the parameters of the exactly (zero-order-hold) discretized link by recursive least
   squares with forgetting factor ``lambda``, in either form of the appendix -- speed measured
   (``theta = [A22, B2]``) or not (position differences, ``theta = [A22, B1, B2 A12 - B1 A22]``)
   (:mod:`designkit.families.self_tuning.model`);
2. redesigns the controller for the estimated model (certainty equivalence): pole placement by the
   Diophantine equation ``A R + B S = Am Ao`` (``design: pole_placement``), or the one-link PID
   placing three continuous poles on the estimated ``Km``, ``tau`` (``design: pid``);
3. computes the command, held until the next sample.

It is one :func:`~designkit.synthesis.law.dynamic_law` with discrete memory
(:mod:`designkit.families.self_tuning.laws`) that declares its sampling period, so the simulation
samples it there.

**Contract.**  ``Linearization("none")``: the law is a difference equation in its memory (past inputs
and outputs, estimates, covariance); the generic linear checks linearize continuous-time laws in
``(y, xc)`` and would see a constant command.  The loop that *is* linear -- the estimated discrete
model under the controller designed for it -- is checked by the family's own rules
(:mod:`designkit.families.self_tuning.checks`) on the discrete closed loop, sample by sample.
"""

from __future__ import annotations

from typing import Any, Literal

from pydantic import Field, field_validator, model_validator

from designkit.families.self_tuning.arx import Orders, causality, desired, parameter_names, place, true_arx
from designkit.families.self_tuning.data import SelfTuningData
from designkit.families.self_tuning.laws import KIND, Settings, self_tuning_law
from designkit.families.self_tuning.model import PARAMETER_NAMES, PARAMETER_UNITS, theta_of
from designkit.spec.fields import Pole, PositiveFinite, Section, check_conjugates
from designkit.spec.ranges import Ranged, check_poles
from designkit.synthesis.closed_loop import with_law
from designkit.synthesis.design import Design, Gain, Gains
from designkit.synthesis.family import Display, Family
from designkit.synthesis.knobs import Knob
from designkit.synthesis.linearization import Linearization

__all__ = ["FAMILY", "SelfTuningSpec", "law", "synthesize"]

REASON = ("the self-tuning regulator is a sampled difference equation in its memory (estimates, covariance, past "
          "inputs and outputs): a continuous-time linearization in (y, xc) does not describe it; its discrete "
          "closed loop is checked sample by sample by the family's own checks")
MIN_WINDOW_SAMPLES = 10
"""The excitation window spans at least this many samples."""
DEFAULT_WINDOW = 2.0
"""The default excitation window (s), widened to :data:`DEFAULT_WINDOW_SAMPLES` samples at long sampling periods."""
DEFAULT_WINDOW_SAMPLES = 20
"""The default excitation window spans at least this many samples."""
MAX_DEFAULT_ORDER = 8
"""The largest plant order whose ARX orders default to the plant's (``na``, ``nb`` are at most 8)."""
LINK_FORMS = ("speed", "position")
"""The estimator forms of the link only."""


def default_window(Ts: float) -> float:
    """The default excitation window (s) at the sampling period ``Ts`` (s): 2 s or 20 samples, the longer."""
    return max(DEFAULT_WINDOW, DEFAULT_WINDOW_SAMPLES * Ts)


class NominalLink(Section):
    """The link the initial estimates are the exact ZOH parameters of: ``Km`` ((rad/s)/(N*m)) and ``tau`` (s),
    1e-6 to 1e6 each; a missing one is the spec's plant's."""

    Km: Ranged(1e-6, 1e6, "(rad/s)/(N*m)", base=PositiveFinite) | None = None
    tau: Ranged(1e-6, 1e6, "s", base=PositiveFinite) | None = None


class ArxOrders(Section):
    """Orders of the ARX model: ``na`` past outputs (1 to 8), ``nb`` input coefficients (1 to 8), delay ``d``
    (samples, 1 to 8)."""

    na: int = Field(ge=1, le=8)
    nb: int = Field(ge=1, le=8)
    d: int = Field(default=1, ge=1, le=8)


class Observer(Section):
    """The observer polynomial ``Ao(z)`` of the ARX form: ``poles`` (continuous, 1/s, mapped by ``z = exp(p h)``) or
    ``polynomial`` (coefficients in ``z``, highest power first, monic: ``[1, 0]`` is the deadbeat ``Ao = z``,
    ``[1]`` no observer; its roots inside the unit circle, checked at the design)."""

    poles: list[Pole] | None = None
    polynomial: list[Ranged(-1e6, 1e6, "", base=float)] | None = Field(default=None, min_length=1, max_length=16)

    @model_validator(mode="after")
    def _one(self) -> Observer:
        if (self.poles is None) == (self.polynomial is None):
            raise ValueError("observer: give either poles (1/s) or polynomial (coefficients in z)")
        if self.poles is not None:
            check_conjugates(self.poles)
        return self


class SelfTuningSpec(Section):
    """Self-tuning regulator (RLS with forgetting and a certainty-equivalence design, notes section 4.3).

    ``sampling_period`` (s, required): the period the regulator is designed and run at.  ``estimator``:
    ``speed`` (speed measured, fig. 4.1) or ``position`` (position differences, fig. 4.2).
    ``forgetting``: ``lambda`` in (0, 1].  ``initial_covariance``: ``P(0) = p I``, > 0.  ``max_trace``: the
    covariance bound (default ``n p``, the initial trace).  ``safeguards``: the covariance bound and the
    controller hold (default true).  ``design``: ``pole_placement`` (``poles``: two, 1/s, plus ``observer``,
    1/s, default twice the fastest pole's modulus) or ``pid`` (``poles``: three).  ``nominal``: the link the
    initial estimates come from (default the spec's plant).  ``excitation_window`` (s): the window of the
    excitation indicator (default 2 s or 20 samples, the longer).

    ARX form (``estimator: arx``, the default on a ``transfer_function`` or ``state_space`` plant): ``orders``
    (``na``, ``nb``, ``d``; default the plant's order ``N``: ``na = nb = N``, ``d = 1``), ``observer`` a number (one
    pole, 1/s), ``{poles}`` or ``{polynomial}`` (default: the fewest poles the design needs, each at twice the
    fastest pole's modulus), ``zeros`` (``keep`` or ``cancel``), ``initial_estimates`` (``a1 .. a_na, b0 ..
    b_(nb-1)``; default the spec's plant's exact ARX parameters).
    """

    kind: Literal[KIND]
    sampling_period: Ranged(1e-5, 10.0, "s", base=PositiveFinite) = Field(
        description="Sampling period of the regulator (s).")
    estimator: Literal["speed", "position", "arx"] | None = None
    forgetting: Ranged(0.0, 1.0, "", low_open=True) = 0.99
    initial_covariance: Ranged(0.0, 1e12, "", low_open=True) = 1000.0
    max_trace: Ranged(0.0, 1e15, "", low_open=True) | None = None
    safeguards: bool = True
    design: Literal["pole_placement", "pid"] = "pole_placement"
    poles: list[Pole] = Field(description="Requested continuous closed-loop poles (1/s).")
    observer: Ranged(-1e6, 0.0, "1/s", high_open=True) | Observer | None = None
    nominal: NominalLink | None = None
    excitation_window: Ranged(1e-4, 1e6, "s", base=PositiveFinite) | None = None
    orders: ArxOrders | None = None
    zeros: Literal["keep", "cancel"] = "keep"
    initial_estimates: list[Ranged(-1e6, 1e6, "", base=float)] | None = Field(default=None, max_length=16)

    @property
    def window(self) -> float:
        """The excitation window (s): the given one or :func:`default_window`."""
        return float(self.excitation_window) if self.excitation_window is not None else \
            default_window(float(self.sampling_period))

    @field_validator("observer", mode="before")
    @classmethod
    def _observer(cls, v: Any) -> Any:
        """A mapping is an :class:`Observer`; its errors name their key under ``observer``."""
        if not isinstance(v, dict):
            return v
        from pydantic import ValidationError

        try:
            return Observer.model_validate(v)
        except ValidationError as exc:
            err = exc.errors(include_url=False)[0]
            where = "".join(f"[{p}]" if isinstance(p, int) else (("." if i else "") + str(p))
                            for i, p in enumerate(err.get("loc", ())))
            msg = str(err.get("msg", "invalid value")).removeprefix("Value error, ")
            if err.get("type") == "extra_forbidden":
                msg = "unknown key"
            value = err.get("input")
            if isinstance(value, int | float | str | bool) and "got" not in msg and err.get("type") != "missing":
                msg = f"{msg}, got {value!r}"
            raise ValueError(f"{where}: {msg}" if where else msg) from None

    @field_validator("poles")
    @classmethod
    def _poles(cls, v: list[complex]) -> list[complex]:
        check_poles(v)
        check_conjugates(v)
        return v

    @model_validator(mode="after")
    def _shape(self) -> SelfTuningSpec:
        if self.excitation_window is not None and self.excitation_window < MIN_WINDOW_SAMPLES * self.sampling_period:
            raise ValueError(f"excitation_window: {self.excitation_window:g} s spans fewer than {MIN_WINDOW_SAMPLES} "
                             f"samples of {self.sampling_period:g} s")
        return self


def validate(spec: Any) -> None:
    """Cross-section rules: no anti-windup; the run must be long enough for the excitation window."""
    c, sim = spec.controller, spec.simulation
    if sim.anti_windup is not None:
        raise ValueError("simulation.anti_windup: the self-tuning regulator has no continuous integral to limit")
    if sim.duration is not None and c.window > sim.duration:
        raise ValueError(f"controller.excitation_window: {c.window:g} s is longer than "
                         f"simulation.duration = {sim.duration:g} s: the run is too short for the excitation window")
    traj = sim.trajectory
    if sim.duration is not None and traj is not None and getattr(traj, "period", None) is not None \
            and sim.duration < 2 * float(traj.period):
        raise ValueError(f"simulation.duration: {sim.duration:g} s covers fewer than two periods of the "
                         f"{traj.kind} reference ({float(traj.period):g} s): too short to excite the estimator")
    if sim.plant_change is not None and sim.duration is not None \
            and sim.plant_change.time + c.window > sim.duration:
        raise ValueError(f"simulation.plant_change.time: {sim.plant_change.time:g} s leaves less than "
                         f"controller.excitation_window = {c.window:g} s of the run after the change")
    _validate_form(spec)


def form_of(spec: Any) -> str:
    """The estimator form: the given one, else ``speed`` on the link and ``arx`` on any other plant."""
    c = spec.controller
    if c.estimator is not None:
        return c.estimator
    return "speed" if spec.plant.kind == "link" else "arx"


def plant_order(spec: Any) -> int:
    """The continuous plant's order read from its spec section."""
    p = spec.plant
    if p.kind == "link":
        return 2
    if p.kind == "transfer_function":
        return len(p.den) - 1
    return len(p.A)


def orders_of(spec: Any) -> Orders:
    """The ARX orders: the given ones, else ``na = nb = N`` (the plant's order) and ``d = 1``."""
    o = spec.controller.orders
    if o is not None:
        return Orders(o.na, o.nb, o.d)
    N = plant_order(spec)
    return Orders(N, N, 1)


def observer_degree(spec: Any) -> int:
    """Degree of the observer polynomial the spec asks for (given, or the fewest the design needs)."""
    c = spec.controller
    ob = c.observer
    if ob is None:
        o = orders_of(spec)
        m = len(c.poles)
        need = (o.n + o.d - 1 - m) if c.zeros == "cancel" else (2 * o.n - 1 - m)
        return max(0, need)
    if isinstance(ob, Observer):
        return len(ob.poles) if ob.poles is not None else len(ob.polynomial) - 1
    return 1


def _validate_link_form(c: Any) -> None:
    for key in ("orders", "initial_estimates"):
        if getattr(c, key) is not None:
            raise ValueError(f"controller.{key}: only the ARX form (estimator: arx) reads it")
    if c.zeros != "keep":
        raise ValueError("controller.zeros: only the ARX form (estimator: arx) cancels zeros")
    if isinstance(c.observer, Observer):
        raise ValueError("controller.observer: the link's forms take one observer pole (a number, 1/s); poles or a "
                         "polynomial are the ARX form's (estimator: arx)")
    need = 2 if c.design == "pole_placement" else 3
    if len(c.poles) != need:
        why = ("the pole-placement loop is A R + B S = Am Ao with Am of degree 2 (and the observer pole)"
               if need == 2 else "the PID loop on the link is third order")
        raise ValueError(f"controller.poles: must list exactly {need} poles for design {c.design}, got "
                         f"{len(c.poles)}: {why}")
    if c.design == "pid" and c.observer is not None:
        raise ValueError("controller.observer: only the pole-placement design has an observer pole")


def _validate_form(spec: Any) -> None:
    c = spec.controller
    form = form_of(spec)
    kind = spec.plant.kind
    if form in LINK_FORMS:
        if kind != "link":
            raise ValueError(f"controller.estimator: the {form} form is the link's; a {kind} plant is estimated by the "
                             "ARX form (estimator: arx)")
        _validate_link_form(c)
        return
    if c.design != "pole_placement":
        raise ValueError("controller.design: the ARX form designs by pole placement only (the PID is the link's)")
    if c.nominal is not None:
        raise ValueError("controller.nominal: the ARX form starts from controller.initial_estimates (nominal is the "
                         "link's forms')")
    if kind == "state_space" and len(spec.plant.B[0]) != 1:
        raise ValueError(f"plant.B: the ARX self-tuner drives one input; the plant has {len(spec.plant.B[0])}")
    if c.orders is None and plant_order(spec) > MAX_DEFAULT_ORDER:
        raise ValueError(f"controller.orders: the plant is of order {plant_order(spec)}; the default ARX orders "
                         f"(na = nb = the plant's order) go to {MAX_DEFAULT_ORDER}: give orders (na, nb at most 8)")
    o = orders_of(spec)
    deg_ao = observer_degree(spec)
    why = causality(o, len(c.poles), deg_ao, c.zeros == "cancel")
    if why is not None:
        raise ValueError(f"controller.poles: {len(c.poles)} poles and an observer of degree {deg_ao} give no causal "
                         f"controller for n = {o.n}: {why}")
    if c.initial_estimates is not None and len(c.initial_estimates) != o.count:
        raise ValueError(f"controller.initial_estimates: the ARX model (na = {o.na}, nb = {o.nb}) has {o.count} "
                         f"parameters a1 .. a{o.na}, b0 .. b{o.nb - 1}, got {len(c.initial_estimates)}")


def _nominal(spec: Any, plant: Any) -> Any:
    nominal = spec.controller.nominal
    if nominal is None:
        return plant
    values = {k: v for k, v in (("Km", nominal.Km), ("tau", nominal.tau)) if v is not None}
    return plant.with_params(**values) if values else plant


def link_values(plant: Any) -> tuple[float, float]:
    """``(Km, tau)`` of a link plant."""
    return float(plant.parameter("Km").value), float(plant.parameter("tau").value)


def settings_of(spec: Any, plant: Any) -> Settings:
    """The law's :class:`~designkit.families.self_tuning.laws.Settings` from the spec."""
    c = spec.controller
    Ts = float(c.sampling_period)
    form = form_of(spec)
    P0 = float(c.initial_covariance)
    if form == "arx":
        return _arx_settings(spec, plant)
    Km, tau = link_values(_nominal(spec, plant))
    theta0 = theta_of(Km, tau, Ts, form)
    n = len(theta0)
    observer = (float(c.observer) if c.observer is not None else
                -2.0 * max(abs(complex(p)) for p in c.poles)) if c.design == "pole_placement" else 0.0
    return Settings(form=form, Ts=Ts, forgetting=float(c.forgetting), P0=P0, theta0=theta0,
                    max_trace=float(c.max_trace) if c.max_trace is not None else n * P0, safeguards=bool(c.safeguards),
                    design=c.design, poles=tuple(complex(p) for p in c.poles), observer=observer)


def observer_polynomial(spec: Any) -> tuple[float, ...]:
    """``Ao(z)`` of the ARX form (monic, highest power first)."""
    c = spec.controller
    Ts = float(c.sampling_period)
    ob = c.observer
    if isinstance(ob, Observer):
        if ob.polynomial is not None:
            return tuple(float(v) for v in ob.polynomial)
        return tuple(float(v) for v in desired(ob.poles, Ts))
    if ob is not None:
        return tuple(float(v) for v in desired([float(ob)], Ts))
    k = observer_degree(spec)
    fast = -2.0 * max(abs(complex(p)) for p in c.poles)
    return tuple(float(v) for v in desired([fast] * k, Ts))


def _check_observer(ao: tuple[float, ...]) -> None:
    """``Ao`` monic and stable (:class:`~designkit.errors.SpecError` at ``controller.observer.polynomial``)."""
    import numpy as np

    from designkit.errors import SpecError

    if ao[0] != 1.0:
        raise SpecError("controller.observer.polynomial", f"must be monic (leading coefficient 1), got {ao[0]:g}")
    roots = np.roots(ao) if len(ao) > 1 else np.array([])
    if roots.size and np.max(np.abs(roots)) >= 1.0:
        raise SpecError("controller.observer.polynomial", f"a root of modulus {np.max(np.abs(roots)):.4g} is not "
                        "inside the unit circle: the observer must be stable")


def _arx_settings(spec: Any, plant: Any) -> Settings:
    import numpy as np

    from designkit.errors import SpecError
    from designkit.families.self_tuning.arx_runs import plant_matrices

    c = spec.controller
    Ts = float(c.sampling_period)
    o = orders_of(spec)
    if c.initial_estimates is not None:
        theta0 = tuple(float(v) for v in c.initial_estimates)
    else:
        exact = true_arx(*plant_matrices(plant), Ts, o)
        if exact is None:
            raise SpecError("controller.initial_estimates", f"the ARX orders (na = {o.na}, nb = {o.nb}, d = {o.d}) do "
                            "not hold the spec's plant sampled at controller.sampling_period exactly, so there are no "
                            "exact parameters to start from: give the initial estimates")
        theta0 = tuple(float(v) for v in exact)
    am = tuple(float(v) for v in desired(c.poles, Ts))
    ao = observer_polynomial(spec)
    _check_observer(ao)
    cancel = c.zeros == "cancel"
    try:
        first = place(theta0, o, am, ao, cancel)
    except np.linalg.LinAlgError:
        first = None
    if first is None or not np.all(np.isfinite([*first.R, *first.S, *first.T])) or first.condition > 1e12:
        raise SpecError("controller.initial_estimates", "the initial model gives a singular Diophantine equation (A "
                        "and B share a root, or b0 = 0 with the zeros cancelled): no controller to start with")
    P0 = float(c.initial_covariance)
    return Settings(form="arx", Ts=Ts, forgetting=float(c.forgetting), P0=P0, theta0=theta0,
                    max_trace=float(c.max_trace) if c.max_trace is not None else o.count * P0,
                    safeguards=bool(c.safeguards), design="pole_placement", poles=tuple(complex(p) for p in c.poles),
                    orders=(o.na, o.nb, o.d), am=am, ao=ao, cancel=cancel)


def synthesize(spec: Any, plant: Any) -> Design:
    """The self-tuning regulator a spec asks for (module docstring)."""
    st = settings_of(spec, plant)
    nominal = _nominal(spec, plant)
    notes = []
    if st.form == "arx":
        nominal = plant
        if spec.controller.initial_estimates is None:
            notes.append("No initial estimates given: they are the exact ARX parameters of the spec's plant.")
    elif spec.controller.nominal is None:
        notes.append("No nominal link given: the initial estimates are the exact parameters of the spec's plant.")
    return design(nominal, st, excitation_window=spec.controller.window, notes=tuple(notes))


def design(nominal: Any, st: Settings, *, excitation_window: float = 2.0, notes: tuple[str, ...] = ()) -> Design:
    """The self-tuning design for ``st`` on the link layout of ``nominal``.

    Examples
    --------
    >>> from designkit.models.link import LinkPlant
    >>> from designkit.families.self_tuning.model import theta_of
    >>> st = Settings("speed", 0.01, 0.99, 100.0, theta_of(2.0, 0.5, 0.01, "speed"), 200.0, True,
    ...               "pole_placement", (-4.0, -5.0), -10.0)
    >>> d = design(LinkPlant(Km=2.0, tau=0.5), st)
    >>> d.linearization.kind, d.law.sampling_period, d.law.memory_names[:2]
    ('none', 0.01, ('th1', 'th2'))
    """
    from designkit.families.self_tuning.laws import initial_controller

    if st.form == "arx":
        return _arx_design(nominal, st, excitation_window, notes)
    Km, tau = link_values(nominal)
    names, units = PARAMETER_NAMES[st.form], PARAMETER_UNITS[st.form]
    coefs = initial_controller(st)
    gains = [Gain("Ts", st.Ts, "s", "sampling period"), Gain("λ", st.forgetting, "", "forgetting factor"),
             Gain("P(0)", st.P0, "", "initial covariance (times the identity)"),
             Gain("tr P max", st.max_trace, "", "covariance bound (trace)" + ("" if st.safeguards else ", off"))]
    if st.design == "pole_placement":
        gains += [Gain(n_, v, u, w) for n_, v, u, w in zip(
            ("R1", "S0", "S1", "T0"), coefs, ("", "N*m/rad", "N*m/rad", "N*m/rad"),
            ("R(z) = z + R1, at the initial estimates", "S(z) = S0 z + S1", "S(z) = S0 z + S1",
             "T(z) = T0 (z − zo)"), strict=True)]
    else:
        gains += [Gain("K1", coefs[0], "N*m/rad", "proportional, at the initial estimates"),
                  Gain("K2", coefs[1], "N*m*s/rad", "rate feedback, at the initial estimates"),
                  Gain("K3", coefs[2], "N*m/(rad*s)", "integral, at the initial estimates")]
    data = SelfTuningData(settings=st, parameters=tuple(names), units=tuple(units), nominal=(Km, tau),
                          excitation_window=excitation_window,
                          desired=tuple(st.desired()) if st.design == "pole_placement" else None)
    formulas = (
        "x(k+1) = A x(k) + B u(k),  A = e^(F Ts),  B = ∫₀^Ts e^(F s) ds b  (exact zero-order hold)",
        ("x2(k) = A22 x2(k−1) + B2 u(k−1)" if st.form == "speed" else
         "Δx1(k) = A22 Δx1(k−1) + B1 u(k−1) + (B2 A12 − B1 A22) u(k−2)"),
        "θ ← θ + P φ (y − φᵀθ)/(λ + φᵀPφ),  P ← (P − P φ φᵀ P/(λ + φᵀPφ))/λ",
        ("A R + B S = Am Ao  (Sylvester system, solved each sample)" if st.design == "pole_placement" else
         "K2 = (τ̂ c1 − 1)/K̂m,  K1 = τ̂ c2/K̂m,  K3 = τ̂ c3/K̂m  (each sample)"),
    )
    poles = tuple(complex(p) for p in st.poles) + ((complex(st.observer),) if st.design == "pole_placement" else ())
    d = Design(kind=KIND, plant=nominal, gains=Gains.of(gains), poles=poles, reference="step", formulas=formulas,
               notes=notes, data=data)
    return with_law(d, self_tuning_law(nominal, st), Linearization("none", reason=REASON))


def _arx_design(plant: Any, st: Settings, excitation_window: float, notes: tuple[str, ...]) -> Design:
    from designkit.families.self_tuning.arx_law import arx_controller_names
    from designkit.families.self_tuning.laws import initial_controller

    o = Orders(*st.orders)
    coefs = initial_controller(st)
    gains = [Gain("h", st.Ts, "s", "sampling period"), Gain("λ", st.forgetting, "", "forgetting factor"),
             Gain("P(0)", st.P0, "", "initial covariance (times the identity)"),
             Gain("tr P max", st.max_trace, "", "covariance bound (trace)" + ("" if st.safeguards else ", off"))]
    gains += [Gain(name, value, "", "R u = T r − S y at the initial estimates")
              for name, value in zip(arx_controller_names(st), coefs, strict=True)]
    nominal = link_values(plant) if plant.kind == "link" else ()
    data = SelfTuningData(settings=st, parameters=parameter_names(o), units=("",) * o.count, nominal=nominal,
                          excitation_window=excitation_window, desired=tuple(st.desired()))
    words = "cancelled: A R' + b0 S = Am Ao, R = R' B/b0" if st.cancel else "kept: A R + B S = Am Ao"
    formulas = (
        "x(k+1) = Φ x(k) + Γ u(k),  Φ = e^(F h),  Γ = ∫₀^h e^(F s) ds G  (exact zero-order hold)",
        f"y(k) = −a1 y(k−1) − … − a{o.na} y(k−{o.na}) + b0 u(k−{o.d}) + … + b{o.nb - 1} u(k−{o.d + o.nb - 1})",
        "θ ← θ + P φ (y − φᵀθ)/(λ + φᵀPφ),  P ← (P − P φ φᵀ P/(λ + φᵀPφ))/λ",
        f"zeros {words}  (Sylvester system, solved each sample);  T = t0 Ao",
    )
    d = Design(kind=KIND, plant=plant, gains=Gains.of(gains), poles=tuple(complex(p) for p in st.poles),
               reference="step", formulas=formulas, notes=notes, data=data)
    return with_law(d, self_tuning_law(plant, st), Linearization("none", reason=REASON))


def law(design: Design, anti_windup: Any = None) -> Any:
    """The self-tuning law of ``design`` (rebuilt from its :class:`Settings`)."""
    return self_tuning_law(design.plant, settings_from(design))


def settings_from(design: Design) -> Settings:
    """The :class:`Settings` the design's law is made of (its :class:`SelfTuningData`)."""
    return design.data.settings


def _family() -> Family:
    from designkit.families.self_tuning import answers, checks, figures, report

    return Family(
        kind=KIND, spec=SelfTuningSpec, plants=("link", "transfer_function", "state_space"), reference="step",
        synthesize=synthesize, law=law,
        uses=("plant.uncertainty", "plant.uncertainty.samples"),
        checks=("time_domain", "box_runs", *checks.RULES),
        display=Display(
            label="Self-tuning regulator (RLS and certainty-equivalence design)",
            law=("θ̂(k) = θ̂(k−1) + K(k) (y(k) − φ(k)ᵀ θ̂(k−1))  (recursive least squares, forgetting λ)",
                 "R̂(z) u = T̂(z) xD − Ŝ(z) x1,  Â R̂ + B̂ Ŝ = Am Ao  (pole placement on the estimated model)",
                 "or u = −K̂1 (x1 − xD) − K̂2 x2 − K̂3 Σ Ts (x1 − xD)  (PID on the estimated Km, τ)"),
            summary="Notes §4.3 and the SELFTUNE simulator, and Åström–Wittenmark's indirect self-tuner: a sampled "
                    "regulator that estimates the plant's discrete model by recursive least squares and redesigns "
                    "itself for the estimate at every sample."),
        validate=validate, references=("step", "square", "prbs"),
        figures=figures.FIGURES, sections=(report.section,), diagnoses=(checks.diagnose,), json=report.json,
        knobs=(Knob("forgetting", "", "forgetting factor λ of the least squares (1 − λ sets its memory)", 0.5, 1.0,
                    path="controller.forgetting", role="forgetting", boundary=True),
               Knob("poles", "1/s", "requested closed-loop poles of the certainty-equivalence design", 1e-3, 1e6,
                    path="controller.poles"),
               Knob("sampling_period", "s", "the regulator's sampling period", 1e-5, 10.0,
                    path="controller.sampling_period")),
        traits=("adaptive", "certainty_equivalence"),
        answers=answers.ANSWERS,
        variants=answers.VARIANTS,
    )


FAMILY = _family()
