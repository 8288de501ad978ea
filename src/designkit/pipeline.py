"""spec -> plant -> design -> simulation -> checks: the pipeline behind ``designkit synth``.

Each step is a pure function of the previous steps' frozen values; the report is written
from the :class:`PipelineResult` alone.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property
from importlib import metadata
from pathlib import Path
from typing import Any

from designkit.errors import SpecError
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
    """

    loaded: LoadedSpec
    design: Design
    checks: tuple[Check, ...]
    simulation: Any = None
    versions: Mapping[str, str] = field(default_factory=dict)
    plant: Any = None
    trials: Any = None

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
    def _report_model(self) -> Any:
        from designkit.report.model import build_report_model

        return build_report_model(self)

    def _repr_html_(self) -> str:
        """Jupyter view of the run, laid out from the same report model as the HTML and PDF reports
        (verdict, why it failed, requirement compliance, every check, figures inline as SVG).

        The report model (with its figures) is built on first display and kept for later ones.
        """
        from designkit.report.notebook import result_html

        return result_html(self._report_model)

    def to_json(self) -> dict[str, Any]:
        """The JSON object printed by ``designkit synth --json``."""
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
            "checks": [c.to_dict() for c in self.checks],
            "notes": list(d.notes),
            "versions": dict(self.versions),
            **extra,
        }


def base_dir(loaded: LoadedSpec) -> Path | None:
    """Folder of the spec file (relative model paths are resolved against it), or None for text."""
    return None if loaded.path.startswith("<") else Path(loaded.path).resolve().parent


def plant(loaded: LoadedSpec) -> Any:
    """The nominal plant of a spec."""
    from designkit.spec.plant_builder import plant_from_spec

    return plant_from_spec(loaded.spec.plant, base_dir(loaded))


def design(loaded: LoadedSpec, true_plant: Any = None) -> Design:
    """Synthesise the controller of a spec (for its true plant, built from the spec when not given), with its law
    carrying the spec's anti-windup (:func:`designkit.families.synthesize`)."""
    from designkit.families import synthesize

    true_plant = plant(loaded) if true_plant is None else true_plant
    return synthesize(loaded.spec, true_plant)


def _check_per_input(spec: Spec, true_plant: Any) -> None:
    """Per-input requirement lists have one entry per plant input, else :class:`SpecError`."""
    limit = spec.requirements.max_control if spec.requirements is not None else None
    if isinstance(limit, list | tuple) and len(limit) != true_plant.n_inputs:
        raise SpecError("requirements.max_control",
                        f"needs one value per input ({true_plant.n_inputs}), got {len(limit)}")


def run(loaded: LoadedSpec | Spec, *, simulate: bool = True) -> PipelineResult:
    """Synthesise, simulate and verify a spec.

    Parameters
    ----------
    loaded : LoadedSpec or Spec
        A validated spec (see :func:`designkit.spec.load_spec`), or a :class:`Spec` built in
        Python, which is wrapped with :meth:`LoadedSpec.from_spec`: its text (and the report's
        spec hash) is then the SHA-256 of its canonical JSON (``model_dump(mode="json")``, keys
        sorted), and model files such as a URDF are resolved against the working directory.
    simulate : bool
        Run the closed-loop simulation and the time-domain checks that need it.

    Raises
    ------
    SpecError
        ``loaded`` is neither a :class:`LoadedSpec` nor a :class:`Spec`, or the spec cannot be
        designed as given (a :class:`~designkit.errors.DesignkitError` names the key path).
    """
    from designkit.families import check_rules
    from designkit.simulation.run import build
    from designkit.simulation.trials import run_trials
    from designkit.verification.suite import run_checks

    if isinstance(loaded, Spec):
        loaded = LoadedSpec.from_spec(loaded)
    elif not isinstance(loaded, LoadedSpec):
        hint = "; read a file with load_spec or YAML text with parse_spec" if isinstance(loaded, str | Path) else ""
        raise SpecError("loaded", f"expected a LoadedSpec or a Spec, got {type(loaded).__name__}{hint}")
    spec = loaded.spec
    true_plant = plant(loaded)
    _check_per_input(spec, true_plant)
    dsn = design(loaded, true_plant)
    sim = trials = None
    if simulate:
        learning = dsn.learning
        simulator = build(spec, dsn, plant=true_plant, expected_runs=learning.trials if learning else 1)
        if learning is not None:
            trials = run_trials(simulator, learning.trials, learning.update)
            sim = trials.results[-1]
        else:
            sim = simulator.run()
    checks = run_checks(spec, dsn, sim, plant=true_plant, rules=check_rules(dsn.kind), trials=trials)
    return PipelineResult(loaded=loaded, design=dsn, checks=tuple(checks), simulation=sim, versions=versions(),
                          plant=true_plant, trials=trials)


def codegen(loaded: LoadedSpec | str | Path, out_dir: str | Path, *, name: str | None = None) -> Any:
    """Design the controller of a spec and write its C code (the body of ``designkit codegen``).

    Parameters
    ----------
    loaded : LoadedSpec or path-like
        A loaded spec (:func:`designkit.schema.loader.load_spec`) or the path of a YAML spec.
    out_dir : path-like
        Root folder; the code goes to ``out_dir/<spec name>/``.
    name : str, optional
        C prefix; default the spec name made a C identifier (:func:`designkit.synthesis.codegen.c_identifier`).

    Returns
    -------
    LawCode
        See :func:`designkit.synthesis.codegen.generate_law_code`.

    Raises
    ------
    SpecError
        Bad spec (its key path), bad ``name`` or unwritable ``out_dir``; nothing is written.
    """
    from designkit.families import family
    from designkit.schema.loader import load_spec
    from designkit.synthesis.codegen import check_name, generate_law_code

    if name is not None:
        check_name(name)
    loaded = loaded if isinstance(loaded, LoadedSpec) else load_spec(loaded)
    dsn = design(loaded)
    return generate_law_code(dsn, dsn.law, out_dir, name=name, spec_name=loaded.spec.name, spec_sha256=loaded.sha256,
                             law_lines=family(dsn.kind).display.law)
