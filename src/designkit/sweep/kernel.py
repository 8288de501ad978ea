"""The sweep's fast path: every sample's per-joint metrics reduced inside the compiled integrator, no records kept.

For a loop the compiled Dormand--Prince pair integrates (a smooth loop, the default integrator) whose samples
differ only in the true plant's parameters -- the samples of ``plant.uncertainty``, ``sweep.parameters`` and
``sweep.payload``; not an initial position, whose reference and rest start are the sample's own, nor noise, nor a
task-space motion, whose tracked coordinates are computed from the records -- a batch of samples is one C call
(:func:`designkit.simulation.observed.observed`): the pair integrates each run and hands every grid point's
positions (and, with ``max_control``, commands) to the observer below, which keeps running sums, extrema and
crossings.  What comes out is :class:`~designkit.sweep.margins.JointMetrics`, the same numbers
:func:`~designkit.sweep.margins.joint_metrics` computes from the records, with the same formulas in the same order
of operations (tested against it), except the steady-state error's mean, summed here in grid order where NumPy
sums pairwise: the two agree to about 1e-12 relative (2e-13 measured on SIMNOG), not to the last bit.  A sample's
numbers do not depend on its batch, so a sweep's results are still identical however it is split.

Which grid points are read: on a step to a constant reference without ``max_control``, the pair hands each
accepted step's continuous extension to the observer's plan (``dk_obs_plan`` below), which bounds each position
over the step and lets only the points that can change a metric be evaluated -- the last of every step, the first
where a maximum may sit or the band's last outside point was just before, every point of a step that may cross a
rise level or the settling band and of the steady-state window.  The points read go through the same
``dk_obs_point`` in grid order, so the metrics are those of every point.  Inputs that do not change over the grid
are passed as one column (``DK_WSTRIDE`` 0).

Memory per run: nothing of the size of the run (the per-step inputs are the simulator's, shared).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from designkit.sweep.margins import JointMetrics
from designkit.verification.tolerances import REST_TOL, RISE_LIMITS, STEADY_STATE_WINDOW

__all__ = ["Kernel", "kernel_for"]

PER_JOINT = 8
"""Numbers the observer writes per joint: finite, overshoot, rise, settle, moving, sse, max_err, amps."""

OBSERVER = r"""
#define NJ {nj}
#define NU {nu}
typedef struct {{
  const double *W, *T; long N, kwin, seen, last[NJ]; int traj, fixed, finite[NJ], zero[NJ], found[NJ][2], uok;
  double sb, lv[2], y0[NJ], r[NJ], amp[NJ], amps[NJ], xdmax[NJ], denom[NJ], band[NJ], bandx[NJ], max_err[NJ],
    sum[NJ], max_yn[NJ], prev_yn[NJ], cross[NJ][2], d0[NJ], d1[NJ], peak[NU + 1];
  long cnt[NJ];
}} dk_obs;

/* prm: [0 a step to a constant reference, 1 a trajectory, 2 another step; settling band, k of the steady-state
   window's start, then the N instants] */
static void dk_obs_begin(dk_obs *o, const double *s0, const double *W, long N, const double *prm) {{
  memset(o, 0, sizeof *o);
  o->W = W; o->N = N; o->traj = prm[0] == 1.0; o->fixed = prm[0] == 0.0;
  o->sb = prm[1]; o->kwin = (long)prm[2]; o->T = prm + 3;
  o->lv[0] = {rise_lo}; o->lv[1] = {rise_hi}; o->uok = 1;
  for (int j = 0; j < NJ; ++j) {{
    const double x0 = W[j];
    o->finite[j] = 1; o->r[j] = W[(size_t)(N - 1) * DK_WSTRIDE + j];
    o->max_yn[j] = -INFINITY; o->max_err[j] = -INFINITY; o->last[j] = -1;
    if (o->traj)
      for (long k = 0; k < N; ++k) {{
        double xd = W[(size_t)k * DK_WSTRIDE + j], e = fabs(xd - x0), a = fabs(xd);
        if (e > o->amps[j] || e != e) o->amps[j] = e;
        if (a > o->xdmax[j] || a != a) o->xdmax[j] = a;
      }}
  }}
  for (int i = 0; i < NU; ++i) o->peak[i] = -INFINITY;
  (void)s0;
}}

