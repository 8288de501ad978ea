"""Studies: what interprets a verdict, each one module, discovered like the families and the check rules.

A study varies what a family declares it may vary (its knobs, :mod:`designkit.synthesis.knobs`) and runs every
variant through the family's own run with the family's own checks (:mod:`designkit.runner`); it measures what the
family declares meaningful (its metrics) and says only what those runs showed.  Every module or package of this
package other than :mod:`~designkit.studies.core` (and names starting with ``_``) is named by its study and defines
``STUDY``, a :class:`~designkit.studies.core.study.Study`; :data:`STUDIES` maps each name to it (a study's module is
imported when its name is first looked up: :class:`designkit.discovery.Registry`), and :func:`in_report_order` lists
them in report order.  Adding a study
is adding a module here: no generic file changes, the report lays out its section and figures, ``synth --json``
carries its rows, and the spec's ``studies`` section takes its settings under its name.

A spec's ``studies`` section::

    studies:
      budget: 20                  # s of work each study may spend on its variants (default 15)
      gains: {knobs: [K1, K2], factors: [0.5, 2]}
      boundary: {knob: gamma, low: 100, high: 1.0e6}

is read by :func:`validate` before anything is run: an unknown study, a knob the family does not declare, a value
outside the knob's declared range, or a budget too small for one variant is refused with its key path.

A comparison study cites a member's own study with :func:`study_of` (through
:meth:`~designkit.studies.core.study.StudyContext.study`): it is run once for that member and kept, and the member's
own studies (:func:`run_studies`, its own report) return it rather than running it again.
"""

from __future__ import annotations

import time
import weakref
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from designkit.discovery import Registry
from designkit.errors import SpecError
from designkit.studies.core.study import Study, StudyContext, StudyResult

__all__ = ["DEFAULT_BUDGET", "STUDIES", "StudyFix", "in_report_order", "run_studies", "study_fixes", "study_of",
           "study_settings", "validate"]

DEFAULT_BUDGET = 15.0
"""Seconds of work each study may spend on its variants when the spec's ``studies.budget`` is not given."""


def _registry() -> Registry:
    return Registry(__name__, "STUDY", Study, skip=("core",))


STUDIES: Mapping[str, Study] = _registry()
"""Study name -> :class:`~designkit.studies.core.study.Study` (read-only; a study's module is imported when its name
is first looked up)."""


def in_report_order(studies: Mapping[str, Study] | None = None) -> tuple[Study, ...]:
    """Every study of ``studies`` (default :data:`STUDIES`, each imported) by ``(order, name)``: report order."""
    found = STUDIES if studies is None else studies
    return tuple(sorted(found.values(), key=lambda st: (st.order, st.name)))


def _discover() -> dict[str, Study]:
    """Every study module of the package (listed afresh), name -> study, in report order."""
    return {st.name: st for st in in_report_order(_registry())}


def _section(spec: Any) -> Any:
    return getattr(spec, "studies", None)


def _raw(spec: Any) -> dict[str, Any]:
    """The study keys of the spec's ``studies`` section (its settings, unvalidated)."""
    section = _section(spec)
    return dict(section.model_extra or {}) if section is not None else {}


def budget_of(spec: Any) -> float:
    """Seconds each study may spend (``studies.budget``, default :data:`DEFAULT_BUDGET`)."""
    section = _section(spec)
    value = getattr(section, "budget", None) if section is not None else None
    return DEFAULT_BUDGET if value is None else float(value)


def study_settings(spec: Any, name: str) -> Any:
    """The validated settings of study ``name`` in ``spec`` (its model), or None when the spec gives none."""
    study = STUDIES[name]
    raw = _raw(spec).get(name)
    if raw is None or study.settings is None:
        return None
    return _parse(study, raw)


def _parse(study: Study, raw: Any) -> Any:
    from pydantic import ValidationError

    from designkit.schema.loader import key_path, message

    path = f"studies.{study.name}"
    if study.settings is None:
        raise SpecError(path, "this study takes no settings")
    if not isinstance(raw, dict):
        raise SpecError(path, f"must be a mapping of the study's settings, got {type(raw).__name__}")
    try:
        return study.settings.model_validate(raw)
    except ValidationError as exc:
        err = exc.errors()[0]
        where = key_path(tuple(err.get("loc", ())))
        raise SpecError(f"{path}.{where}" if where else path, message(err)) from None


