"""A spec with one setting changed, and a design with other gains: the variants a fix or a study runs.

A spec variant is the spec's own YAML with key paths set, validated by the same loader as a file
(:func:`changed_spec`), so the family's rules and the key paths of its messages hold for it.  A gain variant is
the family's design with other values of its gains and everything that depends on them rebuilt
(:func:`designkit.synthesis.variation.with_gains`, or the family's own ``regain`` where the design has more
structure, such as per-joint loops).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = ["changed_spec", "knob_value", "spec_value", "vary", "vary_plant", "vary_scenario", "vary_spec"]


def _set(data: dict[str, Any], path: str, value: Any) -> None:
    keys = path.split(".")
    node = data
    for key in keys[:-1]:
        child = node.get(key)
        if not isinstance(child, dict):
            child = node[key] = {}
        node = child
    if value is None:
        node.pop(keys[-1], None)
    else:
        node[keys[-1]] = value


def changed_spec(loaded: Any, changes: Sequence[tuple[str, Any]]) -> Any:
    """The spec of ``loaded`` with ``changes`` (key path, value; None removes the key), validated as a file is.

    Raises
    ------
    SpecError
        The changed spec is not valid (its message names the key path).
    """
    import yaml

    from designkit.schema.loader import parse_spec

    data = _given(loaded)
    for path, value in changes:
        _set(data, path, _plain(value))
    return parse_spec(yaml.safe_dump(data, sort_keys=False, allow_unicode=True), path=loaded.path)


def _given(loaded: Any) -> dict[str, Any]:
    """What the spec of ``loaded`` gives, as data: its YAML, except for a spec built in Python (a comparison's member),
    whose text is its canonical JSON (every default written out): there, only the fields it was given
    (``exclude_unset``), since a default written out is not the same spec (``numerics.integrator`` given chooses the
    integrator, left out lets the loop's poles choose it)."""
    import yaml

    from designkit.schema.loader import LoadedSpec

    if loaded.text == LoadedSpec.from_spec(loaded.spec).text:
        return loaded.spec.model_dump(mode="json", exclude_unset=True)
    return yaml.safe_load(loaded.text)


def _plain(value: Any) -> Any:
    """JSON types for YAML: arrays as lists of floats, NumPy scalars as floats."""
    if isinstance(value, np.ndarray):
        return [_plain(v) for v in value.ravel().tolist()]
    if isinstance(value, np.generic):
        return _plain(value.item())
    if isinstance(value, complex):  # a pole: the spec's complex string, at full precision
        return float(value.real) if value.imag == 0 else f"{value.real!r}{value.imag:+.17g}j"
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    return value


def spec_value(spec: Any, path: str) -> Any:
    """The value at key path ``path`` of a validated spec (None when absent)."""
    node: Any = spec
    for key in path.split("."):
        node = node.get(key) if isinstance(node, dict) else getattr(node, key, None)
        if node is None:
            return None
    return node


def knob_value(knob: Any, spec: Any, design: Any) -> Any:
    """The value of ``knob`` in use: the design's gain, the spec's setting, or what the family computed for it
    (``knob.current``) when the spec leaves it out.  A float, or an array for a per-joint value."""
    if knob.gain:
        value = design.gains[knob.gain]
    else:
        value = spec_value(spec, knob.path)
        if value is None and knob.current is not None:
            value = knob.current(design)
    if value is None:
        return None
    arr = np.asarray(value)
    arr = arr.astype(complex) if np.iscomplexobj(arr) and np.any(np.imag(arr) != 0) else np.real(arr).astype(float)
    return arr.item() if arr.ndim == 0 else arr


def vary(result: Any, knob: Any, value: Any) -> Any:
    """Run ``result``'s spec with ``knob`` set to ``value`` through the family's own run
    (:func:`designkit.runner.run.run_spec`): its trials, its adaptation, its held step, its checks.

    Parameters
    ----------
    result : PipelineResult or Run
        The run varied (its ``loaded`` spec and true ``plant``).
    knob : Knob
        A knob of the run's family.
    value : float or array
        The knob's new value (a spec setting's value; for a gain, the gain's value).

    Returns
    -------
    Run
    """
    from designkit.families import family
    from designkit.runner.run import run_spec
    from designkit.synthesis.variation import with_gains

    loaded = result.loaded
    plant = result.plant if result.plant is not None else result.design.plant
    if knob.path:
        return run_spec(changed_spec(loaded, [(knob.path, value)]), plant=plant)
    fam = family(result.design.kind)
    anti_windup = loaded.spec.simulation.anti_windup

    def adjust(design: Any) -> Any:
        gains = design.gains.replace(**{knob.gain: value})
        if fam.regain is not None:
            return fam.regain(design, gains, anti_windup)
        return with_gains(design, gains, fam.law, anti_windup)

    return run_spec(loaded, plant=plant, adjust=adjust)


def vary_spec(result: Any, changes: Sequence[tuple[str, Any]]) -> Any:
    """Run ``result``'s spec with the key paths of ``changes`` set (a scenario setting: a sampling period, a delay,
    an actuator limit) through the family's own run; the true plant unchanged."""
    from designkit.runner.run import run_spec

    plant = result.plant if result.plant is not None else result.design.plant
    return run_spec(changed_spec(result.loaded, changes), plant=plant)


def vary_scenario(result: Any, changes: Sequence[tuple[str, Any]]) -> Any:
    """Run ``result``'s own design in its spec's scenario with the key paths of ``changes`` set (a load removed):
    what the loop as designed does there, not what a design for that scenario would do (a design sized from the
    load keeps its size); judged by the family's checks, the true plant unchanged."""
    from designkit.runner.run import run_spec

    plant = result.plant if result.plant is not None else result.design.plant
    return run_spec(changed_spec(result.loaded, changes), plant=plant, design=result.design)


def vary_plant(result: Any, values: dict[str, float]) -> Any:
    """Run ``result``'s spec on its true plant with the parameters ``values`` (name -> value, SI) changed, the
    controller designed as before: for the plant the spec describes, not told of the change."""
    from designkit.runner.run import run_spec

    plant = result.plant if result.plant is not None else result.design.plant
    designed_for = None if result.plant is None else result.plant
    return run_spec(result.loaded, plant=designed_for, actual=plant.with_params(**values))
