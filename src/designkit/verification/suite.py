"""The check registry: what a check declares, the generic checks, and the runner.

A check is a :class:`CheckRule`: its name, where it stands in the report, what it needs from a
design (``applies``), whether it reads the design's linearization (``linear``), how it runs
(``run``), and what the report says and draws of it (``label``, ``labels``, ``glossary``,
``figures``, ``diagnose``).  The generic checks are one module each in
:mod:`designkit.verification.checks`, discovered like the controller families (every module there
defines ``RULE``); a family offers generic checks by name and brings rules of its own in
``Family.checks``.  Nothing here knows a family: the caller (the pipeline) hands :func:`run_checks`
the rules the design's family offers.

A check runs when it is offered *and* the design exposes what it needs: a ``linear`` check only
when the design's linearization contract gives a loop (``exact`` or ``frozen``,
:mod:`designkit.synthesis.linearization`), never on a switching law.  The solver or the simulation
never decides which checks exist.  Rules run in ``order``; the generic ones in report order:

================== ===== ======================================= ==============================================
check              order needs                                   what it proves
================== ===== ======================================= ==============================================
pole_placement     10    requested ``poles``, ``closed_loop``    closed-loop poles/zeros are the requested ones
routh_hurwitz      20    a closed-form ``characteristic``        Routh array + the notes' gain conditions
lyapunov           30    ``closed_loop``                         quadratic Lyapunov function (LMI, NumPy re-check)
frozen_final       35    a ``frozen`` contract and a run         the loop frozen at the run's final gains
loops              40    per-joint ``loops``                     the three above for each joint loop
robust_box         50    ``characteristic.linear_conditions``    stability on the whole (Km, tau) box (LP + duality)
                         and an uncertainty on its parameters
robustness         60    ``plant.uncertainty``                   corners, lattice, samples; common Lyapunov P
error_poles        80    a trajectory design with poles          error poles along the path (joint or task space)
singularity        90    a task-space design (``motion``)        conditioning of J along the path; DLS bound
tracking_bounds    100   a trajectory design + uncertainty       tracking error over the box by simulation
loop_margins       110   ``input_loop``                          gain/phase/modulus margins (informational)
coupling           120   per-joint ``loops``                     intercoupling left to the loops (informational)
designed_loop      125   a linear loop and a run                 the simulated loop is the designed one
time_domain        130   a simulation and ``requirements``       overshoot, settling, rise, error, peak control
torque_limits      140   a simulation and ``plant.limits``       commanded torques within the actuator limits
command_chatter    145   a run of a non-switching law            a command jumping back and forth, and why
command_switching  146   a run (every law)                       switching vs averaged control, reversal rate
                                                                 vs the step; ``max_reversal_rate``,
                                                                 ``max_command_variation``
generated_code     148   a run and a law (every law)             the law's generated C, compiled and called at
                                                                 every step, gives the Python law's loop
box_runs           150   a run and ``plant.uncertainty``         the family's own run at the box's corners and
                                                                 samples: every check passes at each
================== ===== ======================================= ==============================================
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from designkit.discovery import Registry
from designkit.verification.check import Check

__all__ = ["CheckRule", "Context", "GENERIC", "applicable", "generic", "owner", "resolve", "run_checks", "words_of"]


@dataclass(frozen=True)
class Context:
    """What a check may read besides the design.

    Parameters
    ----------
    spec : Spec
        The validated spec (``plant.uncertainty``, ``requirements``, ``simulation``, ``numerics``).
    simulation : SimulationResult or None
        The run (the last trial's, for a learning design).
    solver : str
        The conic solver of the LMIs and LPs.
    plant : Plant or None
        The true plant (None: the design's).
    law : Law or None
        The simulated law (the design's, with the spec's anti-windup; None: ``design.law``).
    trials : TrialsResult or None
        Every trial of a learning design.
    rerun : callable or None
        ``{parameter: value} -> tuple of Check``: the family's own run of the spec (its simulation or trials and its
        checks) on the true plant with these parameter values, passed in by the runner (the layer above), which
        the ``box_runs`` check calls at the points of the parameter box; None inside such a run (no nesting) and
        without a simulation.
    verdict_run : bool
        The run gives the spec's verdict (the pipeline's run), not a study's variant, a fix's re-run or a box
        re-run: checks of what the design ships (``generated_code``: its C code, written for this design only) run
        on it alone, so that variants do not compile code nobody ships.
    simulator : Simulator or None
        The built simulation the run ran (:func:`designkit.simulation.run.build`), for a check that runs the loop
        again with something changed (``generated_code``: the law's compiled C); None: built again when needed.
    """

    spec: Any
    simulation: Any = None
    solver: str = "CLARABEL"
    plant: Any = None
    law: Any = None
    trials: Any = None
    rerun: Callable[[Mapping[str, float]], tuple[Check, ...]] | None = None
    verdict_run: bool = False
    simulator: Any = None

    def true_plant(self, design: Any) -> Any:
        """The true plant (the design's when none was given)."""
        return design.plant if self.plant is None else self.plant

    def uncertainty(self) -> Any:
        """The spec's ``plant.uncertainty`` (None without one)."""
        return getattr(self.spec.plant, "uncertainty", None)


@dataclass(frozen=True)
class CheckRule:
    """One check (see the module docstring).

    Parameters
    ----------
    name : str
        The check's name (the names of the :class:`Check` values it returns may add a suffix).
    order : float
        Position in the report (the generic checks' are in the module docstring).
    applies : callable
        ``(design, Context) -> bool``: the design exposes what the check needs.
    run : callable
        ``(design, Context) -> tuple of Check``.
    linear : bool
        It reads the design's linear loop: offered only when the linearization contract gives one.
    label : str
        The check in words, for the report (``"Lyapunov function (LMI)"``).
    labels : Mapping
        Words for the names of the checks it returns when they differ from ``name`` (``overshoot`` ...).
    glossary : tuple of (str, str)
        Terms its evidence uses and what they mean.
    figures : tuple of callable
        ``(result, check) -> Figure | None``: figures drawn from one of its checks.
    diagnose : callable or None
        ``(result, check) -> (cause, fix) | (cause, fix, changes) | None``: why one of its checks failed, what
        would fix it, and optionally the changes of the spec that realize the fix
        (:class:`~designkit.synthesis.spec_change.SpecChange`), which the diagnosis re-runs.
    universal : bool
        Offered for every family, whether or not its ``checks`` name it (a property of any simulated loop,
        such as a chattering command); ``applies`` still decides.
    reads : tuple of str
        The ``requirements`` keys it judges (``"requirements.overshoot"``): a spec giving a requirement that no
        check its family offers reads is refused when it is read (:class:`~designkit.schema.spec.Spec`).
    """

    name: str
    order: float
    applies: Callable[[Any, Context], bool]
    run: Callable[[Any, Context], tuple[Check, ...]]
    linear: bool = False
    label: str = ""
    labels: Mapping[str, str] = field(default_factory=dict)
    glossary: tuple[tuple[str, str], ...] = ()
    figures: tuple[Callable[[Any, Any], Any], ...] = ()
    diagnose: Callable[[Any, Any], Any] | None = None
    universal: bool = False
    reads: tuple[str, ...] = ()

    def offered_for(self, design: Any, ctx: Context) -> bool:
        """True when the check runs for ``design``: its linearization (if it needs one) and what ``applies`` asks."""
        if self.linear and not design.linearization.linear:
            return False
        return bool(self.applies(design, ctx))

    def label_for(self, check_name: str) -> str:
        """The words of a check this rule returned: its ``labels`` entry, its ``label``, or the name in words; a
        suffix ``[joint1]`` is kept as ``(joint1)``."""
        base, _, suffix = check_name.partition("[")
        words = self.labels.get(base) or (self.label if base == self.name else "") or words_of(base)
        return f"{words} ({suffix.rstrip(']')})" if suffix else words

    def owns(self, check_name: str) -> bool:
        """True when a :class:`Check` named ``check_name`` comes from this rule."""
        base = check_name.split("[", 1)[0]
        return base == self.name or base in self.labels


def words_of(name: str) -> str:
    """A check name without a declared label, in words (``"steady_state_error"`` -> ``"Steady state error"``)."""
    return name.replace("_", " ").capitalize()


_RULES = Registry("designkit.verification.checks", "RULE", CheckRule)
"""Check name -> the generic :class:`CheckRule` of the module of that name (imported on first lookup)."""


_ORDERED: dict[str, CheckRule] = {}


def generic() -> Mapping[str, CheckRule]:
    """The generic checks, name -> :class:`CheckRule`, in report order (every rule module imported)."""
    if not _ORDERED:
        _ORDERED.update(sorted(_RULES.items(), key=lambda item: item[1].order))
    return _ORDERED


class _Generic(Mapping[str, CheckRule]):
    """Read-only view of the generic checks: a rule is imported when its name is looked up, iteration goes in
    report order (importing every rule module)."""

    def __getitem__(self, name: str) -> CheckRule:
        return _RULES[name]

    def __contains__(self, name: object) -> bool:
        return name in _RULES

    def __iter__(self):  # type: ignore[no-untyped-def]
        return iter(generic())

    def __len__(self) -> int:
        return len(_RULES)


GENERIC: Mapping[str, CheckRule] = _Generic()
"""Check name -> the generic :class:`CheckRule`, in report order."""


def resolve(offered: Sequence[str | CheckRule]) -> tuple[CheckRule, ...]:
    """The rules of ``offered`` (generic names and rules of a family's own) and the universal generic rules, in
    report order.

    Raises
    ------
    ValueError
        A name that is no generic check.
    """
    rules = []
    for item in offered:
        if isinstance(item, CheckRule):
            rules.append(item)
        elif item in _RULES:
            rules.append(_RULES[item])
        else:
            raise ValueError(f"unknown check {item!r}; the generic checks are {sorted(_RULES)}")
    names = {r.name for r in rules}
    rules += [r for r in generic().values() if r.universal and r.name not in names]
    return tuple(sorted(rules, key=lambda r: r.order))


def owner(rules: Sequence[CheckRule], check_name: str) -> CheckRule | None:
    """The rule among ``rules`` that returns checks named ``check_name`` (the first that owns it)."""
    return next((r for r in rules if r.owns(check_name)), None)


def _context(spec: Any, simulation: Any, plant: Any, law: Any, trials: Any, rerun: Any = None,
             verdict_run: bool = False, simulator: Any = None) -> Context:
    return Context(spec, simulation, spec.numerics.solver, plant, law, trials, rerun, verdict_run, simulator)


def applicable(design: Any, spec: Any, simulation: Any = None, plant: Any = None, *,
               rules: Sequence[str | CheckRule], law: Any = None, trials: Any = None) -> tuple[str, ...]:
    """Names of the checks among ``rules`` that run for ``design`` (offered and exposed)."""
    ctx = _context(spec, simulation, plant, law, trials)
    return tuple(r.name for r in resolve(rules) if r.offered_for(design, ctx))


def run_checks(spec: Any, design: Any, simulation: Any = None, plant: Any = None, *,
               rules: Sequence[str | CheckRule], law: Any = None, trials: Any = None,
               rerun: Callable[[Mapping[str, float]], tuple[Check, ...]] | None = None,
               verdict_run: bool = False, simulator: Any = None) -> tuple[Check, ...]:
    """Run every check of ``rules`` that applies (see the module docstring).

    Parameters
    ----------
    spec : Spec
        Validated spec (``plant.uncertainty``, ``requirements`` and ``numerics.solver`` are read).
    design : Design
        The synthesised controller.
    simulation : SimulationResult or None
        Closed-loop run for the time-domain and coupling checks.
    plant : Plant, optional
        The true plant (default: the design's); differs when the controller's model does.
    rules : sequence of str or CheckRule
        The checks the design's family offers (``Family.checks``).
    law : Law, optional
        The simulated law (default ``design.law``).
    trials : TrialsResult, optional
        The trials of a learning design.
    rerun : callable, optional
        The family's own run at other parameter values (:attr:`Context.rerun`).
    verdict_run : bool
        The run gives the spec's verdict (:attr:`Context.verdict_run`).
    simulator : Simulator, optional
        The built simulation ``simulation`` came from (:attr:`Context.simulator`).

    Returns
    -------
    tuple of Check
    """
    ctx = _context(spec, simulation, plant, law, trials, rerun, verdict_run, simulator)
    checks: list[Check] = []
    for rule in resolve(rules):
        if rule.offered_for(design, ctx):
            checks.extend(c if c.label else dataclasses.replace(c, label=rule.label_for(c.name))
                          for c in rule.run(design, ctx))
    return tuple(checks)
