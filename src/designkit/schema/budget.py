"""The work a spec asks for, estimated before any model is built, and the budget it must fit.

Every number of a spec has a range, but a spec inside every range can still ask for hours: 10^5
uncertainty samples on the PUMA 560 (each a full simulation), a dozen uncertain parameters (2^12
corners re-simulated), a 64-joint chain (its symbolic model alone), a kHz sine (a microsecond step),
CVODES at ``rtol = 1e-14``.  :func:`estimate` counts the work from the spec alone, in one unit, the
**evaluation** (one evaluation of a one-joint model's right-hand side; an ``n``-joint model's costs
:func:`size` of them), and converts it to seconds with :data:`SECONDS_PER_EVALUATION`, calibrated once
on the development machine (two shared cores, under load; ``docs/budget.md`` has the table of estimate
against measured time).  :func:`check_budget` refuses a spec whose estimate exceeds the budget
(:data:`DEFAULT_BUDGET`, or ``--budget SECONDS`` / ``run(..., budget=)``), naming the field that drives
the cost, in well under a second.

The terms (each a :class:`Term` with the key path that drives it):

* **model build** -- a robot's symbolic model and the law's functions: :data:`BUILD` ``n^3.5``
  evaluations (measured in CPU time on DH chains of 1 to 24 joints: 0.23 s at 6, 4.3 s at 16, 20 s at 24);
* **simulations** -- ``runs x steps x evaluations per step x size(n)``.  Steps: ``duration / dt``,
  with ``simulation.dt`` when given, else the simulator's default rule (``min(0.02 / rate,
  duration / 200)``) with the rate the spec shows: the controller's poles, ``natural_frequency`` or
  ``bandwidth``, the reference's own (``2 pi f`` for a sine, ``2 pi / T`` for a move of duration ``T``,
  ``2 pi / gap`` for via points); the default duration is the reference's horizon plus ten time
  constants of the slowest requested decay.  At most :data:`MAX_STEPS` (beyond it the simulator refuses the
  run itself, naming the field).  Evaluations per step: 4 for RK4; for CVODES :data:`CVODES_STEP`
  ``x (1e-8 / rtol)^(1/6)`` (a BDF of order 5 shrinks its step as the tolerance's sixth root); for any
  other (adaptive) integrator, conservatively :data:`ADAPTIVE_STEP` (seven stages, rejected steps).
  Runs: the nominal run, the small-signal run of ``designed_loop``, the trials of a learning law, the
  corners (``2^k`` for ``k`` uncertain parameters) and samples of ``tracking_bounds``, the family's whole run
  (trials included) at up to 16 corners and 16 samples for a family offering ``box_runs``, and the corners the
  arm's answers re-simulate (the studies of ``synth`` are bounded by their own budget, ``studies.budget``,
  :mod:`designkit.studies`, and not counted here);
* **task path** -- a line or circle of the end effector is solved by inverse kinematics at 401 instants
  (:data:`IK_EVALUATIONS` each);
* **lattice** -- the robustness checks linearize the loop at every plant of the uncertainty lattice
  (``grid^k`` capped at 100,000, plus the samples, plus at most 2,000 added by its refinement):
  :data:`LINEARIZATION` ``x size(n)`` each; and the common Lyapunov matrix of a linear family is one LMI per corner
  of the box: :data:`LMI_VERTEX` ``x 2^k x (3n)^3``.

Which field is named: the largest term's driver.  For the simulations, the factor that is furthest
above an ordinary run: the samples or the corners when the runs dominate, else what sets the step count
(``simulation.dt``, ``simulation.duration``, the reference's frequency, duration or times, the controller's
poles) or ``numerics.rtol``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from designkit.errors import SpecError

__all__ = [
    "DEFAULT_BUDGET", "SECONDS_PER_EVALUATION", "Estimate", "Term", "check_budget", "check_comparison_budget",
    "estimate", "size",
]

DEFAULT_BUDGET = 60.0
"""Estimated seconds a spec may ask for by default (``--budget SECONDS`` raises it)."""
SECONDS_PER_EVALUATION = 1.25e-7
"""CPU seconds per evaluation (one right-hand side of a one-joint model), calibrated on the development machine:
RK4 steps of 0.8 µs on one link, 4-6 µs on the PUMA 560 (compiled), 27 µs on a 12-joint chain."""
BUILD = 2400.0
"""Evaluations per ``n^3.5`` of building a robot model and its law (3e-4 s n^3.5)."""
MAX_STEPS = 2_000_000
"""The simulator's own bound on a run's steps (:mod:`designkit.simulation.timing`)."""
DT_FACTOR, MIN_SAMPLES, POLE_HORIZON, SETTLE_FACTOR = 0.02, 200, 10.0, 3.0
"""The simulator's default-step and default-duration rule (:mod:`designkit.simulation.timing`)."""
CVODES_STEP = 50.0
"""Evaluations per CVODES output step at ``rtol = 1e-8`` (measured in CPU time: 35-60 µs per step on one link
against 1 µs per RK4 step; about 0.55 ms per step on the PUMA 560 at rtol 1e-14, against 4-6 µs per RK4 step)."""
ADAPTIVE_STEP = 14.0
"""Evaluations per output step of an adaptive explicit pair (seven stages, twice for rejected steps)."""
LINEARIZATION = 50.0
"""Evaluations per lattice plant of a robustness check (a Jacobian and the eigenvalues of the closed loop)."""
LMI_VERTEX = 136.0
"""Evaluations per corner and cubed closed-loop state of the common-Lyapunov LMI over the box's corners (measured:
15 s of CPU time for 512 corners of a SCARA's 12-state loop)."""
LATTICE_CAP = 100_000
"""Most lattice plants (:data:`designkit.spec.plants.MAX_GRID_POINTS`)."""
REFINED_CAP = 2000
"""Most plants the refinement of the lattice adds (:data:`designkit.verification.refine.MAX_REFINED_PLANTS`)."""
BOX_CORNERS, BOX_SAMPLES = 16, 16
"""Most corners and samples the ``box_runs`` check runs (:mod:`designkit.verification.checks.box_runs`)."""
PATH_SAMPLES, IK_EVALUATIONS = 401, 100.0
"""A task-space path is solved by inverse kinematics at 401 instants
(:data:`designkit.families.resolved_acceleration.PATH_SAMPLES`), a few Newton iterations with the Jacobian
each: about 100 evaluations per instant."""
OVERHEAD = 1.2e7
"""Evaluations of the fixed work of a run (imports, checks, certificates, the solver): about 1.5 s."""
STIFF_RATIO = 100.0
"""A pole faster than this times the lower median of the poles is stiff (:mod:`designkit.simulation.timing`)."""
ORDINARY_RATE, ORDINARY_DURATION = 10.0, 10.0
"""An ordinary loop's rate (1/s) and run (s): the step count's driver is the factor furthest above them."""
UNKNOWN_RATE, UNKNOWN_DECAY = 20.0, 1.0
"""The rate and slowest decay (1/s) assumed when the spec shows no pole (the family computes them)."""


