"""What lab experiment 3 measures on every run, the same way for every controller: the command's chattering and the
step's steady-state error, as :class:`~designkit.synthesis.knobs.Metric` values of a run (next to the family's own
metrics and the generic ones, :func:`designkit.studies.core.metrics.metrics_of`).

* **chattering**: the command's variation per second (:data:`designkit.synthesis.knobs.COMMAND_VARIATION`, the total
  variation ``sum |u[k+1] - u[k]|`` over the run's length, the measure the switching families declare) and its
  reversals per second (sign changes of ``u[k+1] - u[k]``, steps below :data:`REVERSAL_TOL` ``max |u|`` ignored)
  (:func:`chattering`);
* **steady-state error**: ``|x - xD|`` of the step at the end of the run
  (:func:`designkit.verification.time_domain.response_metrics`), in the controlled position's unit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.synthesis.knobs import COMMAND_VARIATION, Metric

__all__ = ["MEASURES", "REVERSAL_TOL", "Chatter", "chattering", "measures_of"]

REVERSAL_TOL = 1e-9
"""A command step below this fraction of ``max |u|`` is not a reversal."""


@dataclass(frozen=True)
class Chatter:
    """Chattering of a run's command: ``total_variation`` (the command's unit), ``reversals`` and their ``rate``
    (1/s), over a run of ``duration`` (s)."""

    total_variation: float
    reversals: int
    rate: float
    duration: float = 1.0

    @property
    def variation(self) -> float:
        """The total variation per second (the command's unit per s): :data:`~designkit.synthesis.knobs.
        COMMAND_VARIATION` of the run."""
        return self.total_variation / self.duration if self.duration > 0 else math.inf


def chattering(sim: Any) -> Chatter:
    """:class:`Chatter` of ``sim.u_command[:, 0]`` (module docstring); ``inf`` for a command that is not finite."""
    t = np.asarray(sim.time, float)
    u = np.asarray(sim.u_command, float).reshape(len(t), -1)[:, 0]
    duration = float(t[-1] - t[0])
    if not np.all(np.isfinite(u)):
        return Chatter(math.inf, 0, math.inf, duration)
    du = np.diff(u)
    tv = float(np.sum(np.abs(du)))
    big = du[np.abs(du) > REVERSAL_TOL * max(float(np.max(np.abs(u))), 1e-300)]
    reversals = int(np.count_nonzero(np.sign(big[1:]) != np.sign(big[:-1])))
    return Chatter(tv, reversals, reversals / duration, duration)


def _steady(run: Any) -> float | None:
    from designkit.verification.time_domain import response_metrics

    sim = run.simulation
    if sim is None or sim.kind != "step":
        return None
    req = run.loaded.spec.requirements
    return response_metrics(sim, settling_band=req.settling_band if req is not None else 0.02).steady_state_error


MEASURES = (
    Metric("steady_state_error", "steady-state error", "rad", _steady, "|x − xD| of the step at the end of the run"),
    COMMAND_VARIATION,
    Metric("command_reversals", "reversals of the command per second", "1/s", lambda run: chattering(run.simulation)
           .rate if run.simulation is not None else None, "sign changes of u[k+1] − u[k] per second"),
)
"""The experiment's measures (module docstring): the same for every controller, added to its family's own."""


def measures_of(run: Any, family: Any) -> tuple[Metric, ...]:
    """The family's metrics and the generic ones (:func:`~designkit.studies.core.metrics.metrics_of`), then
    :data:`MEASURES`."""
    from designkit.studies.core.metrics import metrics_of

    own = metrics_of(run, family)
    keys = {m.key for m in own}
    return own + tuple(m for m in MEASURES if m.key not in keys)
