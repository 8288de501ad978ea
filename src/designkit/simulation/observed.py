"""Many runs of the compiled Dormand--Prince pair in one C call, each reduced on the fly by a caller's observer.

A sweep (:mod:`designkit.sweep`) needs a handful of numbers per run -- a requirement's margin -- not the run's
records: writing ``N`` records per run and reducing them in NumPy afterwards costs many times the integration
itself (on SIMNOG, 2 s at 0.1 ms: the records and their reduction were 9 ms of a 10 ms sample).  Here the pair of
:mod:`designkit.simulation.dopri5` integrates ``B`` runs one after the other inside one C call; at each grid
point it evaluates a small output function of the loop (``dk_out(s, a, q)``: the rows of the record the
observer reads) and hands it to the **observer**, C source the caller supplies, which keeps what it needs.

What varies per run: the initial state (``S0``, ``B x ns``) and the true plant's parameters (``P``, ``B x np``,
held over the run: they replace the last ``np`` held inputs of every grid step, which is where the simulator's
per-step inputs carry them).  The per-step inputs, the breakpoints and the grid are the simulator's, shared.  A
run's numbers are the single run's to the last bit (the same driver, the same compiled right-hand side with the
same flags; tested), whatever the batch it is in.

The observer's source defines ``NOUT`` (numbers it writes per run), a ``dk_obs`` struct and::

    void dk_obs_begin(dk_obs *o, const double *s0, const double *W, long N, const double *prm);
    void dk_obs_point(dk_obs *o, long k, const double *y, const double *w);   /* y: dk_out's rows at t_k */
    void dk_obs_end(dk_obs *o, int status, long stop, double *out);           /* stop: first point not seen */

``W`` is the per-step input block (``NW`` numbers a step: the reference's three stages, then the held
inputs; grid point ``k``'s inputs start at ``W + k * DK_WSTRIDE``, ``DK_WSTRIDE`` being ``NW``, or 0 for a runner
built for inputs that do not change over the grid), ``prm`` the caller's constants.  An observer may also plan,
step by step, which grid points it reads (``observed(steps=True)``).  The library is cached by the hash of its
source, like the pair's.
"""

from __future__ import annotations

import ctypes
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from designkit.simulation.dopri5 import MAX_STEPS_PER_SAMPLE, Dopri5, _compiler, _library, breakpoints, source

__all__ = ["FLAGS", "Observed", "observed"]

FLAGS = ("-O2", "-ffp-contract=off", "-fno-semantic-interposition", "-fPIC", "-shared")
"""The batch library runs many samples, so it is built at ``-O2`` (the pair's ``-O1`` is chosen for one run's
compile time); without fused multiply-add or reassociation either way, a run's numbers are the single run's."""

ENTRY = r"""
typedef struct {{ dk_ctx c; dk_obs *o; casadi_int iw[OUT_IW + 1]; casadi_real w[OUT_W + 1]; double y[NOBS + 1]; }}
  dk_obs_user;

static void dk_emit_observe(void *user, long k, const double *s) {{
  dk_obs_user *u = (dk_obs_user *)user;
#if OBS_FROM_STATE
  static const int rows[NOBS + 1] = {{OBS_ROWS}};
  for (int i = 0; i < NOBS; ++i) u->y[i] = s[rows[i]];
  dk_obs_point(u->o, k, u->y, u->c.W + (size_t)k * DK_WSTRIDE);
  return;
#endif
  const casadi_real *arg[OUT_ARG + 3] = {{0}};
  casadi_real *res[OUT_RES + 1] = {{0}};
  arg[0] = s; arg[1] = u->c.W + (size_t)k * DK_WSTRIDE; arg[2] = dk_held(&u->c, k);
  res[0] = u->y;
  dk_out(arg, res, u->iw, u->w, 0);
  dk_obs_point(u->o, k, u->y, u->c.W + (size_t)k * DK_WSTRIDE);
}}

#ifdef DK_STEP_OBSERVER
/* One accepted step's grid points first..lastk: the observer's plan says which it reads (all, or the first and
   the last, or the last); each is written exactly as the driver writes a grid point. */
static void dk_step(void *user, long first, long lastk, double t, double h, double dt, int exact_end,
                    const double *const *coef) {{
  dk_obs_user *u = (dk_obs_user *)user;
  static const int rows[NOBS + 1] = {{OBS_ROWS}};
  double s[NS];
  const int plan = dk_obs_plan(u->o, first, lastk, t, h, dt, coef);
  for (long k = first; k <= lastk; ++k) {{
    if (!(plan & DK_PLAN_ALL) && k != lastk && !(k == first && (plan & DK_PLAN_FIRST))) continue;
    if (k == lastk && exact_end)
      for (int i = 0; i < NOBS; ++i) s[rows[i]] = coef[5][rows[i]];
    else {{
      const double th = ((double)k * dt - t) / h;
      for (int i = 0; i < NOBS; ++i) {{
        const int r = rows[i];
        s[r] = dk_dense(coef[0][r], coef[1][r], coef[2][r], coef[3][r], coef[4][r], th);
      }}
    }}
    dk_emit_observe(user, k, s);
  }}
}}
#endif

int dk_dopri5_observe(const double *S0, const double *P, long np, long B, const double *W, const double *brk,
                      long N, double dt, double rtol, double atol, long max_steps, const double *prm, double *OUT,
                      double *STATS) {{
  int failed = 0;
  for (long b = 0; b < B; ++b) {{
    dk_ctx c;
    dk_obs o;
    dk_obs_user u;
    memset(&c, 0, sizeof c);
    c.W = W; c.dt = dt; c.P = P ? P + (size_t)b * np : 0; c.np = (int)np;
    memset(&u, 0, sizeof u);
    u.c = c; u.o = &o;
    dk_obs_begin(&o, S0 + (size_t)b * NS, W, N, prm);
    int status = dk_integrate(&c, S0 + (size_t)b * NS, brk, N, rtol, atol, max_steps, dk_emit_observe, &u,
                              STATS + (size_t)b * 4);
    dk_obs_end(&o, status, (long)STATS[(size_t)b * 4 + 3], OUT + (size_t)b * NOUT);
    failed += status;
  }}
  return failed;
}}
"""
"""The batch entry point, appended after the pair's driver, the output function and the observer's source."""