@dataclass(frozen=True)
class Term:
    """One part of the work.

    Parameters
    ----------
    what : str
        Which work, in words.
    evaluations : float
        Its work (evaluations of a one-joint model's right-hand side).
    key : str
        The spec key path that drives it.
    words : str
        Why it costs what it does, one clause with numbers.
    """

    what: str
    evaluations: float
    key: str
    words: str

    @property
    def seconds(self) -> float:
        """Estimated time (s)."""
        return self.evaluations * SECONDS_PER_EVALUATION


@dataclass(frozen=True)
class Estimate:
    """The work a spec asks for.

    Parameters
    ----------
    joints : int or None
        Joints of the plant (None: not known before the model is built).
    terms : tuple of Term
        The parts, largest first.
    """

    joints: int | None
    terms: tuple[Term, ...]

    @property
    def evaluations(self) -> float:
        """Total work (evaluations)."""
        return sum(t.evaluations for t in self.terms)

    @property
    def seconds(self) -> float:
        """Estimated time (s)."""
        return self.evaluations * SECONDS_PER_EVALUATION

    @property
    def driver(self) -> Term:
        """The largest term."""
        return self.terms[0]

    def to_json(self) -> dict[str, Any]:
        """The estimate as JSON: seconds, evaluations, the terms."""
        return {"seconds": self.seconds, "evaluations": self.evaluations, "joints": self.joints,
                "terms": [{"what": t.what, "seconds": t.seconds, "key": t.key, "words": t.words} for t in self.terms]}


def size(n: int | None) -> float:
    """Evaluations one right-hand side of an ``n``-joint model costs (``1 + 0.2 n^2 + 0.02 n^3``, over 1.22 for
    one joint; fitted to RK4 steps of 1, 6, 12 and 24 joints)."""
    n = 1 if n is None else n
    return (1.0 + 0.2 * n * n + 0.02 * n ** 3) / 1.22


