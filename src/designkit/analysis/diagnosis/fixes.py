"""Every fix a diagnosis proposes, re-simulated: :func:`check_fixes` and the :class:`ProposedFix` it returns.

For each distinct fix sentence of the findings (in finding order), the remedies its owner declared as changes
of the spec, or else the remedies it reads as (:func:`~designkit.analysis.diagnosis.remedies.propose`), are
re-run through the pipeline
(:func:`~designkit.analysis.diagnosis.resimulate.try_remedy`), at most
:data:`~designkit.analysis.diagnosis.resimulate.MAX_FIX_RUNS` in all.  A remedy whose re-run passes every
required check is a fix; one that does not is "tried, and not a fix", with what it still fails measured.
When the diagnosis' root cause says the settling requirement cannot be met with the actuator, a remedy that
then fails only the settling time is re-run once more with that requirement relaxed to the settling time it
reached (rounded up to two digits): a fix that says which requirement it changes.  A remedy of the same kind
(the same recognizer) changing the same fields of the spec as a fix that already passed (K1 raised by a
smaller factor for a weaker requirement) is not re-run, and said so.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

from designkit.analysis.diagnosis.remedies import Remedy, propose, round_up
from designkit.analysis.diagnosis.resimulate import MAX_FIX_RUNS, FixTrial, try_remedy
from designkit.display.numbers import quantity

__all__ = ["ProposedFix", "check_fixes"]


@dataclass(frozen=True)
class ProposedFix:
    """A fix sentence of the diagnosis and its re-runs.

    Parameters
    ----------
    sentence : str
        The sentence as the finding states it.
    trials : tuple of FixTrial
        Its remedies re-run, in order (empty: see ``note``).
    note : str
        Why it was not re-run (no spec change reads from it, or the bound on the re-runs was reached).
    """

    sentence: str
    trials: tuple[FixTrial, ...]
    note: str = ""


def _relaxed(trial: FixTrial) -> Remedy | None:
    """The remedy with the settling requirement set to the settling time its re-run reached, when that is all
    it fails."""
    failing = [o for o in trial.outcomes if o.status != "PASS"]
    if trial.error or len(failing) != 1 or failing[0].name != "settling_time" or failing[0].value is None:
        return None
    value = round_up(failing[0].value, 2)
    r = trial.remedy
    return replace(r, title=f"{r.title}, with the settling-time requirement relaxed to {quantity(value, 's')} "
                            f"(this design settles in {quantity(failing[0].value, 's')}; {failing[0].requirement} "
                            "is beyond this actuator, see the root cause)",
                   changes=(*r.changes, ("requirements.settling_time", value)), requirement=True)


def check_fixes(result: Any, sentences: Sequence[str], settling_infeasible: bool = False,
                budget: int = MAX_FIX_RUNS, declared: Mapping[str, Sequence[Any]] | None = None
                ) -> tuple[ProposedFix, ...]:
    """Re-run the remedies of every fix sentence (see the module docstring).

    Parameters
    ----------
    result : designkit.pipeline.PipelineResult
    sentences : sequence of str
        The distinct fix sentences of the findings.
    settling_infeasible : bool
        The root cause says no controller meets the settling requirement with this actuator.
    budget : int
        At most this many re-runs.
    declared : mapping of str to sequence of SpecChange, optional
        Sentences whose owner declared the changes of the spec that realize them
        (:class:`~designkit.synthesis.spec_change.SpecChange`): those are re-run, and the sentence is not read.
    """
    out = []
    left = budget
    seen: dict[tuple[tuple[str, str], ...], FixTrial] = {}
    passed_fields: set[tuple[str, frozenset[str]]] = set()
    for sentence, remedies in propose(result, sentences, declared):
        if not remedies:
            out.append(ProposedFix(sentence, (), "not re-simulated: no change of the spec is read from it"))
            continue
        trials: list[FixTrial] = []
        skipped = same = 0
        for remedy in remedies:
            key = tuple((p, repr(v)) for p, v in remedy.changes)
            fields = (remedy.kind, frozenset(p for p, _ in remedy.changes))
            if key in seen:  # the same change proposed by another sentence: its re-run, not a second one
                trials.append(seen[key])
                continue
            if fields in passed_fields:  # an earlier fix of the same kind changing the same fields already passes
                same += 1
                continue
            if left <= 0:
                skipped += 1
                continue
            left -= 1
            trial = try_remedy(result, remedy)
            seen[key] = trial
            trials.append(trial)
            if trial.passed:
                passed_fields.add(fields)
            follow = _relaxed(trial) if settling_infeasible and not trial.passed else None
            if follow is not None and left > 0:
                left -= 1
                trials.append(try_remedy(result, follow))
        notes = [f"{skipped} more not re-simulated: at most {budget} re-runs per report"] if skipped else []
        if same:
            notes.append("not re-simulated: a numbered fix of the same kind, changing the same fields of the spec, "
                         "already passes")
        note = "; ".join(notes)
        out.append(ProposedFix(sentence, tuple(trials), note))
    return tuple(out)
