"""The Dormand--Prince driver of :mod:`designkit.simulation.dopri5_c`, step for step in Python.

Used when the pair is not compiled (``numerics.compile: never``, no C compiler): the right-hand side and the
record are CasADi's interpreted Functions, the stepping is this loop.  Same coefficients, error norm, PI
control, continuous extension and breakpoints as the C driver (its module docstring).
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["run_interpreted"]

_C = (0.2, 0.3, 0.8, 8.0 / 9.0)
_A = ((0.2,), (3 / 40, 9 / 40), (44 / 45, -56 / 15, 32 / 9),
      (19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729),
      (9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656))
_B = (35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84)
_E = (71 / 57600, 0.0, -71 / 16695, 71 / 1920, -17253 / 339200, 22 / 525, -1 / 40)
_D = (-12715105075 / 11282082432, 0.0, 87487479700 / 32700410799, -10690763975 / 1880347072,
      701980252875 / 199316789632, -1453857185 / 822651844, 69997945 / 29380423)
_AM = np.zeros((5, 5))
for _i, _row in enumerate(_A):
    _AM[_i, :len(_row)] = _row
_BV, _EV, _DV = np.array(_B), np.array(_E), np.array(_D)
SAFE, BETA, EXPO1, FACC1, FACC2 = 0.9, 0.04, 0.2 - 0.04 * 0.75, 5.0, 0.1


def _buffered(f: Any) -> Any:
    """``f`` (three vector inputs, one vector output) called through CasADi's zero-copy buffer interface."""
    ins = [np.zeros(f.size1_in(k)) for k in range(3)]
    out = np.zeros(f.size1_out(0))
    buf, evaluate = f.buffer()
    for k, a in enumerate(ins):
        buf.set_arg(k, memoryview(a))
    buf.set_res(0, memoryview(out))

    def call(*args: np.ndarray) -> np.ndarray:
        for a, v in zip(ins, args, strict=True):
            a[:] = v
        evaluate()
        return out.copy()

    call.keep = (buf, ins, out)  # type: ignore[attr-defined]  # the buffers must outlive the closure
    return call


def run_interpreted(rhs: Any, rec: Any, s0: np.ndarray, W: np.ndarray, brk: np.ndarray, dt: float, rtol: float,
                    atol: float, max_steps: int, proj: Any = None) -> tuple[np.ndarray, dict[str, int], int]:
    """``(records (N, nrec), stats, stop)``: the pair over the grid; ``stop`` the first grid index not reached
    (``N`` when the run went through).  ``W`` is ``(N, nw)``, one per-step input column per row.  ``proj`` (the
    law's projection, ``Dopri5.proj``) is applied at every grid instant; where it moves the state the run starts
    again from there."""
    n, na = W.shape[0], rhs.size1_in(1)
    states = np.full((n, rhs.size1_in(0)), np.nan)
    count = {"evaluations": 0, "accepted": 0, "rejected": 0}

    def ref(t: float, k0: int, k1: int) -> np.ndarray:
        i = min(max(int(np.floor(t / dt)), k0), k1 - 1)
        tau = (t - i * dt) / dt
        w = W[i]
        return (2 * (tau - 0.5) * (tau - 1) * w[:na] - 4 * tau * (tau - 1) * w[na:2 * na]
                + 2 * tau * (tau - 0.5) * w[2 * na:3 * na])

    rhs_call = _buffered(rhs)

    y = np.array(s0, dtype=float)
    states[0] = y
    ks = np.zeros((7, y.size))
    k, h, stop = 0, 0.0, n
    while k < n - 1 and stop == n:
        kend = k + 1
        while kend < n - 1 and brk[kend] == 0.0:
            kend += 1
        q = W[k, 3 * na:]

        def f(t: float, s: np.ndarray, k0: int = k, k1: int = kend, q: np.ndarray = q) -> np.ndarray:
            count["evaluations"] += 1
            return rhs_call(s, ref(t, k0, k1), q)

        t, tend, facold, rejected, nxt, reset = k * dt, kend * dt, 1e-4, False, k + 1, -1
        k1 = f(t, y)
        if h <= 0.0:
            sk = atol + rtol * np.abs(y)
            dnf, dny = float(np.sum((k1 / sk) ** 2)), float(np.sum((y / sk) ** 2))
            h = 1e-6 if dnf <= 1e-10 or dny <= 1e-10 else np.sqrt(dny / dnf) * 0.01
            h = min(h, tend - t)
            der2 = np.sqrt(np.sum(((f(t + h, y + h * k1) - k1) / sk) ** 2)) / h
            der12 = max(der2, np.sqrt(dnf))
            h1 = max(1e-6, h * 1e-3) if der12 <= 1e-15 else (0.01 / der12) ** 0.2
            h = max(min(100.0 * h, h1), 1e-6 * dt)
        while nxt <= kend:
            if (count["accepted"] + count["rejected"] >= max_steps or h < 1e-14 * max(1.0, abs(t))
                    or not np.sum(np.abs(y)) < 1e150):
                stop = nxt
                break
            last = t + h >= tend - 1e-9 * dt
            if last:
                h = tend - t
            ks[0] = k1
            for i, c in enumerate((*_C, 1.0)):
                ks[i + 1] = f(t + c * h, y + h * (_AM[i, :i + 1] @ ks[:i + 1]))
            y1 = y + h * (_BV @ ks[:6])
            k7 = ks[6] = f(t + h, y1)
            sk = atol + rtol * np.maximum(np.abs(y), np.abs(y1))
            err = float(np.sqrt(np.mean((h * (_EV @ ks) / sk) ** 2)))
            fac11 = err ** EXPO1 if err == err else 1e3
            if err <= 1.0:
                count["accepted"] += 1
                tn = tend if last else t + h
                yd = y1 - y
                bs = h * k1 - yd
                r5 = h * (_DV @ ks)
                top = kend if last else min(kend, int(np.floor((tn + 1e-9 * dt) / dt)))
                if top >= nxt:
                    th = ((np.arange(nxt, top + 1) * dt - t) / h)[:, None]
                    states[nxt:top + 1] = y + th * (yd + (1 - th) * (bs + th * (yd - h * k7 - bs + (1 - th) * r5)))
                    if last:
                        states[kend] = y1
                    if proj is not None:
                        reset = _first_moved(proj, states, nxt, top)
                    nxt = top + 1 if reset < 0 else reset + 1
                y, k1 = y1, k7.copy()
                fac = max(FACC2, min(FACC1, fac11 / facold ** BETA / SAFE))
                hnew = h / fac
                if rejected:
                    hnew = min(hnew, h)
                facold, rejected, t, h = max(err, 1e-4), False, tn, hnew
                if reset >= 0:
                    y = states[reset].copy()
                    break
            else:
                count["rejected"] += 1
                rejected = True
                h = h / min(FACC1, fac11 / SAFE)
        k = reset if reset >= 0 else kend
    states[stop:] = np.nan
    records = rec.map(n)(states.T, W[:, :na].T, W[:, 3 * na:].T)
    return np.asarray(records).T, count, stop


def _first_moved(proj: Any, states: np.ndarray, lo: int, hi: int) -> int:
    """The first grid point of ``lo..hi`` whose state the projection moves (written projected), or -1."""
    block = states[lo:hi + 1]
    out = np.asarray(proj.map(block.shape[0])(block.T), dtype=float).T
    moved = np.flatnonzero(np.any(out != block, axis=1))
    if moved.size == 0:
        return -1
    i = lo + int(moved[0])
    states[i] = out[i - lo]
    return i