# ----------------------------------------------------------------------------- rates and steps


def _moduli(value: Any) -> list[float]:
    """|p| of every pole in a (nested) list of poles written as numbers or strings (``-1+2j``)."""
    out: list[float] = []
    for v in value if isinstance(value, list | tuple) else [value]:
        if isinstance(v, list | tuple):
            out += _moduli(v)
            continue
        try:
            out.append(abs(complex(str(v).replace(" ", "").replace("i", "j"))) if isinstance(v, str) else abs(v))
        except (TypeError, ValueError):
            continue
    return [x for x in out if math.isfinite(x) and x > 0]


def _decays(value: Any) -> list[float]:
    out: list[float] = []
    for v in value if isinstance(value, list | tuple) else [value]:
        if isinstance(v, list | tuple):
            out += _decays(v)
            continue
        try:
            p = complex(str(v).replace(" ", "").replace("i", "j")) if isinstance(v, str) else complex(v)
        except (TypeError, ValueError):
            continue
        if p.real < 0 and math.isfinite(p.real):
            out.append(-p.real)
    return out


def _listed(value: Any) -> list[float]:
    return [float(v) for v in (value if isinstance(value, list | tuple) else [value]) if v is not None]


def controller_rates(ctrl: Any) -> tuple[float, float, str] | None:
    """``(fastest |p|, slowest decay, key)`` the controller section shows (1/s), or None when it shows none."""
    poles = getattr(ctrl, "poles", None)
    if poles:
        moduli, decays = _moduli(poles), _decays(poles)
        if moduli:
            return max(moduli), min(decays) if decays else min(moduli), "controller.poles"
    wn = getattr(ctrl, "natural_frequency", None)
    if wn is not None:
        wns, zetas = _listed(wn), _listed(getattr(ctrl, "damping", None) or 1.0)
        fast = max(w * (z + math.sqrt(max(z * z - 1.0, 0.0))) for w in wns for z in zetas)
        slow = min(w * (z - math.sqrt(max(z * z - 1.0, 0.0))) if z >= 1 else w * z for w in wns for z in zetas)
        return fast, max(slow, 1e-12), "controller.natural_frequency"
    bandwidth = getattr(ctrl, "bandwidth", None)
    if bandwidth is not None:
        b = max(_listed(bandwidth))
        return b, b, "controller.bandwidth"
    return None


def reference_rate(traj: Any) -> tuple[float, float, str]:
    """``(rate 1/s, horizon s, key)`` of ``simulation.trajectory`` as the simulator's references set them."""
    if traj is None:
        return 0.0, 0.0, "simulation.step"
    kind = traj.kind
    key = f"simulation.trajectory.{'frequency' if kind == 'sine' else 'duration'}"
    if kind == "sine":
        f = float(traj.frequency)
        return 2 * math.pi * f, 3.0 / f, key
    if kind == "via_points":
        times = [float(t) for t in traj.times]
        gaps = [b - a for a, b in zip([0.0, *times], times, strict=False) if b > a]
        return 2 * math.pi / min(gaps) if gaps else 0.0, times[-1], "simulation.trajectory.times"
    if kind == "trapezoidal":
        v, a = max(_listed(traj.max_velocity)), min(_listed(traj.max_acceleration))
        amp = max(abs(x) for x in _listed(traj.amplitude))
        T = float(traj.duration) if traj.duration is not None else amp / v + v / a
        return 2 * math.pi / max(min(v / a, T / 2), 1e-12), T, "simulation.trajectory.max_acceleration"
    if kind == "square":
        return 0.0, 2 * float(traj.period), "simulation.trajectory.period"
    if kind == "multisine":  # the highest harmonic of joint n is n K; n is not known here: that of the amplitudes
        joints = len(traj.amplitude) if isinstance(traj.amplitude, list) else 1
        T = float(traj.period)
        return 2 * math.pi * joints * int(traj.harmonics) / T, 3 * T, "simulation.trajectory.harmonics"
    if kind == "prbs":
        return 0.0, (2 ** int(traj.order) - 1) * float(traj.bit), "simulation.trajectory.order"
    T = float(traj.duration)
    return 2 * math.pi / T, T, key