@dataclass(frozen=True, eq=False)
class Observed:
    """``B`` runs of a compiled pair, reduced by an observer (module docstring).

    Parameters
    ----------
    library : pathlib.Path
        The shared library.
    pair : Dopri5
        The single-run pair it extends (sizes, grid step, tolerances).
    n_out : int
        Numbers the observer writes per run.
    n_params : int
        Parameters replaced per run (the last held inputs).
    constant : bool
        Built for inputs whose columns are all equal (one column is passed).
    """

    library: Path
    pair: Dopri5
    n_out: int
    n_params: int
    constant: bool = False
    _lib: list = field(default_factory=list, repr=False)

    def _entry(self) -> Any:
        if not self._lib:
            lib = ctypes.CDLL(str(self.library))
            fn = lib.dk_dopri5_observe
            vec = np.ctypeslib.ndpointer(dtype=np.float64, flags="C_CONTIGUOUS")
            fn.argtypes = [vec, ctypes.c_void_p, ctypes.c_long, ctypes.c_long, vec, vec, ctypes.c_long,
                           ctypes.c_double, ctypes.c_double, ctypes.c_double, ctypes.c_long, vec, vec, vec]
            fn.restype = ctypes.c_int
            self._lib.extend([lib, fn])
        return self._lib[1]

    def run(self, z0: np.ndarray, inputs: np.ndarray, constants: np.ndarray,
            parameters: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Run ``B`` samples and return what the observer wrote, ``(B, n_out)``, and each run's work ``(B, 4)``
        (evaluations, accepted and rejected steps, the first grid point not reached: ``N`` when it ran through).

        Parameters
        ----------
        z0 : ndarray, shape (B, nz)
            Each run's initial augmented state (its first ``ns`` entries are integrated).
        inputs : ndarray, shape (nw, N)
            The simulator's per-step inputs, shared by every run.
        constants : ndarray
            The observer's constants (``prm``).
        parameters : ndarray, shape (B, n_params), optional
            Each run's true-plant parameters (default: the inputs' own).
        """
        pair = self.pair
        S0 = np.ascontiguousarray(np.atleast_2d(np.asarray(z0, dtype=float))[:, :pair.ns])
        B = S0.shape[0]
        W, brk, one = _prepared(pair, inputs)
        n = W.shape[0]
        if self.constant:
            if one is None:
                raise ValueError("this runner was built for inputs that do not change over the grid")
            W = one
        P = None
        if parameters is not None and self.n_params:
            P = np.ascontiguousarray(np.asarray(parameters, dtype=float).reshape(B, self.n_params))
        out = np.full((B, self.n_out), np.nan)
        stats = np.zeros((B, 4))
        prm = np.ascontiguousarray(np.asarray(constants, dtype=float).reshape(-1))
        if prm.size == 0:
            prm = np.zeros(1)
        budget = MAX_STEPS_PER_SAMPLE * n + 10_000
        self._entry()(S0, None if P is None else P.ctypes.data, self.n_params, B, W, brk, n, pair.dt, pair.rtol,
                      pair.atol, budget, prm, out, stats)
        return out, stats


def _prepared(pair: Dopri5, inputs: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """The inputs' transpose, breakpoints and (when every column is the same) that one column, kept for the same
    array object (the simulator's own inputs)."""
    kept = pair._prepared.get("observed")
    if kept is not None and kept[0] is inputs:
        return kept[1], kept[2], kept[3]
    W, brk = np.ascontiguousarray(inputs.T, dtype=float), breakpoints(inputs, pair.n_ref)
    one = np.ascontiguousarray(W[:1]) if np.all(W[:1] == W) else None
    pair._prepared["observed"] = (inputs, W, brk, one)
    return W, brk, one


def observed(pair: Dopri5, rows: Sequence[int], observer_source: str, n_out: int, n_params: int,
             steps: bool = False, constant: bool = False) -> Observed | str:
    """The batch runner of ``pair`` whose observer reads the record rows ``rows`` at every grid point.

    Parameters
    ----------
    pair : Dopri5
        A compiled single-run pair (``pair.library`` not None).
    rows : sequence of int
        Rows of the pair's record (``dk_rec``) the observer reads, in order (``dk_out`` computes only these).
    observer_source : str
        C source defining ``dk_obs``, ``dk_obs_begin``, ``dk_obs_point``, ``dk_obs_end`` (module docstring); it
        may use the macros ``NS``, ``NA``, ``NW``, ``NOBS`` (``len(rows)``) and ``NOUT``.
    n_out : int
        Numbers the observer writes per run.
    n_params : int
        The plant's parameter count (the last held inputs), replaced per run when ``run`` is given them.
    steps : bool
        The observer also defines ``int dk_obs_plan(dk_obs *o, long first, long last, double t, double h,
        double dt, const double *const *coef)``, called once per accepted step with the step's grid points
        ``first..last`` and its continuous extension (``coef[0..4]``: Hairer's ``r1..r5`` of every state row read,
        ``coef[5]`` the step's end state; ``y(t + theta h) = r1 + theta (r2 + (1 - theta) (r3 + theta (r4 +
        (1 - theta) r5)))``); it returns which of them ``dk_obs_point`` is given: ``DK_PLAN_ALL``, or the last
        and with ``DK_PLAN_FIRST`` the first.  The grid points left out are never evaluated (only when every row
        read is a state of the plant; otherwise every point is).
    constant : bool
        The runner is given inputs whose columns are all the same (``run`` checks): ``W`` is that one column
        (``DK_WSTRIDE`` 0: the grid point ``k``'s inputs are ``W + k * DK_WSTRIDE``; observers index ``W`` so).  A
        run then reads ``NW`` numbers instead of streaming through ``N NW`` (14 MB for 50,001 points of 36 inputs,
        read again by every run of the batch and beyond the caches: most of an evaluation's time on SIMNOG).

    Returns
    -------
    Observed or str
        The runner, or why there is none (an interpreted pair, no compiler, a failed compilation).
    """
    if pair.library is None:
        return "the pair runs interpreted"
    if pair.proj is not None:
        return "the law's projection restarts the integration at grid instants (the records path applies it)"
    cc = _compiler()
    if cc is None:
        return "no C compiler on PATH"
    rec = pair.rec
    # the record starts with the plant's state x: rows read from it are copied from the integrated state itself
    from_state = all(0 <= int(r) < pair.ns and int(r) < _plant_states(pair) for r in rows)
    ins = [ca.SX.sym(rec.name_in(k), rec.sparsity_in(k)) for k in range(rec.n_in())]
    full = rec(*ins)
    out = ca.Function("dk_out", ins, [full[list(rows)] if rows else ca.SX(0, 1)], ["s", "a", "q"], ["y"])
    head = "\n".join(f"#define {k} {v}" for k, v in (
        ("OUT_ARG", out.sz_arg()), ("OUT_RES", out.sz_res()), ("OUT_IW", out.sz_iw()), ("OUT_W", out.sz_w()),
        ("NOBS", len(rows)), ("NOUT", int(n_out)), ("OBS_FROM_STATE", int(from_state)),
        ("OBS_ROWS", ", ".join(str(int(r)) for r in rows) or "0"), ("DK_PLAN_FIRST", 1), ("DK_PLAN_ALL", 4)))
    dense = f"#define DK_DENSE_ROWS {', '.join(str(int(r)) for r in rows)}\n" if from_state and rows else ""
    if dense and steps:
        dense += ("#define DK_STEP_OBSERVER\n"
                  "static void dk_step(void *user, long first, long lastk, double t, double h, double dt, "
                  "int exact_end, const double *const *coef);\n")
    if constant:
        dense = "#define DK_WSTRIDE 0\n" + dense
    text = dense + "\n".join([source(pair.rhs, rec, pair.nw, pair.n_ref, extra=(out,)), head, observer_source,
                      ENTRY.format()])
    built = _library(text, cc, FLAGS)
    if isinstance(built, str):
        return built
    return Observed(library=built[0], pair=pair, n_out=int(n_out), n_params=int(n_params), constant=constant)


def _plant_states(pair: Dopri5) -> int:
    """Rows of the record that are the plant's state ``x`` (the record is ``(x, xc, command, ...)``): the record's
    rows equal to the state's entries, found symbolically."""
    rec = pair.rec
    ins = [ca.SX.sym(rec.name_in(k), rec.sparsity_in(k)) for k in range(rec.n_in())]
    full = rec(*ins)
    s = ins[0]
    n = 0
    while n < min(pair.ns, full.size1()) and ca.is_equal(full[n], s[n]):
        n += 1
    return n
