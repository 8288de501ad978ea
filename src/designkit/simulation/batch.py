"""Many runs of one built closed loop at once: the compiled step mapped over samples.

A :class:`~designkit.simulation.run.Simulator` holds one integration step ``sim_step: (z, w) -> (z_next,
record)`` whose per-step input ``w`` carries the true plant's parameters (:mod:`designkit.simulation.step`).
:func:`batch_simulator` maps that step over ``B`` samples (``Function.map``: one column of ``z`` and ``w``
per sample, the same arithmetic for every column) and rolls the mapped step over time with
``Function.mapaccum``, compiled to C like the single run (:func:`designkit.models.codegen.compile_function`,
the single run's flags: a sample's numbers do not depend on which batch, or which column, it ran in).

What varies per sample: the true plant's parameter vector (held over the run), the augmented initial
state (another initial position, solved at rest like the single run), the measurement noise (each
sample its own seeded draw, generated exactly as the single run draws it) and the reference (when the
initial position changes a trajectory's start).  Everything else is the simulator's.

Only what the time-domain requirements read is kept: the tracked positions, the commanded and the
applied control, per sample and step (``B * N * (n + 2 nu)`` numbers; the augmented state and the
other records are dropped chunk by chunk, so the memory is bounded by the batch, not by the sweep).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from designkit.simulation.step import layout

__all__ = ["STEPS_PER_CALL", "BatchRecords", "BatchSimulator", "batch_simulator", "noise_rows"]

STEPS_PER_CALL = 100
"""Steps of the mapped loop per ``mapaccum`` evaluation (the records of one call are ``B * 100`` columns)."""


@dataclass(frozen=True, eq=False)
class BatchRecords:
    """The kept records of ``B`` runs.

    Parameters
    ----------
    time : ndarray, shape (N,)
        Instants (s), shared.
    desired : ndarray, shape (B, N, n)
        The reference positions ``xD`` of each run (rad, or m for a task-space motion).
    tracked : ndarray, shape (B, N, n)
        The tracked positions (joint positions, or the task-space coordinates of a motion).
    u_command, u_applied : ndarray, shape (B, N, nu)
        Commanded and applied control (N*m).
    failures : tuple of str
        Per run, the integrator's failure (empty when it ran through); the records are NaN from there.
    """

    time: np.ndarray
    desired: np.ndarray
    tracked: np.ndarray
    u_command: np.ndarray
    u_applied: np.ndarray
    failures: tuple[str, ...] = field(default_factory=tuple)

    @property
    def size(self) -> int:
        """Number of runs ``B``."""
        return int(self.tracked.shape[0])


def noise_rows(std: np.ndarray, seed: int, n_steps: int) -> np.ndarray:
    """The measurement noise ``(nx, N)`` of a run with ``simulation.noise: {std, seed}``: one Gaussian draw per
    step and state from ``numpy.random.default_rng(seed)``, scaled per state (the single run's draw)."""
    rng = np.random.default_rng(seed)
    return rng.normal(0.0, 1.0, size=(n_steps, std.size)).T * std[:, None]


@dataclass(frozen=True, eq=False)
class BatchSimulator:
    """A simulator's step mapped over ``batch`` samples and rolled over time (:func:`batch_simulator`).

    Parameters
    ----------
    simulator : Simulator
        The single run it is built from (inputs, initial state, plant, law).
    batch : int
        Samples per evaluation ``B``; a call with fewer runs pads with copies of the last.
    accumulated : casadi.Function
        ``mapaccum`` over :data:`STEPS_PER_CALL` steps of ``sim_step.map(B)``, compiled when possible.
    compiled : dict
        Whether it was compiled, and why not.
    """

    simulator: Any
    batch: int
    accumulated: ca.Function
    compiled: dict[str, Any]

    @property
    def adaptive(self) -> bool:
        """True when the simulator integrates with its compiled adaptive pair (``Simulator.dopri5``): each run is
        then one call of that integrator (its steps are its own, so runs are not mapped column by column)."""
        return getattr(self.simulator, "dopri5", None) is not None

    @property
    def n_steps(self) -> int:
        """Steps per run ``N``."""
        return int(self.simulator.time.size)

    def run(self, parameters: np.ndarray, *, z0: np.ndarray | None = None, noise: np.ndarray | None = None,
            references: Sequence[Any] | None = None) -> BatchRecords:
        """Run ``B <= batch`` samples.

        Parameters
        ----------
        parameters : ndarray, shape (B, np)
            Each run's true-plant parameter vector (the plant's order, SI units), held over the run.
        z0 : ndarray, shape (B, nz), optional
            Each run's augmented initial state (default the simulator's).
        noise : ndarray, shape (B, nx, N), optional
            Each run's measurement noise (default the simulator's).
        references : sequence of Reference, optional
            Each run's reference (default the simulator's, shared).

        Returns
        -------
        BatchRecords
        """
        sim = self.simulator
        P = np.atleast_2d(np.asarray(parameters, dtype=float))
        b = P.shape[0]
        if not 1 <= b <= self.batch:
            raise ValueError(f"a batch runs 1 to {self.batch} samples, got {b}")
        B, N, nw = self.batch, self.n_steps, sim.inputs.shape[0]
        nz, nrec = sim.step.size1_in(0), sim.step.size1_out(1)
        pad = np.r_[np.arange(b), np.full(B - b, b - 1)].astype(int)
        P = P[pad]
        Z = np.tile(np.asarray(sim.z0, dtype=float), (B, 1)) if z0 is None else np.asarray(z0, dtype=float)[pad]
        noise = None if noise is None else np.asarray(noise, dtype=float)[pad]
        refs = None if references is None else [references[i] for i in pad]
        if self.adaptive:
            return self._one_by_one(P[:b], Z[:b], noise, refs, None)
        p, law = sim.plant, sim.law
        L = layout(p, law, _NoElement, 0)
        cuts = np.cumsum([0, *L.record_sizes])
        pos_rows = [int(cuts[0]) + k for k in p.positions]
        uc_rows = np.arange(cuts[2], cuts[3])
        ua_rows = np.arange(cuts[3], cuts[4])
        n_ref = 3 * L.n
        noise_at = 9 * L.n
        npar = L.np_
        m = STEPS_PER_CALL
        steps = -(-N // m) * m
        inputs = np.concatenate([sim.inputs, np.repeat(sim.inputs[:, -1:], steps - N, axis=1)], axis=1)
        t_pad = np.concatenate([sim.time, sim.time[-1] + sim.settings["dt"] * np.arange(1, steps - N + 1)])
        keep = np.empty((steps, B, len(pos_rows) + 2 * L.nu))
        rows = np.r_[pos_rows, uc_rows, ua_rows].astype(int)
        buf, evaluate = self.accumulated.buffer()
        z = np.ascontiguousarray(Z).ravel()
        z_out = np.empty(nz * m * B)
        rec = np.empty(nrec * m * B)
        failures = [""] * B
        for j in range(steps // m):
            sl = slice(j * m, (j + 1) * m)
            W = np.repeat(inputs[:, sl].T[:, None, :], B, axis=1)  # (m, B, nw)
            if npar:
                W[:, :, nw - npar:] = P[None, :, :]
            if noise is not None:
                chunk = np.concatenate([noise[:, :, sl.start:min(sl.stop, N)],
                                        np.repeat(noise[:, :, -1:], max(0, sl.stop - N), axis=2)], axis=2)
                W[:, :, noise_at:noise_at + L.nx] = chunk.transpose(2, 0, 1)
            if refs is not None:
                W[:, :, :3 * n_ref] = _reference_rows(refs, t_pad[sl], sim.settings["dt"])
            w = np.ascontiguousarray(W).ravel()
            buf.set_arg(0, memoryview(z))
            buf.set_arg(1, memoryview(w))
            buf.set_res(0, memoryview(z_out))
            buf.set_res(1, memoryview(rec))
            try:
                evaluate()
            except RuntimeError as exc:  # CVODES gave up on some run: finish the batch run by run
                return self._one_by_one(P[:b], Z[:b], noise, refs, exc)
            keep[sl] = rec.reshape(m, B, nrec)[:, :, rows]
            z = z_out[-nz * B:].copy()
        keep = keep[:N].transpose(1, 0, 2)[:b]
        npos = len(pos_rows)
        tracked = keep[:, :, :npos]
        if sim.motion is not None:
            from designkit.simulation.motion import tracked_outputs

            tracked = np.stack([tracked_outputs(sim.motion, q) for q in tracked])
        desired = self._desired(refs, b)
        return BatchRecords(time=sim.time, desired=desired, tracked=tracked, u_command=keep[:, :, npos:npos + L.nu],
                            u_applied=keep[:, :, npos + L.nu:], failures=tuple(failures[:b]))

    def _desired(self, refs: Sequence[Any] | None, b: int) -> np.ndarray:
        sim = self.simulator
        if refs is None:
            ref = np.asarray(sim.reference, dtype=float)
            xd = ref[:, :, 0] if ref.ndim == 3 else ref[:, :1]
            return np.broadcast_to(xd, (b, *xd.shape))
        return np.stack([np.asarray(r.evaluate(sim.time), dtype=float)[:, :, 0] for r in refs[:b]])

    def _one_by_one(self, P: np.ndarray, Z: np.ndarray, noise: np.ndarray | None, refs: Sequence[Any] | None,
                    exc: Exception | None) -> BatchRecords:
        """Every run of a batch alone through the single-run path, each failing step recorded (an adaptive
        simulator, or a batch whose mapped evaluation raised: ``exc``)."""
        from designkit.simulation.integrate import run_steps

        sim = self.simulator
        L = layout(sim.plant, sim.law, _NoElement, 0)
        cuts = np.cumsum([0, *L.record_sizes])
        pos = [int(cuts[0]) + k for k in sim.plant.positions]
        rows = np.r_[pos, np.arange(cuts[2], cuts[4])].astype(int)
        npar, nw = L.np_, sim.inputs.shape[0]
        # one (N, nw) buffer per batch, changed in place run by run; the integrator is given its transpose, whose
        # own transpose is this C-contiguous buffer, so nothing of the size of the run is copied per run
        buf = np.ascontiguousarray(sim.inputs.T)
        kept, failed = [], []
        for i in range(P.shape[0]):
            if npar:
                buf[:, nw - npar:] = P[i][None, :]
            if noise is not None:
                buf[:, 9 * L.n:9 * L.n + L.nx] = noise[i].T
            if refs is not None:
                buf[:, :9 * L.n] = _reference_rows([refs[i]], sim.time, sim.settings["dt"])[:, 0, :]
            failure: dict[str, Any] = {}
            if self.adaptive:
                rec = sim.dopri5.run(Z[i], buf.T, failure)
            else:
                rec = run_steps(sim.step, Z[i], buf.T, failure=failure)
            kept.append(rec[rows].T)
            failed.append(failure)
        time = sim.time
        npos = len(pos)
        tracked = np.stack([k[:, :npos] for k in kept])
        if sim.motion is not None:
            from designkit.simulation.motion import tracked_outputs

            tracked = np.stack([tracked_outputs(sim.motion, q) for q in tracked])
        u_c = np.stack([k[:, npos:npos + L.nu] for k in kept])
        u_a = np.stack([k[:, npos + L.nu:] for k in kept])
        failures = tuple(
            (f"the integrator stopped at t = {time[f['step']]:.6g} s ({f['error']})" if f else "") for f in failed)
        return BatchRecords(time=time, desired=self._desired(refs, P.shape[0]), tracked=tracked, u_command=u_c,
                            u_applied=u_a, failures=failures)


def _reference_rows(refs: Sequence[Any], t: np.ndarray, dt: float) -> np.ndarray:
    """``(m, B, 9 n)``: each run's reference at the steps' starts, middles and ends (the single run's stages)."""
    out = []
    for r in refs:
        a = r.flat(t)
        stages = (a, a, a) if r.piecewise_constant else (a, r.flat(t + 0.5 * dt), r.flat(t + dt))
        out.append(np.concatenate(stages, axis=1))
    return np.stack(out, axis=1)


class _NoElement:
    n_memory = 0


def batch_simulator(simulator: Any, batch: int, *, compile: str = "auto") -> BatchSimulator:
    """Map ``simulator``'s step over ``batch`` samples and roll it over time.

    Parameters
    ----------
    simulator : Simulator
        A built single run (:func:`designkit.simulation.run.build`).
    batch : int
        Samples per evaluation (1 to 4096).
    compile : {"auto", "always", "never"}
        Compile the rolled, mapped step to C (``auto``: when a C compiler is found and the step is not a
        CVODES step; the library is cached by content hash, so workers on one machine compile it once).

    Returns
    -------
    BatchSimulator
    """
    if not 1 <= int(batch) <= 4096:
        raise ValueError(f"batch must be 1 to 4096 samples, got {batch}")
    from designkit.models.codegen import compile_function, find_compiler
    from designkit.simulation.compiled import COMPILE_FLAGS

    step = simulator.step
    if getattr(simulator, "dopri5", None) is not None:  # runs one by one through the compiled adaptive pair
        return BatchSimulator(simulator=simulator, batch=int(batch), accumulated=step,
                              compiled={"compiled": True, "why": "the simulator's compiled adaptive integrator"})
    acc = step.map(int(batch)).mapaccum(f"{step.name()}_batch{int(batch)}", STEPS_PER_CALL)
    info: dict[str, Any] = {"compiled": False}
    if compile == "never":
        info["why"] = "compile: never"
    elif not step.is_a("SXFunction"):
        info["why"] = "a CVODES step is not compiled"
    elif find_compiler() is None:
        info["why"] = "no C compiler on PATH"
    else:
        compiled = compile_function(acc, flags=COMPILE_FLAGS)
        if compiled.compiled:
            acc, info = compiled.function, {"compiled": True, "flags": " ".join(COMPILE_FLAGS)}
        else:
            info["why"] = compiled.reason
    return BatchSimulator(simulator=simulator, batch=int(batch), accumulated=acc, compiled=info)
