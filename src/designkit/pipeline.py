"""spec -> plant -> design -> simulation -> checks: the pipeline behind ``designkit synth``.

Each step is a pure function of the previous steps' frozen values; the report is written
from the :class:`PipelineResult` alone.  A comparison spec (``controllers:``) runs each controller as
its own single-controller spec through the same path and returns a :class:`ComparisonResult`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property
from importlib import metadata
from pathlib import Path
from typing import Any

from designkit import arguments
from designkit.errors import SpecError
from designkit.schema.comparison import ComparisonSpec
from designkit.schema.loader import LoadedSpec
from designkit.schema.spec import Spec
from designkit.synthesis.design import Design
from designkit.verification.check import Check, all_passed, not_passed

_DEPENDENCIES = ("casadi", "numpy", "scipy", "control", "cvxpy", "clarabel", "matplotlib", "pydantic", "typst")


def versions() -> dict[str, str]:
    """Versions of designkit and its core dependencies (for reports)."""
    out = {}
    for name in ("designkit", *_DEPENDENCIES):
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = "not installed"
    return out


@dataclass(frozen=True, eq=False)
class PipelineResult:
    """Everything a design run produced.

    Parameters
    ----------
    loaded : LoadedSpec
        The validated spec with its source text and hash.
    design : Design
        Gains and nominal closed loop.
    checks : tuple of Check
        Every verification check, in report order.
    simulation : SimulationResult or None
        The closed-loop simulation (None when not run); for a learning design, the last trial's.
    versions : Mapping
        designkit and dependency versions.
    plant : Plant or None
        The true plant the simulation ran on (the design's ``plant`` is the controller's model; the two
        differ when the spec gives ``controller.model``).  None means the design's.
    trials : TrialsResult or None
        Every trial of a learning design (``design.learning``), None for a design run once.
    seconds : float
        Wall time of the design, the run and the checks (s): what a study expects one variant to cost.
    """

    loaded: LoadedSpec
    design: Design
    checks: tuple[Check, ...]
    simulation: Any = None
    versions: Mapping[str, str] = field(default_factory=dict)
    plant: Any = None
    trials: Any = None
    seconds: float = 0.0

    @property
    def verified(self) -> bool:
        """True when every check passed (undecided is not a pass)."""
        return all_passed(self.checks)

    @property
    def failed(self) -> tuple[Check, ...]:
        """Required checks that failed or are undecided."""
        return not_passed(self.checks)

    @property
    def display(self) -> Any:
        """How the design's family is named and written (:class:`~designkit.synthesis.family.Display`)."""
        from designkit.families import family

        return family(self.design.kind).display

    @cached_property
    def studies(self) -> tuple[Any, ...]:
        """Every study that applies to this run (:func:`designkit.studies.run_studies`), run on first access:
        gain studies, boundaries, lab answers, each through the family's own run."""
        from designkit.studies import run_studies

        return run_studies(self)

    @cached_property
    def diagnosis(self) -> Any:
        """The run's diagnosis (:func:`designkit.analysis.diagnosis.diagnose`: why it failed, the re-simulated fixes,
        the linear model against the run), on first access; the exception itself when the diagnosis failed."""
        from designkit.analysis.diagnosis import diagnose

        try:
            return diagnose(self)
        except Exception as exc:  # noqa: BLE001 - a failed diagnosis is reported, never costs the verdict
            return exc

    @cached_property
    def _report_model(self) -> Any:
        from designkit.report.model import build_report_model

        # the studies only once asked for (``result.studies``): a notebook shows the run at once
        return build_report_model(self, studies="studies" in self.__dict__)

    def _repr_html_(self) -> str:
        """Jupyter view of the run, laid out from the same report model as the HTML and PDF reports
        (verdict, why it failed, requirement compliance, every check, figures inline as SVG).

        The report model (with its figures) is built on first display and kept for later ones.
        """
        from designkit.report.notebook import result_html

        return result_html(self._report_model)

    @property
    def warnings(self) -> tuple[str, ...]:
        """What a reviewer must see even when every check passes, one plain sentence each: the checks' own
        warnings (weak margins, chattering commands) and inertial parameters of the plant that are not physically
        consistent."""
        out = [w for c in self.checks for w in c.warnings]
        robot = getattr(self.design.plant, "robot", None)
        if robot is not None:
            from designkit.models.physical import check_inertia

            consistency = check_inertia(robot.description)
            if not consistency.consistent:
                out.append(consistency.sentences()[0])
        return tuple(dict.fromkeys(out))

    @property
    def scope(self) -> dict[str, Any]:
        """What the verdict is on: ``implemented`` (the spec gives ``implementation``, the run is the controller as
        implemented) and ``words``: the implementation in words (sampling rate, computation delay, quantisation,
        actuator), or, for a switching law run without the section, that the verdict holds for a continuous-time
        switch simulated at ``1/dt``; None otherwise."""
        settings = dict(getattr(self.simulation, "settings", None) or {})
        words = settings.get("implementation") or settings.get("scope")
        return {"implemented": getattr(self.loaded.spec, "implementation", None) is not None,
                "words": str(words) if words else None}

    def to_json(self, *, studies: bool = False) -> dict[str, Any]:
        """The JSON object printed by ``designkit verify --json``; with ``studies`` (``synth --json``) also
        ``"studies"`` (:meth:`designkit.studies.core.study.StudyResult.to_json`, one object per study and
        parameter) and ``"fixes"`` (each proposed fix's changed spec fields and its re-run verdict)."""
        from designkit.families import family

        d = self.design
        fam = family(d.kind)
        extra = dict(fam.json(self)) if fam.json is not None else {}
        return {
            "name": self.loaded.spec.name,
            "spec_sha256": self.loaded.sha256,
            "kind": d.kind,
            "plant": d.plant.kind,
            "gains": d.gains.to_json(),
            "gain_units": {k: d.gains.unit(k) for k in d.gains},
            "poles": [[p.real, p.imag] for p in d.poles],
            "zeros": [[z.real, z.imag] for z in d.zeros],
            "loops": {name: {"poles": [[p.real, p.imag] for p in loop.poles],
                             "zeros": [[z.real, z.imag] for z in loop.zeros]}
                      for name, loop in zip(d.loop_names, d.loops, strict=True)},
            "verified": self.verified,
            "warnings": list(self.warnings),
            "checks": [c.to_dict() for c in self.checks],
            "notes": list(d.notes),
            "scope": self.scope,
            "versions": dict(self.versions),
            **extra,
            **({"studies": [e for st in self.studies for e in st.to_json()], "fixes": self._fixes_json()}
               if studies else {}),
        }

    def _fixes_json(self) -> list[dict[str, Any]]:
        """Each re-simulated fix: its title, the spec fields it changes, whether every required check then passes,
        and the re-run's verdict in words; then each study's recommendation that changes a spec setting (already run
        by the study, with its neighbourhood)."""
        from designkit.studies import study_fixes

        studied = [{"fix": f.text, "note": f"run by the {f.study} study", "runs": [
            {"title": f.text, "changes": [{"path": k, "value": _jsonable(v)} for k, v in f.changes],
             "requirement": False, "passed": True, "verdict": "every required check passes", "error": "",
             "checks": []}]} for f in study_fixes(self, self.studies)]
        diagnosis = self.diagnosis
        if diagnosis is None or isinstance(diagnosis, Exception):
            return studied
        return studied + [{"fix": p.sentence, "note": p.note, "runs": [
            {"title": t.remedy.title, "changes": [{"path": k, "value": _jsonable(v)} for k, v in t.remedy.changes],
             "requirement": t.remedy.requirement, "passed": t.passed, "verdict": t.verdict, "error": t.error,
             "checks": [{"name": o.name, "status": o.status, "measured": o.measured, "requirement": o.requirement}
                        for o in t.outcomes]} for t in p.trials]}
            for p in diagnosis.proposed]


