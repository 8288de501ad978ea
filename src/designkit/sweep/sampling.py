"""What a sweep samples, and the samples themselves, each drawn from its own seeded stream.

The sample space is a box: the intervals of ``plant.uncertainty`` (and ``sweep.parameters``), the
initial position of each joint (``sweep.initial_position``) and a payload mass (``sweep.payload``).  Sample
``i`` of a sweep with seed ``S`` takes its uniform numbers from ``numpy.random.default_rng([S, i])``, so a
sample does not depend on how the sweep is split into chunks or workers.  The distributions:

* ``uniform``: ``low + u (high - low)``;
* ``normal``: centred on the box, the half-width ``cut`` standard deviations, truncated at the box's
  ends (``scipy.stats.truncnorm``'s quantile of ``u``);
* ``corners``: sample ``i`` is corner ``i mod 2^d`` of the box (bit ``k`` of ``i`` says low or high in
  dimension ``k``): every corner once per ``2^d`` samples.

With ``sweep.noise`` each sample also draws its own measurement-noise seed (0 to 2^32 - 1) from its stream.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.errors import SpecError

__all__ = ["Dimension", "SampleSpace", "sample_space"]


@dataclass(frozen=True)
class Dimension:
    """One sampled quantity.

    Parameters
    ----------
    name : str
        Column name in the sample table (``m2``, ``q0_1``, ``payload``).
    kind : str
        ``"parameter"``, ``"initial_position"`` or ``"payload"``.
    key : str or int
        The plant parameter's name, or the 0-based joint.
    low, high : float
        The interval (SI units).
    unit : str
    path : str
        The spec key path it comes from.
    """

    name: str
    kind: str
    key: Any
    low: float
    high: float
    unit: str
    path: str


@dataclass(frozen=True)
class SampleSpace:
    """The box a sweep samples, and how (module docstring)."""

    dimensions: tuple[Dimension, ...]
    distribution: str = "uniform"
    cut: float = 3.0
    noise: bool = False
    payload_link: int | None = None

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(d.name for d in self.dimensions)

    @property
    def low(self) -> np.ndarray:
        return np.array([d.low for d in self.dimensions], dtype=float)

    @property
    def high(self) -> np.ndarray:
        return np.array([d.high for d in self.dimensions], dtype=float)

    def draw(self, seed: int, indices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The samples of ``indices``: values ``(len, d)`` and noise seeds ``(len,)`` (-1 without ``noise``)."""
        indices = np.asarray(indices, dtype=np.int64)
        d = len(self.dimensions)
        u = np.empty((indices.size, d))
        seeds = np.full(indices.size, -1, dtype=np.int64)
        for k, i in enumerate(indices):
            rng = np.random.default_rng([int(seed), int(i)])
            u[k] = rng.random(d)
            if self.noise:
                seeds[k] = int(rng.integers(0, 2**32 - 1))
        return self.values(u, indices), seeds

    def values(self, u: np.ndarray, indices: np.ndarray | None = None) -> np.ndarray:
        """Map uniform numbers ``u`` in [0, 1) (``(len, d)``) to the box under the distribution."""
        lo, hi = self.low, self.high
        if self.distribution == "corners":
            idx = np.arange(len(u)) if indices is None else np.asarray(indices, dtype=np.int64)
            bits = (idx[:, None] >> np.arange(lo.size)[None, :]) & 1
            return np.where(bits == 1, hi, lo)
        if self.distribution == "normal":
            from scipy.stats import truncnorm

            z = truncnorm.ppf(u, -self.cut, self.cut)
            return 0.5 * (lo + hi) + z * (0.5 * (hi - lo) / self.cut)
        return lo + u * (hi - lo)