/* The bands, once y(0) is known (the step's amplitude is xD(end) - y(0)). */
static void dk_obs_bands(dk_obs *o, const double *y) {{
  int all = 1;
  double scale = -INFINITY;
  for (int j = 0; j < NJ; ++j) {{
    o->y0[j] = y[j];
    if (!o->traj) {{
      o->amp[j] = o->r[j] - o->y0[j];
      o->amps[j] = fabs(o->r[j] - o->y0[j]);
      o->zero[j] = fabs(o->amp[j]) <= {rest_tol} * (1.0 + fabs(o->r[j]));
      o->denom[j] = o->zero[j] ? 1.0 : o->amp[j];
    }}
    if (!isfinite(o->amps[j])) all = 0;
    if (o->amps[j] > scale) scale = o->amps[j];
  }}
  scale = (NJ > 1 && all) ? scale : NAN;
  for (int j = 0; j < NJ; ++j) {{
    double band;
    if (o->traj) {{
      int own = o->amps[j] > {rest_tol} * (1.0 + o->xdmax[j]);
      double bs = own ? o->amps[j] : (NJ > 1 ? (scale == scale ? scale : 0.0) : 0.0);
      band = bs > 0 ? o->sb * bs : NAN;
    }} else {{
      band = o->zero[j] ? o->sb * (NJ > 1 ? scale : NAN) : o->sb * fabs(o->amp[j]);
    }}
    o->band[j] = band;
    o->bandx[j] = band == band ? band : INFINITY;
  }}
}}

static void dk_obs_point(dk_obs *o, long k, const double *y, const double *w) {{
  if (k == 0) dk_obs_bands(o, y);
  for (int j = 0; j < NJ; ++j) {{
    const double yj = y[j], xd = w[j];
    if (!(isfinite(yj) && isfinite(xd))) o->finite[j] = 0;
    const double err = fabs(yj - xd);
    if (err > o->max_err[j]) o->max_err[j] = err;
    if (k >= o->kwin) {{ o->sum[j] += err; o->cnt[j]++; }}
    double dev = err;
    if (!o->traj) {{
      const double yn = (yj - o->y0[j]) / o->denom[j];
      if (yn > o->max_yn[j]) o->max_yn[j] = yn;
      for (int l = 0; l < 2; ++l)
        if (!o->found[j][l] && yn >= o->lv[l]) {{
          o->found[j][l] = 1;
          o->cross[j][l] = k == 0 ? o->T[0]
            : o->T[k - 1] + (o->T[k] - o->T[k - 1]) * (o->lv[l] - o->prev_yn[j]) / (yn - o->prev_yn[j]);
        }}
      o->prev_yn[j] = yn;
      dev = fabs(yj - o->r[j]);
    }}
    if (dev > o->bandx[j]) {{ o->last[j] = k; o->d0[j] = dev; }}
    else if (k == o->last[j] + 1) o->d1[j] = dev;
  }}
  for (int i = 0; i < NU; ++i) {{
    const double u = y[NJ + i];
    if (!isfinite(u)) o->uok = 0;
    if (fabs(u) > o->peak[i]) o->peak[i] = fabs(u);
  }}
  o->seen = k + 1;
}}

static void dk_obs_end(dk_obs *o, int status, long stop, double *out) {{
  const int through = !status && o->seen == o->N;
  const double *T = o->T;
  const long N = o->N;
  (void)stop;
  for (int j = 0; j < NJ; ++j) {{
    double *v = out + {per_joint} * j;
    const int fin = through && o->finite[j];
    double os = NAN, rise = NAN, settle;
    if (o->last[j] < 0) settle = 0.0;
    else if (o->last[j] == N - 1) settle = NAN;
    else {{
      const long kk = o->last[j];
      const double d0 = o->d0[j], d1 = o->d1[j];
      const double frac = d0 != d1 ? (d0 - o->bandx[j]) / (d0 - d1) : 1.0;
      settle = T[kk] + (T[kk + 1] - T[kk]) * frac - T[0];
    }}
    if (o->band[j] != o->band[j]) settle = NAN;
    if (!o->traj && !o->zero[j]) {{
      os = 100.0 * fmax(0.0, o->max_yn[j] - 1.0);
      if (o->found[j][0] && o->found[j][1]) rise = o->cross[j][1] - o->cross[j][0];
    }}
    v[0] = fin; v[1] = fin ? os : NAN; v[2] = fin ? rise : NAN; v[3] = fin ? settle : NAN;
    v[4] = fin ? (o->traj ? o->amps[j] : o->amp[j]) : NAN;
    v[5] = fin ? o->sum[j] / (double)o->cnt[j] : NAN; v[6] = fin ? o->max_err[j] : NAN; v[7] = o->amps[j];
  }}
  for (int i = 0; i < NU; ++i) {{
    out[{per_joint} * NJ + 2 * i] = o->peak[i];
    out[{per_joint} * NJ + 2 * i + 1] = through && o->uok;
  }}
}}