@dataclass(frozen=True, eq=False)
class ComparisonResult:
    """The runs of a comparison spec: each controller run alone on the shared task, and their table.

    Parameters
    ----------
    loaded : LoadedSpec
        The comparison spec (``controllers:``) with its source text and hash.
    labels : tuple of str
        The controllers' labels, in spec order.
    results : tuple of PipelineResult
        Each controller's run of its single-controller spec (:meth:`LoadedSpec.members`), exactly what
        :func:`run` returns for that spec alone.
    table : ComparisonTable
        The same metrics for every controller (:func:`designkit.comparison.table.comparison_table`).
    versions : Mapping
        designkit and dependency versions.
    unchanged : tuple of SimulationResult or None
        Each controller's run on the unchanged plant (the spec without ``plant_change``; None without one), the
        reference of the departure metrics and figure.
    """

    loaded: LoadedSpec
    labels: tuple[str, ...]
    results: tuple[PipelineResult, ...]
    table: Any
    versions: Mapping[str, str] = field(default_factory=dict)
    unchanged: tuple[Any, ...] = ()

    @property
    def verified(self) -> bool:
        """True when every controller is verified (every check of every run passed)."""
        return all(r.verified for r in self.results)

    @property
    def failed(self) -> tuple[tuple[str, Check], ...]:
        """``(label, check)`` of every required check that failed or is undecided, controller by controller."""
        return tuple((label, c) for label, r in zip(self.labels, self.results, strict=True) for c in r.failed)

    @cached_property
    def studies(self) -> tuple[Any, ...]:
        """Every comparison study that applies (:func:`designkit.studies.run_studies`: lab experiments over several
        controllers), run on first access, each through the members' families' own runs."""
        from designkit.studies import run_studies

        return run_studies(self)

    def __getitem__(self, label: str) -> PipelineResult:
        """The run of controller ``label``."""
        try:
            return self.results[self.labels.index(label)]
        except ValueError:
            raise KeyError(label) from None

    def to_json(self, *, studies: bool = False) -> dict[str, Any]:
        """The JSON object printed by ``designkit synth --json`` for a comparison.

        ``comparison`` has one object per controller (label, kind, verified, metrics, checks, warnings, and its
        own run's JSON under ``result``); ``winners`` one object per metric, with ``tie`` and ``tied``
        (:meth:`~designkit.comparison.table.ComparisonTable.winners_json`); ``passed`` and ``verified`` say whether
        every controller is verified; ``warnings`` every controller's warnings, each prefixed with its label;
        ``checks`` lists every check of every controller, each with its ``controller`` label.  With ``studies``
        (``synth --json``) also ``"studies"``, the comparison studies' objects
        (:meth:`designkit.studies.core.study.StudyResult.to_json`), and each controller's own ``studies`` and
        ``fixes`` under ``result``.
        """
        rows = self.table.to_json()
        for row, r in zip(rows, self.results, strict=True):
            row["result"] = r.to_json(studies=studies)
        return {
            "name": self.loaded.spec.name,
            "spec_sha256": self.loaded.sha256,
            "kind": "comparison",
            "controllers": list(self.labels),
            "comparison": rows,
            "metric_units": {m.key: self.table.unit_of(m) for m in self.table.metrics},
            "winners": self.table.winners_json(),
            "passed": self.verified,
            "verified": self.verified,
            "warnings": [f"{label}: {w}" for label, r in zip(self.labels, self.results, strict=True)
                         for w in r.warnings],
            "checks": [{**c.to_dict(), "controller": label}
                       for label, r in zip(self.labels, self.results, strict=True) for c in r.checks],
            "versions": dict(self.versions),
            **({"studies": [e for st in self.studies for e in st.to_json()]} if studies else {}),
        }


