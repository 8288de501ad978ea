"""What a controller family declares: the single registration point of a controller kind.

One module (or package) of :mod:`designkit.families` per family defines ``FAMILY = Family(...)``;
the registry (:mod:`designkit.families`) collects them, and everything that depends on the kind --
the spec's ``controller`` union and its JSON Schema, the loader's error paths, the references it
may be driven by, which checks run, the report's law, gain table, loop formula, figures, sections
and diagnoses -- is derived from these declarations.  Nothing outside the family's module names its
kind.

A family brings what is its own: checks (:class:`~designkit.verification.suite.CheckRule` values,
next to the generic ones it names), figures drawn from a run, report sections (its lab answers),
and diagnoses of a failed check.  These are plain callables on the run (the pipeline's result), so
this module imports none of the layers that define them.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from designkit.synthesis.design import Design
from designkit.synthesis.knobs import Knob, Metric, Variant
from designkit.synthesis.law import Law

__all__ = ["ANSWER_TOPICS", "Display", "Family", "PlantField", "SETTINGS", "STEP_REFERENCES", "TRAJECTORY_REFERENCES"]

STEP_REFERENCES = ("step", "square", "prbs")
"""References a servo (a ``"step"`` design) follows by default: ``simulation.step``, a square wave, a PRBS."""
TRAJECTORY_REFERENCES = ("quintic", "sine", "trapezoidal", "via_points")
"""References a joint tracker (a ``"trajectory"`` design) follows by default."""
ANSWER_TOPICS = {
    "how": "why and how the law does what it does on this run, with the run's numbers: what an adaptive law adapted "
           "and what it ended at, how a switching law reached and held its surface",
    "strategy": "the control strategy: what the law measures and computes at each instant or sample, from which "
                "settings, and which algorithms its design needs, with the design's numbers",
}
"""The topics a family may answer (:attr:`Family.answers`) when a study asks it about one of its runs."""

SETTINGS = {
    "simulation.anti_windup": "an anti-windup limits the integral state of a PID law, and this law has none it may "
                              "limit",
    "plant.uncertainty": "none of its checks judges the design over a box of plant parameters",
    "plant.uncertainty.grid": "the lattice of the box is read by the lattice check (robust_grid), which it does "
                              "not offer",
    "plant.dt": "it designs and simulates a continuous-time loop, and a discrete-time plant is a difference equation "
                "the simulator does not integrate; give the continuous-time model (no dt)",
    "plant.uncertainty.samples": "the box's random samples are read by the robust_grid, tracking_bounds and box_runs "
                                 "checks, none of which it offers",
}
"""The optional settings outside ``controller`` that only some families honour, and why a family that does not
(:attr:`Family.uses`) refuses them: a spec giving one its family does not use is refused when it is read, naming
the key path, so no setting is silently ignored."""


@dataclass(frozen=True)
class PlantField:
    """A ``controller`` field a family reads on some plant kinds only (:attr:`Family.plant_fields`).

    Parameters
    ----------
    name : str
        The field (``"workspace"``).
    plants : tuple of str
        The plant kinds on which the family reads it.
    what : str
        What it is for, in words (the refusal on another plant kind says it).
    """

    name: str
    plants: tuple[str, ...]
    what: str


@dataclass(frozen=True)
class Display:
    """How the report names and writes a family.

    Parameters
    ----------
    label : str
        The family in words (``"PID position servo"``).
    law : tuple of str
        The control law, one plain-text (Unicode) line each, in the plant's signal names.
    loop_transfer : str
        The loop transfer at the plant input in closed form, or ``""``.
    summary : str
        One sentence: what the family does and where it comes from (notes section).
    law_of : callable or None
        ``design -> tuple of str``: the law of a design when it depends on the design (a family with one form per
        plant kind); :meth:`law_lines` falls back to ``law``.
    loop_transfer_of : callable or None
        ``design -> str or None``: the loop transfer of a design when it depends on the design; ``None`` from it
        falls back to ``loop_transfer`` (:meth:`loop_line`).
    """

    label: str
    law: tuple[str, ...]
    loop_transfer: str = ""
    summary: str = ""
    law_of: Callable[[Any], tuple[str, ...]] | None = None
    loop_transfer_of: Callable[[Any], str | None] | None = None

    def loop_line(self, design: Any) -> str:
        """The loop transfer the report writes for ``design`` (``""``: none in closed form)."""
        line = self.loop_transfer_of(design) if self.loop_transfer_of is not None and design is not None else None
        return self.loop_transfer if line is None else line

    def law_lines(self, design: Any) -> tuple[str, ...]:
        """The law as the report writes it for ``design``: ``law_of(design)`` when given and not empty, else
        ``law``."""
        lines = self.law_of(design) if self.law_of is not None else ()
        return tuple(lines) or self.law


@dataclass(frozen=True)
class Family:
    """A controller family (see the module docstring).

    Parameters
    ----------
    kind : str
        The spec's ``controller.kind``.
    spec : type
        Its pydantic model (a :class:`~designkit.spec.fields.Section` with ``kind: Literal[kind]``),
        a member of the spec's ``controller`` discriminated union.
    plants : tuple of str
        Plant kinds it can be designed for (``("link",)``, ``("robot",)``).
    reference : str
        What its law reads of the reference: ``"step"`` (a servo: positions) or ``"trajectory"`` (a tracker:
        positions, velocities and accelerations).
    synthesize : callable
        ``(spec, plant) -> Design``: the gains, for the nominal plant built from the spec, with the design's
        ``law`` (and its linearization contract).
    law : callable
        ``(design, anti_windup) -> Law``: the control law, written once as CasADi functions (the registry's
        :func:`~designkit.families.synthesize` gives the design the law with the spec's anti-windup).
    checks : tuple of str or CheckRule
        The checks it offers: names of the generic checks (:data:`designkit.verification.suite.GENERIC`) and
        rules of its own; each runs when the design exposes what it needs.
    display : Display
        Report data.
    validate : callable or None
        ``spec -> None``: cross-section rules of the parsed spec (raise ``ValueError("key.path:
        message")``), e.g. "poles or requirements".
    references : tuple of str
        The ``simulation.trajectory`` kinds (and ``"step"`` for ``simulation.step``) it can follow; a spec
        giving another is refused when it is read.  Default: :data:`STEP_REFERENCES` for a servo,
        :data:`TRAJECTORY_REFERENCES` for a tracker.
    figures : tuple of callable
        ``result -> Figure | None``: figures of its own drawn from a run (a phase portrait, adaptation traces).
    sections : tuple of callable
        ``result -> ReportSection | None``: report sections of its own (lab questions answered from the run).
    diagnoses : tuple of callable
        ``(result, check) -> (cause, fix) | (cause, fix, changes) | None``: why a check failed on its design (its
        own checks, and a generic one explained from its own quantities), what would fix it, and optionally the
        changes of the spec that realize the fix (:class:`~designkit.synthesis.spec_change.SpecChange`), which
        the diagnosis re-runs.
    motion : callable or None
        Task-space families: ``(spec, design) -> TaskMotion``, also stored in ``design.motion`` at synthesis.
    json : callable or None
        ``result -> Mapping``: top-level fields it adds to ``synth --json`` / ``verify --json`` (what its
        results are, for checking from outside: an adaptive law's initial and final parameters, a learning
        law's error per trial), JSON types only.
    knobs : tuple of Knob
        What a study may vary (:class:`~designkit.synthesis.knobs.Knob`): its gains and settings with their
        ranges and roles, most telling first.
    metrics : tuple of Metric
        The numbers meaningful for its law (:class:`~designkit.synthesis.knobs.Metric`), the first the one a
        study ranks by; empty: a study measures the tracking error and the command.
    traits : frozenset of str
        What a study may match it on, words for the law, never a spec or a kind (``"pid"``: a classical PID, the
        notes' experiment 1; ``"adaptive"``, ``"switching"``, ``"learning"``, ``"model_based"``,
        ``"model_reference"``, ``"certainty_equivalence"``, ``"state_feedback"``).
    regain : callable or None
        ``(design, gains, anti_windup) -> Design``: the design with other gains (its law, its closed loop and
        its per-joint loops rebuilt), for a family whose design the generic rebuild
        (:func:`designkit.runner.variants.with_gains`) cannot redo, e.g. one with per-joint loops.
    per_joint_fields : tuple of str
        Names of its ``controller`` fields that hold one value for every joint or a list with one per joint (or per
        task coordinate, as many): the loader refuses a list of another length before the plant's model is built
        (:func:`designkit.schema.joint_count.check_joint_lists`).
    answers : tuple of (str, callable)
        ``(topic, result -> tuple of str)``: what the family says of one of its runs when a study asks about a
        topic of :data:`ANSWER_TOPICS` (a comparison's lab answer asks every member), one sentence each, numbers
        from the run and the design; an empty tuple when it has nothing to say of that run.
    predictions : tuple of Metric
        Numbers the family predicts in closed form for a run (``load_offset``: the static offset a constant load
        leaves), each a :class:`~designkit.synthesis.knobs.Metric` (None where it does not apply), which a study
        sets beside what the run measured; unlike :attr:`metrics` they rank nothing.
    variants : tuple of Variant
        Named changes of the spec a study may run (:class:`~designkit.synthesis.knobs.Variant`): another form of
        the law, such as an adaptive rule's ad hoc modifications.
    uses : tuple of str
        The optional settings of :data:`SETTINGS` it honours (``"simulation.anti_windup"``, ``"plant.uncertainty"``,
        ``"plant.uncertainty.grid"``, ``"plant.uncertainty.samples"``); a spec giving another is refused when it is
        read (:class:`~designkit.schema.spec.Spec`), with the reason from :data:`SETTINGS`.
    plant_fields : tuple of PlantField
        Its ``controller`` fields that it reads on some plant kinds only; given on another plant kind, one is
        refused when the spec is read.
    box_design : str
        How its run is repeated at a plant of ``plant.uncertainty`` (the ``box_runs`` check): ``"nominal"`` (the
        design for the spec's plant, run on the other plant, which the controller is not told of) or ``"each"``
        (its synthesis for that plant: for a family whose design takes what it reads of the plant as known -- the
        adaptive computed torque's non-adapted parameters and ideal accelerometer -- and which refuses a box
        that moves anything it does not estimate).
    """

    kind: str
    spec: type
    plants: tuple[str, ...]
    reference: str
    synthesize: Callable[[Any, Any], Design]
    law: Callable[[Design, Any], Law]
    checks: tuple[Any, ...]
    display: Display
    validate: Callable[[Any], None] | None = None
    references: tuple[str, ...] = ()
    figures: tuple[Callable[[Any], Any], ...] = ()
    sections: tuple[Callable[[Any], Any], ...] = ()
    diagnoses: tuple[Callable[[Any, Any], Any], ...] = ()
    motion: Callable[[Any, Design], Any] | None = None
    json: Callable[[Any], Any] | None = None
    knobs: tuple[Knob, ...] = ()
    metrics: tuple[Metric, ...] = ()
    traits: frozenset[str] = frozenset()
    regain: Callable[[Design, Any, Any], Design] | None = None
    per_joint_fields: tuple[str, ...] = ()
    answers: tuple[tuple[str, Callable[[Any], tuple[str, ...]]], ...] = ()
    predictions: tuple[Metric, ...] = ()
    variants: tuple[Variant, ...] = ()
    uses: tuple[str, ...] = ()
    plant_fields: tuple[PlantField, ...] = ()
    box_design: str = "nominal"

    def __post_init__(self) -> None:
        if self.reference not in ("step", "trajectory"):
            raise ValueError(f"family {self.kind!r}: reference must be 'step' or 'trajectory'")
        if self.box_design not in ("nominal", "each"):
            raise ValueError(f"family {self.kind!r}: box_design must be 'nominal' or 'each'")
        if not self.references:
            default = STEP_REFERENCES if self.reference == "step" else TRAJECTORY_REFERENCES
            object.__setattr__(self, "references", default)
        for name in ("checks", "references", "figures", "sections", "diagnoses", "knobs", "metrics", "answers",
                     "predictions", "variants", "uses", "plant_fields"):
            object.__setattr__(self, name, tuple(getattr(self, name)))
        object.__setattr__(self, "traits", frozenset(self.traits))
        unknown = [u for u in self.uses if u not in SETTINGS]
        if unknown:
            raise ValueError(f"family {self.kind!r}: uses settings {unknown} not in {tuple(SETTINGS)}")
        keys = [k.key for k in self.knobs]
        if len(set(keys)) != len(keys):
            raise ValueError(f"family {self.kind!r}: two knobs share a name ({keys})")
        for topic, _ in self.answers:
            if topic not in ANSWER_TOPICS:
                raise ValueError(f"family {self.kind!r}: answers a topic {topic!r} not in {tuple(ANSWER_TOPICS)}")

    def answer(self, topic: str, result: Any) -> tuple[str, ...]:
        """What the family says of ``result`` on ``topic`` (:attr:`answers`); empty when it does not answer it."""
        return tuple(s for t, make in self.answers if t == topic for s in make(result))

    def prediction(self, key: str) -> Metric | None:
        """The prediction named ``key`` (:attr:`predictions`), or None."""
        return next((m for m in self.predictions if m.key == key), None)

    def knob(self, key: str) -> Knob | None:
        """The knob named ``key`` (:attr:`Knob.key`), or None."""
        return next((k for k in self.knobs if k.key == key), None)

    @property
    def check_names(self) -> tuple[str, ...]:
        """Names of the checks it offers, generic and its own."""
        return tuple(c if isinstance(c, str) else c.name for c in self.checks)