/* Which grid points first..last of an accepted step [t, t + h] can change what dk_obs_point keeps (a step run
   to a constant reference, before the steady-state window, no command observed; otherwise all of them).  Each
   position is the step's quartic p(theta), theta in [0, 1]: p = a0 + a1 theta + ... + a4 theta^4 from Hairer's
   r1..r5, within M = |a2|/4 + 0.385 |a3| + 0.473 |a4| of its chord (max |theta^k - theta| on [0, 1]), and
   monotone when |a1| exceeds 2 |a2| + 3 |a3| + 4 |a4| (a bound of the other terms of p'); the bounds are widened
   by EPS = 1e-12 of the coefficients' size, far above the rounding of a grid point's value.  A point is read
   when its value could move a maximum (then, the step being monotone, only its first or last point can), cross
   a rise level, or cross the settling band (then every point is: the crossing's grid points and interpolation
   are the grid's); the last point of a step is always read (the next crossing's previous value, the count of
   points seen). */
static int dk_obs_plan(dk_obs *o, long first, long lastk, double t, double h, double dt, const double *const *coef) {{
  static const int rows[NOBS + 1] = {{OBS_ROWS}};
  if (o->traj || !o->fixed || NU > 0 || lastk >= o->kwin || first < 1) return DK_PLAN_ALL;
  int plan = 0;
  const double gap = dt / h;
  (void)t;
  for (int j = 0; j < NJ; ++j) {{
    const int i = rows[j];
    const double A = coef[0][i], B = coef[1][i], C = coef[2][i], D = coef[3][i], E = coef[4][i];
    if (!(isfinite(A) && isfinite(B) && isfinite(C) && isfinite(D) && isfinite(E))) return DK_PLAN_ALL;
    const double a1 = B + C, a2 = D + E - C, a3 = -(D + 2.0 * E), a4 = E;
    const double eps = 1e-12 * (1.0 + fabs(A) + fabs(B) + fabs(C) + fabs(D) + fabs(E));
    const double M = 0.25 * fabs(a2) + 0.385 * fabs(a3) + 0.473 * fabs(a4);
    const double p1 = A + B, lo = fmin(A, p1) - M - eps, hi = fmax(A, p1) + M + eps;
    const double bend = 2.0 * fabs(a2) + 3.0 * fabs(a3) + 4.0 * fabs(a4);
    const int up = (a1 - bend) * gap > 2.0 * eps, down = (-a1 - bend) * gap > 2.0 * eps;
    if (!o->zero[j]) {{
      const double ya = (lo - o->y0[j]) / o->denom[j], yb = (hi - o->y0[j]) / o->denom[j], ynhi = fmax(ya, yb);
      for (int l = 0; l < 2; ++l)
        if (!o->found[j][l] && !(ynhi < o->lv[l])) return DK_PLAN_ALL;
      if (!(ynhi < o->max_yn[j])) {{
        const int rising = o->denom[j] > 0 ? up : down, falling = o->denom[j] > 0 ? down : up;
        if (falling) plan |= DK_PLAN_FIRST;
        else if (!rising) return DK_PLAN_ALL;
      }}
    }}
    const double r = o->r[j];
    const double dhi = fmax(fabs(lo - r), fabs(hi - r));
    const double dlo = (lo <= r && r <= hi) ? 0.0 : fmin(fabs(lo - r), fabs(hi - r));
    if (dhi <= o->bandx[j]) {{
      if (o->last[j] == first - 1) plan |= DK_PLAN_FIRST;  /* the point after the last one outside */
    }} else if (!(dlo > o->bandx[j])) return DK_PLAN_ALL;
    if (!(dhi <= o->max_err[j])) {{
      if (lo > r) {{ if (down) plan |= DK_PLAN_FIRST; else if (!up) return DK_PLAN_ALL; }}
      else if (hi < r) {{ if (up) plan |= DK_PLAN_FIRST; else if (!down) return DK_PLAN_ALL; }}
      else return DK_PLAN_ALL;
    }}
  }}
  return plan;
}}
"""
"""The observer (C, formatted with the joint and input counts and the tolerances): the formulas of
:func:`designkit.sweep.margins.joint_metrics`, one grid point at a time, and the plan that picks, step by step,
the grid points that can change them (the others are not evaluated)."""


@dataclass(frozen=True, eq=False)
class Kernel:
    """A compiled batch runner of one prepared sweep (module docstring).

    Parameters
    ----------
    observed : Observed
        The pair's batch entry with this module's observer.
    n, nu : int
        Tracked joints, and inputs observed (0 without ``max_control``).
    constants : ndarray
        The observer's constants: trajectory flag, settling band, the steady-state window's first index, the grid.
    """

    observed: Any
    n: int
    nu: int
    constants: np.ndarray

    def run(self, simulator: Any, parameters: np.ndarray) -> tuple[JointMetrics, np.ndarray]:
        """The per-joint metrics of the runs of ``simulator`` on the parameter vectors ``parameters`` ``(B, np)``,
        and which runs the integrator stopped early."""
        B = parameters.shape[0]
        z0 = np.tile(np.asarray(simulator.z0, dtype=float), (B, 1))
        out, stats = self.observed.run(z0, simulator.inputs, self.constants, parameters)
        n, nu = self.n, self.nu
        per = out[:, :PER_JOINT * n].reshape(B, n, PER_JOINT)
        u = out[:, PER_JOINT * n:].reshape(B, nu, 2)
        jm = JointMetrics(finite=per[:, :, 0] != 0, overshoot=per[:, :, 1], rise=per[:, :, 2], settle=per[:, :, 3],
                          moving=per[:, :, 4], sse=per[:, :, 5], max_err=per[:, :, 6], amps=per[:, :, 7],
                          u_peak=u[:, :, 0] if nu else np.full((B, 0), np.nan),
                          u_ok=np.all(u[:, :, 1] != 0, axis=1) if nu else np.ones(B, dtype=bool))
        failed = stats[:, 3] < simulator.time.size
        return jm, failed


def kernel_for(simulator: Any, requirements: Any) -> Kernel | str:
    """The kernel of ``simulator`` scoring ``requirements``, or why the records path runs instead."""
    from designkit.simulation.observed import observed
    from designkit.simulation.step import layout

    pair = getattr(simulator, "dopri5", None)
    if pair is None:
        return "the loop is not integrated by the compiled Dormand-Prince pair"
    if simulator.motion is not None:
        return "a task-space motion's tracked coordinates are computed from the records"
    plant, law = simulator.plant, simulator.law
    L = layout(plant, law, _NoElement, 0)
    cuts = np.cumsum([0, *L.record_sizes])
    control = requirements is not None and requirements.max_control is not None
    rows = [int(cuts[0]) + k for k in plant.positions]
    nu = L.nu if control else 0
    if control:
        rows += list(range(int(cuts[2]), int(cuts[2]) + nu))
    n = len(plant.positions)
    source = OBSERVER.format(nj=n, nu=nu, per_joint=PER_JOINT, rest_tol=repr(REST_TOL),
                             rise_lo=repr(RISE_LIMITS[0]), rise_hi=repr(RISE_LIMITS[1]))
    w = np.asarray(simulator.inputs, dtype=float)
    runner = observed(pair, rows, source, PER_JOINT * n + 2 * nu, L.np_, steps=True,
                      constant=bool(np.all(w == w[:, :1])))
    if isinstance(runner, str):
        return runner
    t = np.asarray(simulator.time, dtype=float)
    window = np.flatnonzero(t >= t[-1] - STEADY_STATE_WINDOW * float(t[-1] - t[0]))
    sb = requirements.settling_band if requirements is not None else 0.02
    kind = 1.0 if simulator.kind == "trajectory" else (0.0 if _constant_reference(simulator, n) else 2.0)
    constants = np.concatenate([[kind, float(sb), float(window[0])], t])
    return Kernel(observed=runner, n=n, nu=nu, constants=constants)


def _constant_reference(simulator: Any, n: int) -> bool:
    """True when every tracked joint's desired position is its final value at every grid point (a step held from
    ``t = 0``): the observer's plan bounds the tracking error with it."""
    xd = np.asarray(simulator.inputs, dtype=float)[:n]
    return bool(np.all(xd == xd[:, -1:]))


class _NoElement:
    n_memory = 0