def _jsonable(value: Any) -> Any:
    """A spec value for JSON (complex poles as ``[re, im]``, arrays as lists)."""
    import numpy as np

    if isinstance(value, complex):
        return [value.real, value.imag]
    if isinstance(value, np.ndarray | list | tuple):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


def base_dir(loaded: LoadedSpec) -> Path | None:
    """Folder of the spec file (relative model paths are resolved against it), or None for text."""
    from designkit.runner.run import base_dir as of

    return of(loaded)


def plant(loaded: LoadedSpec) -> Any:
    """The nominal plant of a spec."""
    from designkit.spec.plant_builder import plant_from_spec

    return plant_from_spec(loaded.spec.plant, base_dir(loaded))


def single(loaded: LoadedSpec, what: str) -> None:
    """Refuse a comparison spec where one controller is needed (:class:`SpecError` at ``controllers``)."""
    if isinstance(loaded.spec, ComparisonSpec):
        raise SpecError("controllers", f"{what} needs a spec with one controller (controller:); this one compares "
                        f"{len(loaded.spec.controllers)} ({', '.join(loaded.spec.labels)}): give each its own spec")


def design(loaded: LoadedSpec, true_plant: Any = None) -> Design:
    """Synthesise the controller of a spec (for its true plant, built from the spec when not given), with its law
    carrying the spec's anti-windup (:func:`designkit.families.synthesize`)."""
    from designkit.families import synthesize

    single(loaded, "a design")
    true_plant = plant(loaded) if true_plant is None else true_plant
    return synthesize(loaded.spec, true_plant)


