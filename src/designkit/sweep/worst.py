"""The worst samples of a sweep, each written as a design spec that ``designkit synth`` re-runs.

A sample is ranked by its worst requirement margin over the requirement's limit (dimensionless; an
undefined metric ranks below every defined one), ties by sample index.  Its spec is the swept spec with
the sample's true plant from the start of the run (``simulation.plant_change`` at ``t = 0``: the controller
is designed on the spec's nominal plant and is not told, exactly as in the sweep), its initial position
(``simulation.initial_position``) and its noise seed (``simulation.noise.seed``), so the pipeline runs the
same loop the sweep scored.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["rank", "sample_changes", "worst_spec"]


def rank(normalized: np.ndarray, index: np.ndarray) -> np.ndarray:
    """Positions of the samples from the worst up: by the smallest normalized margin, then by sample index."""
    worst = np.min(normalized, axis=1) if normalized.size else np.zeros(index.size)
    return np.lexsort((index, worst))


def sample_changes(prep: Any, values: np.ndarray, seed: int) -> dict[str, Any]:
    """The spec changes that make the pipeline run sample ``values``: ``parameters`` (true-plant values that
    differ from the nominal plant's), ``initial_position`` (list, or None) and ``noise_seed`` (or None)."""
    from designkit.sweep.chunk import _inputs, initial_positions

    row = np.asarray(values, dtype=float).reshape(1, -1)
    P = _inputs(prep, row, np.array([max(int(seed), 0)]) if prep.space.noise else np.array([-1]))["parameters"][0]
    nominal = np.asarray(prep.plant.parameter_vector, dtype=float)
    params = {q.name: float(P[i]) for i, q in enumerate(prep.plant.parameters) if P[i] != nominal[i]}
    q0 = None
    if any(d.kind == "initial_position" for d in prep.space.dimensions):
        q0 = [float(v) for v in initial_positions(prep, row)[0]]
    return {"parameters": params, "initial_position": q0, "noise_seed": int(seed) if prep.space.noise else None}


def worst_spec(prep: Any, values: np.ndarray, seed: int, *, name: str, description: str) -> str:
    """The YAML text of a design spec running sample ``values`` (module docstring)."""
    import yaml

    doc = yaml.safe_load(prep.sweep.text)
    changes = sample_changes(prep, values, seed)
    doc["name"] = name[:100]
    doc["description"] = description
    sim = dict(doc.get("simulation") or {})
    if changes["parameters"]:
        sim["plant_change"] = {"time": 0.0, "values": changes["parameters"]}
    if changes["initial_position"] is not None:
        sim["initial_position"] = changes["initial_position"]
    if changes["noise_seed"] is not None:
        sim["noise"] = {**dict(sim.get("noise") or {}), "seed": changes["noise_seed"]}
    doc["simulation"] = sim
    return yaml.safe_dump(doc, sort_keys=False, allow_unicode=True, width=110)
