"""The confirming sweep: a Monte Carlo sample of ``plant.uncertainty`` run on the tuned spec by
:func:`designkit.sweep` (its own batched runs and margins), whose pass fraction the tuning result states beside the
box points the search ran."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["DEFAULT_SAMPLES", "Confirmation", "check_scheduler", "confirm"]

DEFAULT_SAMPLES = 64
"""Samples of the confirming sweep by default."""
_NOT_RUN = "not run: "


@dataclass(frozen=True)
class Confirmation:
    """What the confirming sweep of the tuned spec found.

    Parameters
    ----------
    samples : int
        Samples asked for (0 when the sweep was refused).
    seed : int
        The sweep's seed.
    passed : int
        Samples meeting every requirement.
    pass_fraction : float or None
        ``passed / samples`` (None when refused).
    confidence : tuple of float
        The pass fraction's two-sided 95 % Clopper--Pearson interval (empty when refused).
    worst : dict
        The worst sample: ``sample``, ``parameters`` (its plant values), ``margins`` (each requirement's margin in
        its unit, None undefined) and ``worst_normalized_margin`` (empty when refused or no sample).
    engine : str
        Where it ran, as the sweep reports it (``"this process"``, or ``"dask.distributed at <address>, <k>
        workers"``).
    seconds : float
        Wall time of the sweep (s).
    refused : str or None
        Why the sweep kernel refused the tuned spec (its one-line error), or, starting ``"not run: "``, why the sweep
        could not be run (a scheduler lost after the check); None when it ran.
    """

    samples: int
    seed: int
    passed: int = 0
    pass_fraction: float | None = None
    confidence: tuple[float, ...] = ()
    worst: dict[str, Any] = field(default_factory=dict)
    engine: str = "this process"
    seconds: float = 0.0
    refused: str | None = None

    @property
    def sentence(self) -> str:
        """One line for the report and the command line."""
        if self.refused is not None and self.refused.startswith(_NOT_RUN):
            return f"no confirming sweep: it could not be run ({self.refused[len(_NOT_RUN):]})"
        if self.refused is not None:
            return f"no confirming sweep: the sweep refuses the tuned spec ({self.refused})"
        lo, hi = self.confidence
        text = (f"{self.passed} of {self.samples} sampled plants pass every requirement (pass fraction "
                f"{self.pass_fraction:.3g}, 95 % interval [{lo:.3g}, {hi:.3g}]; seed {self.seed}, {self.engine}, "
                f"{self.seconds:.1f} s)")
        if self.worst:
            params = ", ".join(f"{k} = {v:.4g}" for k, v in self.worst["parameters"].items())
            text += f"; worst sample {self.worst['sample']} at {params or 'the nominal'}"
            if self.worst.get("worst_normalized_margin") is not None:
                text += f" (worst normalised margin {self.worst['worst_normalized_margin']:.3g})"
        return text

    def to_json(self) -> dict[str, Any]:
        """As JSON values."""
        return {"samples": self.samples, "seed": self.seed, "passed": self.passed,
                "pass_fraction": self.pass_fraction, "confidence": list(self.confidence), "worst": self.worst,
                "engine": self.engine, "seconds": round(self.seconds, 3), "refused": self.refused,
                "sentence": self.sentence}


def check_scheduler(scheduler: str | None) -> None:
    """Refuse, before anything runs, a ``--scheduler`` the sweep would refuse (the sweep's own reading and its
    5 s handshake probe, :mod:`designkit.sweep.scheduler`).

    Raises
    ------
    SpecError
        ``--scheduler``: not a tcp:// or tls:// address, or no Dask scheduler answering there.
    """
    if scheduler is None:
        return
    from designkit.sweep.scheduler import endpoint, probe

    probe(endpoint(scheduler))


def confirm(tuned: Any, *, samples: int = DEFAULT_SAMPLES, seed: int = 0, scheduler: str | None = None) -> Any:
    """Sweep ``tuned`` (a LoadedSpec with ``plant.uncertainty``) over its box with :func:`designkit.sweep`.

    Parameters
    ----------
    tuned : LoadedSpec
        The tuned spec.
    samples : int
        Samples of the sweep.
    seed : int
        The sweep's seed.
    scheduler : str, optional
        Address of a Dask scheduler to run the sweep on (checked beforehand by :func:`check_scheduler`); without
        it, the sweep runs in this process.

    Returns
    -------
    Confirmation
        With ``refused`` set when the sweep's kernel refuses the spec (an ``implementation`` section, a family or
        plant it does not carry): the sweep's one-line error, instead of raising.
    """
    import time

    from designkit.errors import DesignkitError
    from designkit.sweep.api import sweep

    start = time.monotonic()
    engine = "process" if scheduler is None else "dask"
    try:
        res = sweep(tuned, samples, seed=seed, scheduler=scheduler, engine=engine, falsification=False,
                    report=False)
    except DesignkitError as exc:
        reason = (f"{exc.path}: {exc.message}" if exc.path else exc.message) or str(exc)
        return Confirmation(samples=0, seed=seed, engine=scheduler or "this process", refused=reason,
                            seconds=time.monotonic() - start)
    except Exception as exc:  # noqa: BLE001 -- a sweep that cannot be run (a scheduler lost mid-way) is stated
        reason = f"{_NOT_RUN}{type(exc).__name__}: {str(exc)[:300]}"
        return Confirmation(samples=0, seed=seed, engine=scheduler or "this process", refused=reason,
                            seconds=time.monotonic() - start)
    worst: dict[str, Any] = {}
    if res.worst:
        w = res.worst[0].to_json()
        worst = {k: w[k] for k in ("sample", "parameters", "margins", "worst_normalized_margin")}
    return Confirmation(samples=res.samples, seed=seed, passed=res.n_passed, pass_fraction=res.pass_fraction,
                        confidence=tuple(float(c) for c in np.asarray(res.confidence, dtype=float)), worst=worst,
                        engine=_where(res.engine), seconds=time.monotonic() - start, refused=None)


def _where(engine: dict[str, Any]) -> str:
    """The sweep's own statement of where it ran, in words."""
    if "scheduler" not in engine:
        return str(engine.get("engine", "this process"))
    k = int(engine.get("workers", 0))
    return f"{engine['engine']} at {engine['scheduler']}, {k} worker{'' if k == 1 else 's'}"