def _check_per_input(spec: Spec, true_plant: Any) -> None:
    """Per-input requirement lists have one entry per plant input, else :class:`SpecError`."""
    limit = spec.requirements.max_control if spec.requirements is not None else None
    if isinstance(limit, list | tuple) and len(limit) != true_plant.n_inputs:
        raise SpecError("requirements.max_control",
                        f"needs one value per input ({true_plant.n_inputs}), got {len(limit)}")


def run(loaded: LoadedSpec | Spec | ComparisonSpec, *, simulate: bool = True,
        budget: float | None = None) -> PipelineResult | ComparisonResult:
    """Synthesise, simulate and verify a spec.

    Parameters
    ----------
    loaded : LoadedSpec, Spec or ComparisonSpec
        A validated spec (see :func:`designkit.spec.load_spec`), or a :class:`Spec` built in
        Python, which is wrapped with :meth:`LoadedSpec.from_spec`: its text (and the report's
        spec hash) is then the SHA-256 of its canonical JSON (``model_dump(mode="json")``, keys
        sorted), and model files such as a URDF are resolved against the working directory.
    simulate : bool
        Run the closed-loop simulation and the time-domain checks that need it.
    budget : float, optional
        Seconds of estimated work the spec may ask for (default
        :data:`~designkit.schema.budget.DEFAULT_BUDGET`, 60 s): the estimate is made before any model is built
        (:func:`designkit.schema.budget.check_budget`) and a spec beyond it is refused naming the field that
        drives the cost.

    Returns
    -------
    PipelineResult or ComparisonResult
        The run of a one-controller spec; for a comparison spec (``controllers:``), every controller run
        alone as its single-controller spec (:meth:`LoadedSpec.members`) and their table.

    Raises
    ------
    SpecError
        ``loaded`` is neither a :class:`LoadedSpec` nor a :class:`Spec`, or the spec cannot be
        designed as given (a :class:`~designkit.errors.DesignkitError` names the key path).
    """
    from designkit.runner.run import run_spec
    from designkit.schema.budget import check_budget

    if isinstance(loaded, Spec | ComparisonSpec):
        loaded = LoadedSpec.from_spec(loaded)
    elif not isinstance(loaded, LoadedSpec):
        hint = "; read a file with load_spec or YAML text with parse_spec" if isinstance(loaded, str | Path) else ""
        raise SpecError("loaded", f"expected a LoadedSpec or a Spec, got {type(loaded).__name__}{hint}")
    simulate = arguments.flag(simulate, "simulate")
    if budget is not None:
        budget = arguments.number(budget, "budget", positive=True)
    if isinstance(loaded.spec, ComparisonSpec):
        return run_comparison(loaded, simulate=simulate, budget=budget)
    spec = loaded.spec
    check_budget(spec, base_dir(loaded), budget)
    check_studies(spec, base_dir(loaded))
    true_plant = plant(loaded)
    _check_per_input(spec, true_plant)
    done = run_spec(loaded, plant=true_plant, simulate=simulate, verdict_run=True)
    return PipelineResult(loaded=loaded, design=done.design, checks=done.checks, simulation=done.simulation,
                          versions=versions(), plant=true_plant, trials=done.trials, seconds=done.seconds)


def check_studies(spec: Spec, folder: Path | None = None) -> None:
    """Refuse, before anything runs, a ``studies`` section the studies cannot honour
    (:func:`designkit.studies.validate`) or a ``studies.budget`` below one variant's estimated cost.

    Raises
    ------
    SpecError
        With the key path (``studies.budget``, ``studies.gains.knobs[0]``, ...).
    """
    section = getattr(spec, "studies", None)
    if section is None:
        return
    from designkit.families import family
    from designkit.studies import validate
    from designkit.studies.core.budget import variant_estimate

    validate(spec, family(spec.controller.kind))
    if section.budget is not None:
        one = variant_estimate(spec, folder)
        if one > section.budget:
            raise SpecError("studies.budget", f"one variant of this spec is estimated at {one:.2g} s, more than the "
                            f"{section.budget:g} s given: no study could run a variant (give at least {one:.2g})")