def _nice_floor(value: float) -> float:
    exp = math.floor(math.log10(value))
    for m in (5.0, 2.5, 2.0, 1.0):
        if m * 10**exp <= value * (1 + 1e-12):
            return m * 10**exp
    return 10 ** (exp - 1) * 5.0


@dataclass(frozen=True)
class Steps:
    """A run's step count and what sets it: ``count`` steps of ``dt`` s over ``duration`` s; ``key`` the field;
    ``integrator`` the one the simulator will take (CVODES when RK4 would exceed its bound on a stiff loop)."""

    count: float
    dt: float
    duration: float
    key: str
    integrator: str = "rk4"


def _delay(spec: Any) -> float:
    """The run's control delay (s): ``implementation.delay`` when positive, else ``simulation.delay``."""
    impl = getattr(spec, "implementation", None)
    return float(impl.delay) if impl is not None and impl.delay > 0 else float(spec.simulation.delay)


def _lag_rate(spec: Any) -> float:
    """The fastest actuator lag of ``implementation.actuator.bandwidth`` (rad/s), 0 without one."""
    actuator = getattr(getattr(spec, "implementation", None), "actuator", None)
    bw = getattr(actuator, "bandwidth", None)
    if bw is None:
        return 0.0
    return max(float(v) for v in bw) if isinstance(bw, list | tuple) else float(bw)


