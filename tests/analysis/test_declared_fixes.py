"""Fixes whose owner declares them as changes of the spec (:class:`~designkit.synthesis.spec_change.SpecChange`):
the owner's answer normalized, the declared changes re-run instead of the sentence being read, and a finding
carrying them."""

from __future__ import annotations

from types import SimpleNamespace

from designkit.analysis.diagnosis.remedies import propose
from designkit.synthesis.spec_change import SpecChange, explanation

SPEC = "name: x\nplant: {kind: link, Km: 2, tau: 0.5}\ncontroller: {kind: sliding_mode, M: 1.0}\n"


def test_an_owner_answers_two_or_three_parts():
    change = SpecChange("a relay of 2 N·m", [("controller.M", 2.0)])
    assert change.changes == (("controller.M", 2.0),)  # frozen as a tuple
    assert explanation(("why", "what")) == ("why", "what", ())
    assert explanation(("why", "what", [change])) == ("why", "what", (change,))
    assert explanation(None) == explanation(()) == ("", "", ())


def test_declared_changes_replace_the_reading_of_the_sentence():
    result = SimpleNamespace(loaded=SimpleNamespace(text=SPEC))
    sentence = "Give M >= 3.000 N·m."
    ((_, read),) = propose(result, [sentence])
    assert [r.changes for r in read] == [(("controller.M", 3.0005),)]  # the recognizer's reading
    declared = (SpecChange("a relay of 4 N·m", (("controller.M", 4.0),)),
                SpecChange("M left to the design", (("controller.M", None),)))
    ((_, owned),) = propose(result, [sentence], {sentence: declared})
    assert [r.changes for r in owned] == [(("controller.M", 4.0),), (("controller.M", None),)]
    assert [r.title for r in owned] == ["a relay of 4 N·m", "M left to the design"]
    assert len({r.kind for r in owned}) == 2 and all(r.source == sentence for r in owned)  # each re-run
    ((_, other),) = propose(result, [sentence], {"Another sentence.": declared})
    assert other == read
