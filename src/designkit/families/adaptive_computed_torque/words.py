"""The adapted parameters and their units in words, for notes, reports and figures."""

from __future__ import annotations

__all__ = ["describe", "unit_text"]

_WORDS = {"m": "mass of link {}", "mcx": "first moment x of link {}", "mcy": "first moment y of link {}",
          "mcz": "first moment z of link {}", "fv": "viscous friction of joint {}",
          "fc": "Coulomb friction of joint {}", "Ia": "rotor inertia of joint {}"}
_UNIT_TEXT = {"kg": "kg", "kg*m": "kg·m", "kg*m^2": "kg·m²", "N*m*s/rad": "N·m·s/rad", "N*m": "N·m"}


def describe(name: str) -> str:
    """A regressor parameter in words: ``m2`` -> ``"m2, mass of link 2"``, ``fv1`` -> ``"fv1, viscous friction of
    joint 1"``."""
    stem = name.rstrip("0123456789")
    index = name[len(stem):]
    if stem in _WORDS:
        return f"{name}, {_WORDS[stem].format(index)}"
    if stem.startswith("I"):
        return f"{name}, inertia {stem[1:]} of link {index} about its frame origin"
    return name


def unit_text(unit: str) -> str:
    """A unit typeset (``kg*m^2`` -> ``kg·m²``)."""
    return _UNIT_TEXT.get(unit, unit)