def steps_of(spec: Any) -> Steps:
    """The step count of the spec's nominal run (module docstring), at most :data:`MAX_STEPS`."""
    sim = spec.simulation
    ctrl = getattr(spec, "controller", None)
    shown = controller_rates(ctrl) if ctrl is not None else None
    fast, slow, ctrl_key = shown if shown is not None else (UNKNOWN_RATE, UNKNOWN_DECAY, "controller")
    ref_rate, horizon, ref_key = reference_rate(sim.trajectory)
    req = spec.requirements
    settle = (SETTLE_FACTOR * float(req.settling_time) if req is not None and req.settling_time is not None
              else POLE_HORIZON / slow)
    if sim.duration is not None:
        duration, duration_key = float(sim.duration), "simulation.duration"
    else:
        duration, duration_key = horizon + settle + _delay(spec), ctrl_key if settle > horizon else ref_key
    rate = max(fast, ref_rate)
    rate_key = ref_key if ref_rate > fast else ctrl_key
    lag = _lag_rate(spec)
    if lag > rate:  # the implemented actuator's lag is the fastest time scale the step resolves
        rate, rate_key = lag, "implementation.actuator.bandwidth"
    numerics = spec.numerics
    integrator = str(getattr(numerics, "integrator", "rk4"))
    moduli = sorted(_moduli(getattr(ctrl, "poles", None) or []))
    if (sim.dt is None and "integrator" not in numerics.model_fields_set and moduli
            and duration * rate / DT_FACTOR > MAX_STEPS):
        median = moduli[(len(moduli) - 1) // 2]
        calm = max(m for m in moduli if m <= STIFF_RATIO * median)
        if calm < fast:  # stiff poles: the simulator takes CVODES, whose output step follows the others
            integrator, rate = "cvodes", max(calm, ref_rate)
    if sim.dt is not None:
        dt, key = float(sim.dt), "simulation.dt"
    else:
        dt = _nice_floor(min(DT_FACTOR / rate, duration / MIN_SAMPLES))
        # the factor furthest above an ordinary run (a rate of 10 1/s over 10 s) is named
        key = rate_key if rate / ORDINARY_RATE >= duration / ORDINARY_DURATION else duration_key
    count = min(duration / dt, float(MAX_STEPS))
    return Steps(count, dt, duration, key, integrator)


# ----------------------------------------------------------------------------- runs and the estimate


def _step_evaluations(spec: Any, integrator: str) -> tuple[float, str, str]:
    """Evaluations per step of ``integrator`` (:attr:`Steps.integrator`), the key that sets them and a word."""
    numerics = spec.numerics
    if integrator == "rk4":
        return 4.0, "numerics.integrator", "RK4"
    if integrator == "cvodes":
        rtol = float(getattr(numerics, "rtol", 1e-8))
        return CVODES_STEP * max(1.0, (1e-8 / rtol) ** (1.0 / 6.0)), "numerics.rtol", f"CVODES at rtol {rtol:g}"
    return ADAPTIVE_STEP, "numerics.integrator", f"the adaptive {integrator}"


def _uncertainty(spec: Any) -> tuple[int, int, int]:
    """``(parameters, samples, lattice plants)`` of ``plant.uncertainty`` (zeros without one)."""
    unc = getattr(spec.plant, "uncertainty", None)
    if unc is None:
        return 0, 0, 0
    k = len(unc.intervals)
    per_axis = max(2, min(int(unc.grid), int(math.floor(LATTICE_CAP ** (1.0 / max(k, 1)) + 1e-9))))
    return k, int(unc.samples), per_axis ** k


def _runs(spec: Any, family: Any) -> tuple[float, str, str]:
    """Full-length runs of the spec (module docstring), the key that drives their number and how they add up."""
    k, samples, _ = _uncertainty(spec)
    ctrl = getattr(spec, "controller", None)
    trials = int(getattr(ctrl, "trials", 1) or 1) if ctrl is not None and hasattr(ctrl, "learning") else 1
    checks = tuple(getattr(family, "checks", ()) or ())
    corners = 2 ** k if k else 0
    box_runs = corners + samples if "tracking_bounds" in checks else min(corners, 16)
    own = 0
    if corners and "box_runs" in checks:  # the family's whole run (its trials too) at each point of the box
        own = (min(corners, BOX_CORNERS) + min(samples, BOX_SAMPLES)) * (trials + 1)
    runs = float(trials + 1 + box_runs + own)
    parts = [f"{trials} trial{'s' if trials > 1 else ''}" if trials > 1 else "the nominal run",
             "the small-signal run"]
    if box_runs:
        parts.append(f"{corners} corners of {k} uncertain parameter{'s' if k > 1 else ''}"
                     + (f" and {samples} samples" if samples and "tracking_bounds" in checks else ""))
    if own:
        parts.append(f"the family's own run repeated at {min(corners, BOX_CORNERS) + min(samples, BOX_SAMPLES)} "
                     "plants of the box (box_runs)")
    if samples and "tracking_bounds" in checks and samples >= corners:
        key = "plant.uncertainty.samples"
    elif corners > 8:
        key = "plant.uncertainty"
    elif trials > 2:
        key = "controller.trials"
    else:
        key = ""
    return runs, key, ", ".join(parts)


def _family(spec: Any) -> Any:
    from designkit.families import FAMILIES

    ctrl = getattr(spec, "controller", None)
    return FAMILIES.get(getattr(ctrl, "kind", None)) if ctrl is not None else None


def estimate(spec: Any, base_dir: Path | None = None, *, joints: int | None = None) -> Estimate:
    """The work ``spec`` (a single-controller :class:`~designkit.schema.spec.Spec`) asks for (module docstring).

    Parameters
    ----------
    spec : Spec
        The validated spec.
    base_dir : Path, optional
        Folder a relative URDF path is resolved against.
    joints : int, optional
        The plant's joints when already known (else read cheaply: :func:`~designkit.schema.joint_count.joint_count`).
    """
    from designkit.schema.joint_count import joint_count

    n = joint_count(spec.plant, base_dir) if joints is None else joints
    robot = getattr(spec.plant, "kind", None) == "robot"
    source = next((f"plant.{k}" for k in ("dh", "urdf", "robot") if robot and getattr(spec.plant, k) is not None),
                  "plant")
    terms = [Term("fixed work", OVERHEAD, "budget", "imports, checks and certificates, which any run needs")]
    if robot and n is not None:
        terms.append(Term("model build", BUILD * n ** 3.5, source,
                          f"a {n}-joint model takes about {BUILD * n ** 3.5 * SECONDS_PER_EVALUATION:.2g} s to build "
                          "(growing as n^3.5)"))
    steps = steps_of(spec)
    per_step, step_key, integrator = _step_evaluations(spec, steps.integrator)
    runs, runs_key, runs_words = _runs(spec, _family(spec))
    per_run = steps.count * per_step * size(n)
    sim_key = runs_key if runs_key and runs > 8 else (step_key if per_step > 4 * 10 and step_key == "numerics.rtol"
                                                      else steps.key)
    terms.append(Term("simulations", runs * per_run, sim_key,
                      f"{runs:.0f} runs ({runs_words}) of {steps.count:.3g} steps of {steps.dt:.3g} s over "
                      f"{steps.duration:.4g} s with {integrator}, {runs * steps.count * per_step:.2g} model evaluations"
                      + (f" of the {n}-joint model" if n and n > 1 else "")))
    traj = spec.simulation.trajectory
    if traj is not None and traj.kind in ("line", "circle"):
        terms.append(Term("task path", PATH_SAMPLES * IK_EVALUATIONS * size(n), "simulation.trajectory",
                          f"the joint path solved by inverse kinematics at {PATH_SAMPLES} instants"))
    k, samples, lattice = _uncertainty(spec)
    if lattice:
        plants = min(lattice, LATTICE_CAP) + samples + REFINED_CAP
        terms.append(Term("lattice", plants * LINEARIZATION * size(n),
                          "plant.uncertainty.samples" if samples > lattice else "plant.uncertainty.grid",
                          f"{plants:,} plants of the uncertainty lattice linearized and checked (at most "
                          f"{REFINED_CAP:,} of them added by the refinement)"))
        family = _family(spec)
        if "robustness" in tuple(getattr(family, "checks", ()) or ()):
            states = 3 * (n or 1)
            terms.append(Term("common Lyapunov LMI", 2**k * states**3 * LMI_VERTEX, "plant.uncertainty",
                              f"one Lyapunov matrix for the {2**k} corners of {k} uncertain parameter"
                              f"{'s' if k > 1 else ''} (an LMI of {states} states at each corner)"))
    return Estimate(n, tuple(sorted(terms, key=lambda t: -t.evaluations)))


def check_budget(spec: Any, base_dir: Path | None = None, budget: float | None = None) -> Estimate:
    """:func:`estimate`, refused beyond ``budget`` seconds (default :data:`DEFAULT_BUDGET`).

    Also refuses, before any model is built, a per-joint list whose length is not the plant's joint count
    (:func:`~designkit.schema.joint_count.check_joint_lists`).

    Raises
    ------
    SpecError
        Naming the field that drives the cost: ``<key>: the run needs ~E model evaluations (~S s), over the
        budget of B s (<why>); raise it with --budget X``; or a per-joint list of the wrong length; or a
        ``budget`` that is not a positive number of seconds (at ``budget``).
    """
    from designkit.schema.joint_count import check_joint_lists, joint_count

    if budget is None:
        budget = DEFAULT_BUDGET
    if isinstance(budget, bool) or not isinstance(budget, int | float) or not math.isfinite(budget) or budget <= 0:
        raise SpecError("budget", f"must be a positive number of seconds, got {budget!r}"[:120])
    n = joint_count(spec.plant, base_dir)
    if n is not None:
        check_joint_lists(spec, n)
    est = estimate(spec, base_dir, joints=n)
    if est.seconds > budget:
        top = est.driver
        key = top.key or "simulation"
        raise SpecError(key, f"the run needs ~{est.evaluations:.2g} model evaluations (~{est.seconds:.3g} s), over the "
                        f"budget of {budget:g} s: {top.what}, {top.words}; raise it with --budget "
                        f"{_round_up(est.seconds * 1.2)} (or budget= in Python)")
    return est


def _round_up(seconds: float) -> str:
    """A round number of seconds at least ``seconds``."""
    exp = 10 ** max(0, math.floor(math.log10(max(seconds, 1.0))) - 1)
    return f"{math.ceil(seconds / exp) * exp:g}"


def check_comparison_budget(specs: list[Any], base_dir: Path | None = None,
                            budget: float | None = None) -> list[float | None]:
    """The budget of a comparison: its members' estimates together (each member is run in turn).

    Returns the budget each member's own :func:`check_budget` is given (the comparison's).

    Raises
    ------
    SpecError
        As :func:`check_budget`, naming the member's field (``controllers[<i>].<key>`` for a controller's)
        whose member costs the most, when the sum exceeds the budget.
    """
    limit = DEFAULT_BUDGET if budget is None else budget
    check_budget(specs[0], base_dir, limit)  # the budget argument itself, and the first member alone
    estimates = [estimate(spec, base_dir) for spec in specs]
    total = sum(e.seconds for e in estimates)
    if total > limit:
        k = max(range(len(estimates)), key=lambda i: estimates[i].seconds)
        top = estimates[k].driver
        key = top.key or "simulation"
        if key == "controller" or key.startswith("controller."):
            key = f"controllers[{k}]{key[len('controller'):]}"
        raise SpecError(key, f"the {len(specs)} controllers need ~{sum(e.evaluations for e in estimates):.2g} model "
                        f"evaluations (~{total:.3g} s), over the budget of {limit:g} s; the costliest, "
                        f"controllers[{k}]: {top.what}, {top.words}; raise it with --budget {_round_up(total * 1.2)} "
                        "(or budget= in Python)")
    return [budget] * len(specs)