def run_comparison(loaded: LoadedSpec, *, simulate: bool = True, budget: float | None = None) -> ComparisonResult:
    """Run every controller of a comparison spec as its own single-controller spec (:func:`run`) and tabulate.

    Raises
    ------
    SpecError
        ``loaded`` names one controller; or a controller cannot be designed as given (the key path is
        rewritten from ``controller`` to ``controllers[<i>]``).
    """
    from designkit.comparison.table import baselines, comparison_table
    from designkit.schema.budget import check_comparison_budget

    members = loaded.members()
    share = check_comparison_budget([m.spec for _, m in members], base_dir(loaded), budget)
    results = []
    for k, (_, member) in enumerate(members):
        try:
            results.append(run(member, simulate=simulate, budget=share[k]))
        except SpecError as exc:
            path = exc.path
            if path == "controller" or path.startswith(("controller.", "controller[")):
                raise SpecError(f"controllers[{k}]{path[len('controller'):]}", exc.message) from None
            raise
    labels = tuple(label for label, _ in members)
    unchanged = baselines(results)
    return ComparisonResult(loaded=loaded, labels=labels, results=tuple(results),
                            table=comparison_table(labels, results, unchanged), versions=versions(),
                            unchanged=unchanged)


def codegen(loaded: LoadedSpec | str | Path, out_dir: str | Path, *, name: str | None = None,
            budget: float | None = None) -> Any:
    """Design the controller of a spec and write its C code (the body of ``designkit codegen``).

    The spec is checked as :func:`run` checks it before anything is written: the work budget
    (:func:`designkit.schema.budget.check_budget`), the studies section, the per-input lists, the design, and the
    simulation the verification would run (:func:`designkit.simulation.run.build`: the step against the poles and
    the law's largest step, the step bound, the reference), so a spec ``verify`` refuses is refused here with the
    same line, and the code written is that of a loop ``verify`` can check.

    Parameters
    ----------
    loaded : LoadedSpec or path-like
        A loaded spec (:func:`designkit.schema.loader.load_spec`) or the path of a YAML spec.
    out_dir : path-like
        Root folder; the code goes to ``out_dir/<spec name>/``.
    name : str, optional
        C prefix; default the spec name made a C identifier (:func:`designkit.synthesis.codegen.c_identifier`).
    budget : float, optional
        Seconds of estimated work the spec may ask for, as in :func:`run` (default 60 s).

    Returns
    -------
    LawCode
        See :func:`designkit.synthesis.codegen.generate_law_code`.

    Raises
    ------
    SpecError
        Bad spec (its key path, as :func:`run` names it), bad ``name`` or unwritable ``out_dir``; nothing is
        written.
    """
    from designkit.families import family
    from designkit.schema.budget import check_budget
    from designkit.schema.loader import load_spec
    from designkit.simulation.run import build
    from designkit.synthesis.codegen import check_name, generate_law_code

    if name is not None:
        check_name(arguments.text(name, "name"))
    if not isinstance(loaded, LoadedSpec):
        loaded = load_spec(arguments.path(loaded, "loaded", what="a LoadedSpec or a spec file path"))
    out_dir = arguments.path(out_dir, "out_dir", what="a folder path")
    single(loaded, "codegen")
    spec = loaded.spec
    check_budget(spec, base_dir(loaded), budget)
    check_studies(spec, base_dir(loaded))
    true_plant = plant(loaded)
    _check_per_input(spec, true_plant)
    dsn = design(loaded, true_plant)
    learning = dsn.learning
    if learning is not None and learning.run is not None:
        raise SpecError("plant.kind", f"the {dsn.kind} design on a {true_plant.kind} plant has no control law to "
                        "generate: its learned input is a sequence played to the plant, trial by trial")
    build(spec, dsn, plant=true_plant, expected_runs=learning.trials if learning else 1)
    return generate_law_code(dsn, dsn.law, out_dir, name=name, spec_name=spec.name, spec_sha256=loaded.sha256,
                             law_lines=family(dsn.kind).display.law)