def validate(spec: Any, family: Any) -> None:
    """Refuse, with its key path, what a spec's ``studies`` section asks that cannot be done (module docstring).

    Raises
    ------
    SpecError
        An unknown study, a study's settings that are not valid, or a setting its family does not allow.
    """
    for name, raw in _raw(spec).items():
        study = STUDIES.get(name)
        if study is None:
            known = ", ".join(st.name for st in in_report_order() if st.settings is not None)
            raise SpecError(f"studies.{name}", f"unknown study; the studies with settings are {known}")
        settings = _parse(study, raw)
        if study.validate is not None:
            try:
                study.validate(settings, family, spec)
            except ValueError as exc:
                where, _, what = str(exc).partition(": ")
                raise SpecError(f"studies.{name}.{where}", what) from None


def run_studies(result: Any) -> tuple[StudyResult, ...]:
    """Every study that applies to ``result`` (a one-controller run, or a comparison), in report order.

    Each study runs its variants within the spec's studies budget (:func:`budget_of`) and says what it reduced
    to stay within it.
    """
    from designkit.families import family

    comparison = hasattr(result, "results") and hasattr(result, "labels")
    spec = result.loaded.spec
    fam = None if comparison else family(result.design.kind)
    asked = {} if comparison else _ASKED.get(result, {})
    out: list[StudyResult] = []
    for study in in_report_order():
        if study.name in asked:  # run already for a comparison study that cites it (study_of): the same result
            if asked[study.name] is not None:
                out.append(asked[study.name])
            continue
        if study.comparison != comparison or not study.applies(result, fam):
            continue
        done = _run_one(study, result, fam, spec, tuple(out), comparison)
        if done is not None:
            out.append(done)
    return tuple(out)


def _run_one(study: Study, result: Any, fam: Any, spec: Any, earlier: tuple[StudyResult, ...],
             comparison: bool) -> StudyResult | None:
    start = time.perf_counter()
    ctx = StudyContext(result, fam, study_settings(spec, study.name) if not comparison else None, budget_of(spec),
                       earlier)
    done = study.run(ctx)
    if done is not None and not done.seconds:
        import dataclasses

        done = dataclasses.replace(done, seconds=time.perf_counter() - start)
    return done


_ASKED: weakref.WeakKeyDictionary[Any, dict[str, StudyResult | None]] = weakref.WeakKeyDictionary()
"""One-controller run -> the studies :func:`study_of` ran on it (None: it does not apply), which
:func:`run_studies` then returns rather than running them again."""


def study_of(result: Any, name: str) -> StudyResult | None:
    """Study ``name`` of the one-controller run ``result`` (a comparison's member): the result its own studies carry
    (``result.studies``, its own report), run once -- alone when they have not been run, and then kept for them
    (:func:`run_studies` returns it rather than running it again).  None when the study does not apply.

    A study run alone sees no earlier study (:attr:`StudyContext.earlier` empty): this is for a study that cites
    none.
    """
    done = getattr(result, "__dict__", {}).get("studies")
    if done is not None:
        return next((st for st in done if st.name == name), None)
    asked = _ASKED.setdefault(result, {})
    if name not in asked:
        from designkit.families import family

        study = STUDIES[name]
        fam = family(result.design.kind)
        asked[name] = (_run_one(study, result, fam, result.loaded.spec, (), False)
                       if not study.comparison and study.applies(result, fam) else None)
    return asked[name]


@dataclass(frozen=True)
class StudyFix:
    """A study's recommendation proposed as a fix of a failing run: the spec change, in words, and the runs that
    passed every required check with it and around it (the study's own, not re-run)."""

    study: str
    text: str
    changes: tuple[tuple[str, Any], ...]
    checked: tuple[float, ...]


def study_fixes(result: Any, studies: tuple[StudyResult, ...]) -> tuple[StudyFix, ...]:
    """The recommendations of ``studies`` that change a spec setting, as fixes of ``result`` when a required check
    of it does not pass (none for a verified run)."""
    if all(c.passed is True for c in result.checks if c.required):
        return ()
    from designkit.display.numbers import fmt_number

    out = []
    for st in studies:
        for e in st.entries:
            if e.setting is None or e.recommended is None:
                continue
            path, value = e.setting
            rec = e.recommended
            out.append(StudyFix(st.name, f"Set {path} = {fmt_number(value, 4)}: the {st.title.lower()} ran it with "
                                f"every required check passing, as at each of the {len(rec.checked)} runs from "
                                f"{fmt_number(rec.low, 4)} to {fmt_number(rec.high, 4)} ({e.parameter}).",
                                ((path, value),), rec.checked))
    return tuple(out)