def check_box(spec: Any, plant: Any, parameters: dict[str, Any], path: str = "sweep.parameters",
              ) -> dict[str, tuple[float, float]]:
    """Check the intervals ``parameters`` exactly as ``plant.uncertainty``'s are checked: the spec format's
    :class:`~designkit.spec.plants.Uncertainty` (finite, ordered, within the range of the plant section's field of
    that name), then the model's own rule for each end (:func:`~designkit.spec.plant_builder.check_uncertainty`:
    a time constant or gain above zero, a mass not negative...), one source of truth for both.

    Returns
    -------
    dict
        Name -> ``(low, high)``, in the parameter's SI unit.

    Raises
    ------
    SpecError
        ``<path>.<name>`` with the message ``plant.uncertainty.<name>`` would get.
    """
    from pydantic import ValidationError

    from designkit.spec.plant_builder import check_uncertainty
    from designkit.spec.plants import Uncertainty

    try:
        box = Uncertainty.model_validate(dict(parameters))
        box.check_ranges(type(spec.plant))
    except (ValidationError, ValueError) as exc:
        text = exc.errors()[0]["msg"].removeprefix("Value error, ") if isinstance(exc, ValidationError) else str(exc)
        name, _, reason = text.partition(": ")
        name = name.removeprefix("uncertainty.")
        if name not in parameters or not reason:
            raise SpecError(path, text) from None
        raise SpecError(f"{path}.{name}", reason) from None
    check_uncertainty(plant, box, path)
    return box.intervals


def sample_space(loaded_sweep: Any, plant: Any) -> SampleSpace:
    """The :class:`SampleSpace` of a spec and its sweep section on its (nominal) plant.

    Raises
    ------
    SpecError
        ``sweep.parameters.<name>`` or ``plant.uncertainty.<name>`` naming no parameter of the plant;
        ``sweep.initial_position`` with the wrong number of joints; ``sweep.payload`` on a plant without
        link masses; ``sweep.noise`` without ``simulation.noise``; ``plant.uncertainty`` when there is
        nothing to sample.
    """
    spec, section = loaded_sweep.loaded.spec, loaded_sweep.section
    names = [q.name for q in plant.parameters]
    units = {q.name: getattr(q, "unit", "") for q in plant.parameters}
    intervals: dict[str, tuple[float, float, str]] = {}
    unc = getattr(spec.plant, "uncertainty", None)
    for name, (lo, hi) in (unc.intervals.items() if unc is not None else ()):
        if name not in names:
            raise SpecError(f"plant.uncertainty.{name}", f"the plant has no parameter {name!r} (it has "
                            f"{', '.join(names)})")
        intervals[name] = (lo, hi, f"plant.uncertainty.{name}")
    for name in section.parameters:
        if name not in names:
            raise SpecError(f"sweep.parameters.{name}", f"the plant has no parameter {name!r} (it has "
                            f"{', '.join(names) or 'none'})")
    if section.parameters:
        for name, (lo, hi) in check_box(spec, plant, section.parameters).items():
            intervals[name] = (lo, hi, f"sweep.parameters.{name}")
    if spec.simulation.plant_change is not None:
        raise SpecError("simulation.plant_change", "a sweep sets the true plant's parameters from the start of each "
                        "run (that is how its worst cases are written); remove simulation.plant_change")
    dims = [Dimension(n, "parameter", n, lo, hi, units.get(n, ""), path) for n, (lo, hi, path) in intervals.items()
            if hi > lo]
    if section.initial_position is not None:
        n = len(plant.positions)
        if len(section.initial_position) != n:
            raise SpecError("sweep.initial_position", f"needs one interval per joint ({n}), got "
                            f"{len(section.initial_position)}")
        dims += [Dimension(f"q0_{j + 1}", "initial_position", j, float(lo), float(hi), "rad",
                           f"sweep.initial_position[{j}]") for j, (lo, hi) in enumerate(section.initial_position)
                 if hi > lo]
    link = None
    if section.payload is not None:
        masses = getattr(plant, "link_masses", ())
        link = section.payload.link or len(masses)
        if not masses or link > len(masses) or masses[link - 1] is None:
            raise SpecError("sweep.payload.link" if masses else "sweep.payload",
                            "this plant has no link mass parameter to carry a payload" if not masses else
                            f"link {link} has no mass parameter (links 1..{len(masses)})")
        lo, hi = section.payload.mass
        if hi > lo:
            dims.append(Dimension("payload", "payload", masses[link - 1], float(lo), float(hi), "kg",
                                  "sweep.payload.mass"))
    if section.noise and spec.simulation.noise is None:
        raise SpecError("sweep.noise", "needs simulation.noise (its std) to draw a noise seed per sample")
    if not dims and not section.noise:
        raise SpecError("plant.uncertainty", "nothing to sample: give plant.uncertainty intervals (or a sweep: "
                        "section with parameters, initial_position, payload or noise) of nonzero width")
    return SampleSpace(dimensions=tuple(dims), distribution=section.distribution, cut=float(section.cut),
                       noise=bool(section.noise), payload_link=link)
