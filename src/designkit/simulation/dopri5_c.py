"""The C driver of :mod:`designkit.simulation.dopri5`: Dormand--Prince 5(4) over the whole output grid.

The pair is Dormand & Prince's (J. Comput. Appl. Math. 6, 1980), with the step-size control and the
continuous extension of Hairer, Norsett & Wanner, *Solving Ordinary Differential Equations I* (2nd ed.,
section II.4 for the PI control, II.6 for the dense output); written here from the published coefficients.

* Seven stages, the last evaluated at the new point and reused as the first of the next step (FSAL): six
  evaluations of the right-hand side per step.
* Error ``err = sqrt(mean((h sum_i e_i k_i / sc)^2))`` with ``sc = atol + rtol max(|y_n|, |y_n+1|)``; a step is
  accepted when ``err <= 1``.  PI control: ``h_new = h / clip(err^0.17 / err_prev^0.04 / 0.9, 0.1, 5)``, no
  increase right after a rejection; a rejected step shrinks by ``min(5, err^0.17 / 0.9)``.
* The grid points an accepted step passes are written from the 4th-order continuous extension
  (``y(t_n + theta h)``, Hairer's ``contd5``); a step that reaches a breakpoint (where a held input changes)
  ends on it, and the next segment starts there from a fresh derivative.
* The reference inside grid interval ``[t_k, t_k + dt]`` is the quadratic through its three stage columns
  (``t_k``, ``t_k + dt/2``, ``t_k + dt``), as for the CVODES step
  (:func:`designkit.simulation.integrate.variable_step`).

The stepping is ``dk_integrate``, which hands every grid point's state to an emitter; the entry point of a
single run records them (:mod:`designkit.simulation.observed` adds one that runs a batch of samples and reduces
each grid point on the fly instead).  Entry point::

    int dk_dopri5(const double *s0, const double *W, const double *brk, long N, double dt, double rtol,
                  double atol, long max_steps, double *R, double *stats, const double *G)

``W`` holds the per-step input columns ``w_k`` one after the other (``NW`` numbers each), ``brk[k] != 0``
marks a breakpoint at ``t_k``; ``R`` receives the record of every grid point (``NREC`` numbers each),
``stats`` the evaluations, accepted and rejected steps, and the index of the grid point where the
integration stopped (``N`` when it did not); ``G`` the loop's constants, the last input of ``dk_rhs`` and ``dk_rec``
when they were lifted out of the code (:mod:`designkit.simulation.lifted`; unread otherwise).  Returns 0, or 1
(step size underflow, step budget exhausted or a state beyond 1e150 in magnitude: the records from there on are
NaN).
"""

from __future__ import annotations

DRIVER = r"""
#include <math.h>
#include <string.h>

#define NS {ns}
#define NA {na}
#define NW {nw}
#define NREC {nrec}
#define RHS_ARG {rhs_arg}
#define RHS_RES {rhs_res}
#define RHS_IW {rhs_iw}
#define RHS_W {rhs_w}
#define REC_ARG {rec_arg}
#define REC_RES {rec_res}
#define REC_IW {rec_iw}
#define REC_W {rec_w}
#define DIVERGED 1e150

#define NQ (NW - 3 * NA)
#ifndef DK_WSTRIDE
#define DK_WSTRIDE NW  /* numbers from one grid step's inputs to the next (0: one column for every step) */
#endif

typedef void (*dk_emit)(void *user, long k, const double *s);

typedef struct {{
  const double *W; long k0, k1; double dt;
  const double *P; int np; const double *held; double q[NQ + 1]; const double *G;
  casadi_int iw[RHS_IW + REC_IW + 1]; casadi_real w[RHS_W + REC_W + 1]; double a[NA + 1];
  long nfev;
}} dk_ctx;

/* The held inputs of grid step k (noise, disturbance, flag, feedforward, parameters): W's own, or a copy with its
   last np entries (the true plant's parameters) replaced by P (one sample of a batch). */
static const double *dk_held(dk_ctx *c, long k) {{
  const double *h = c->W + (size_t)k * DK_WSTRIDE + 3 * NA;
  if (!c->P) return h;
  memcpy(c->q, h, sizeof(double) * NQ);
  memcpy(c->q + NQ - c->np, c->P, sizeof(double) * c->np);
  return c->q;
}}

static void dk_ref(dk_ctx *c, double t, double *a) {{
  long i = (long)floor(t / c->dt);
  if (i < c->k0) i = c->k0;
  if (i > c->k1 - 1) i = c->k1 - 1;
  double tau = (t - (double)i * c->dt) / c->dt;
  double l0 = 2.0 * (tau - 0.5) * (tau - 1.0), lm = -4.0 * tau * (tau - 1.0), l1 = 2.0 * tau * (tau - 0.5);
  const double *w = c->W + (size_t)i * DK_WSTRIDE;
  for (int j = 0; j < NA; ++j) a[j] = l0 * w[j] + lm * w[NA + j] + l1 * w[2 * NA + j];
}}

static void dk_f(dk_ctx *c, double t, const double *s, double *out) {{
  const casadi_real *arg[RHS_ARG + 3] = {{0}};
  casadi_real *res[RHS_RES + 1] = {{0}};
  dk_ref(c, t, c->a);
  arg[0] = s; arg[1] = c->a; arg[2] = c->held; arg[3] = c->G;
  res[0] = out;
  dk_rhs(arg, res, c->iw, c->w, 0);
  c->nfev++;
}}

static void dk_record(dk_ctx *c, long k, const double *s, double *out) {{
  const casadi_real *arg[REC_ARG + 3] = {{0}};
  casadi_real *res[REC_RES + 1] = {{0}};
  arg[0] = s; arg[1] = c->W + (size_t)k * DK_WSTRIDE; arg[2] = c->W + (size_t)k * DK_WSTRIDE + 3 * NA; arg[3] = c->G;
  res[0] = out;
  dk_rec(arg, res, c->iw, c->w, 0);
}}

/* y(t_k) of the continuous extension of the step [t, t + h] (coefficients r1..r5, Hairer's contd5): the one
   expression every grid point is written with. */
#ifdef DK_PROJECT
/* The law's projection of the state at a grid instant, in place; 1 when it moved any entry. */
static int dk_project(double *s) {{
  const casadi_real *arg[PROJ_ARG + 1] = {{0}};
  casadi_real *res[PROJ_RES + 1] = {{0}};
  casadi_int iw[PROJ_IW + 1];
  casadi_real w[PROJ_W + 1];
  double out[NS];
  int moved = 0;
  arg[0] = s; res[0] = out;
  dk_proj(arg, res, iw, w, 0);
  for (int j = 0; j < NS; ++j)
    if (out[j] != s[j]) {{ moved = 1; s[j] = out[j]; }}
  return moved;
}}
#endif

static inline double dk_dense(double r1, double r2, double r3, double r4, double r5, double th) {{
  const double th1 = 1.0 - th;
  return r1 + th * (r2 + th1 * (r3 + th * (r4 + th1 * r5)));
}}

static int dk_bad(const double *y) {{
  double m = 0.0;
  for (int j = 0; j < NS; ++j) m += fabs(y[j]);
  return !(m < DIVERGED);
}}

/* The whole grid from s0: every grid point's state goes to emit(user, k, s); returns 0, or 1 (stopped: stats[3] is
   the first grid point not emitted). */
static int dk_integrate(dk_ctx *c0, const double *s0, const double *brk, long N, double rtol, double atol,
                        long max_steps, dk_emit emit, void *user, double *stats) {{
  static const double c2 = 1.0 / 5, c3 = 3.0 / 10, c4 = 4.0 / 5, c5 = 8.0 / 9;
  static const double a21 = 1.0 / 5;
  static const double a31 = 3.0 / 40, a32 = 9.0 / 40;
  static const double a41 = 44.0 / 45, a42 = -56.0 / 15, a43 = 32.0 / 9;
  static const double a51 = 19372.0 / 6561, a52 = -25360.0 / 2187, a53 = 64448.0 / 6561, a54 = -212.0 / 729;
  static const double a61 = 9017.0 / 3168, a62 = -355.0 / 33, a63 = 46732.0 / 5247, a64 = 49.0 / 176,
                      a65 = -5103.0 / 18656;
  static const double b1 = 35.0 / 384, b3 = 500.0 / 1113, b4 = 125.0 / 192, b5 = -2187.0 / 6784, b6 = 11.0 / 84;
  static const double e1 = 71.0 / 57600, e3 = -71.0 / 16695, e4 = 71.0 / 1920, e5 = -17253.0 / 339200,
                      e6 = 22.0 / 525, e7 = -1.0 / 40;
  static const double d1 = -12715105075.0 / 11282082432.0, d3 = 87487479700.0 / 32700410799.0,
                      d4 = -10690763975.0 / 1880347072.0, d5 = 701980252875.0 / 199316789632.0,
                      d6 = -1453857185.0 / 822651844.0, d7 = 69997945.0 / 29380423.0;
  const double safe = 0.9, beta = 0.04, expo1 = 0.2 - 0.04 * 0.75, facc1 = 5.0, facc2 = 0.1;
  dk_ctx c = *c0;
  const double dt = c.dt;
  double y[NS], y1[NS], k1[NS], k2[NS], k3[NS], k4[NS], k5[NS], k6[NS], k7[NS], ys[NS];
  double r1[NS], r2[NS], r3[NS], r4[NS], r5[NS];
  long nacc = 0, nrej = 0, k = 0, stop = N;
  double h = 0.0;
  int status = 0;
  memcpy(y, s0, sizeof y);
  c.k0 = 0; c.k1 = N > 1 ? 1 : 0;
  emit(user, 0, y);
  while (k < N - 1 && !status) {{
    long kend = k + 1, next = k + 1;
    while (kend < N - 1 && brk[kend] == 0.0) ++kend;
    c.k0 = k; c.k1 = kend; c.held = dk_held(&c, k);
    double t = (double)k * dt, tend = (double)kend * dt, facold = 1e-4;
    int rejected = 0;
    long reset = -1;  /* the grid point where the projection moved the state (DK_PROJECT) */
    dk_f(&c, t, y, k1);
    if (h <= 0.0) {{  /* Hairer's starting step (II.4) */
      double dnf = 0.0, dny = 0.0, der2 = 0.0;
      for (int j = 0; j < NS; ++j) {{
        double sk = atol + rtol * fabs(y[j]);
        dnf += (k1[j] / sk) * (k1[j] / sk); dny += (y[j] / sk) * (y[j] / sk);
      }}
      h = (dnf <= 1e-10 || dny <= 1e-10) ? 1e-6 : sqrt(dny / dnf) * 0.01;
      h = fmin(h, tend - t);
      for (int j = 0; j < NS; ++j) ys[j] = y[j] + h * k1[j];
      dk_f(&c, t + h, ys, k2);
      for (int j = 0; j < NS; ++j) {{
        double sk = atol + rtol * fabs(y[j]);
        der2 += ((k2[j] - k1[j]) / sk) * ((k2[j] - k1[j]) / sk);
      }}
      der2 = sqrt(der2) / h;
      double der12 = fmax(der2, sqrt(dnf));
      double h1 = der12 <= 1e-15 ? fmax(1e-6, h * 1e-3) : pow(0.01 / der12, 0.2);
      h = fmax(fmin(100.0 * h, h1), 1e-6 * dt);  /* a state at 0 makes Hairer's first guess vanish */
    }}
    while (next <= kend) {{
      if (nacc + nrej >= max_steps || h < 1e-14 * fmax(1.0, fabs(t)) || dk_bad(y)) {{ status = 1; stop = next; break; }}
      int last = t + h >= tend - 1e-9 * dt;
      if (last) h = tend - t;
      for (int j = 0; j < NS; ++j) ys[j] = y[j] + h * a21 * k1[j];
      dk_f(&c, t + c2 * h, ys, k2);
      for (int j = 0; j < NS; ++j) ys[j] = y[j] + h * (a31 * k1[j] + a32 * k2[j]);
      dk_f(&c, t + c3 * h, ys, k3);
      for (int j = 0; j < NS; ++j) ys[j] = y[j] + h * (a41 * k1[j] + a42 * k2[j] + a43 * k3[j]);
      dk_f(&c, t + c4 * h, ys, k4);
      for (int j = 0; j < NS; ++j) ys[j] = y[j] + h * (a51 * k1[j] + a52 * k2[j] + a53 * k3[j] + a54 * k4[j]);
      dk_f(&c, t + c5 * h, ys, k5);
      for (int j = 0; j < NS; ++j)
        ys[j] = y[j] + h * (a61 * k1[j] + a62 * k2[j] + a63 * k3[j] + a64 * k4[j] + a65 * k5[j]);
      dk_f(&c, t + h, ys, k6);
      for (int j = 0; j < NS; ++j) y1[j] = y[j] + h * (b1 * k1[j] + b3 * k3[j] + b4 * k4[j] + b5 * k5[j] + b6 * k6[j]);
      dk_f(&c, t + h, y1, k7);
      double err = 0.0;
      for (int j = 0; j < NS; ++j) {{
        double sk = atol + rtol * fmax(fabs(y[j]), fabs(y1[j]));
        double ej = h * (e1 * k1[j] + e3 * k3[j] + e4 * k4[j] + e5 * k5[j] + e6 * k6[j] + e7 * k7[j]) / sk;
        err += ej * ej;
      }}
      err = sqrt(err / NS);
      double fac11 = pow(err, expo1);
      if (err <= 1.0) {{
        ++nacc;
        double tn = last ? tend : t + h;
#ifdef DK_STEP_OBSERVER  /* the step's grid points handed over at once: the emitter picks the ones it reads */
        if (next * dt <= tn + 1e-9 * dt) {{
          static const int dense_s[] = {{DK_DENSE_ROWS}};
          for (size_t i = 0; i < sizeof dense_s / sizeof dense_s[0]; ++i) {{
            const int j = dense_s[i];
            double yd = y1[j] - y[j], bs = h * k1[j] - yd;
            r1[j] = y[j]; r2[j] = yd; r3[j] = bs; r4[j] = yd - h * k7[j] - bs;
            r5[j] = h * (d1 * k1[j] + d3 * k3[j] + d4 * k4[j] + d5 * k5[j] + d6 * k6[j] + d7 * k7[j]);
          }}
          const long first = next;
          while (next <= kend && ((double)next * dt <= tn + 1e-9 * dt)) ++next;
          const double *coef[6] = {{r1, r2, r3, r4, r5, y1}};
          dk_step(user, first, next - 1, t, h, dt, last && next - 1 == kend, coef);
        }}
#else
        if (next * dt <= tn + 1e-9 * dt) {{
          for (int j = 0; j < NS; ++j) {{
            double yd = y1[j] - y[j], bs = h * k1[j] - yd;
            r1[j] = y[j]; r2[j] = yd; r3[j] = bs; r4[j] = yd - h * k7[j] - bs;
            r5[j] = h * (d1 * k1[j] + d3 * k3[j] + d4 * k4[j] + d5 * k5[j] + d6 * k6[j] + d7 * k7[j]);
          }}
          while (next <= kend && ((double)next * dt <= tn + 1e-9 * dt)) {{
            if (next == kend && last) {{
              memcpy(ys, y1, sizeof ys);
            }} else {{
              double th = ((double)next * dt - t) / h, th1 = 1.0 - th;
#ifdef DK_DENSE_ROWS  /* an emitter that reads only these states: the others are not interpolated */
              static const int dense[] = {{DK_DENSE_ROWS}};
              for (size_t i = 0; i < sizeof dense / sizeof dense[0]; ++i) {{
                const int j = dense[i];
                ys[j] = r1[j] + th * (r2[j] + th1 * (r3[j] + th * (r4[j] + th1 * r5[j])));
              }}
#else
              for (int j = 0; j < NS; ++j) ys[j] = r1[j] + th * (r2[j] + th1 * (r3[j] + th * (r4[j] + th1 * r5[j])));
#endif
            }}
#ifdef DK_PROJECT
            if (dk_project(ys)) {{ emit(user, next, ys); reset = next; ++next; break; }}
#endif
            emit(user, next, ys);
            ++next;
          }}
        }}
#endif
        memcpy(y, y1, sizeof y); memcpy(k1, k7, sizeof k1);
        double fac = fac11 / pow(facold, beta);
        fac = fmax(facc2, fmin(facc1, fac / safe));
        double hnew = h / fac;
        if (rejected) hnew = fmin(hnew, h);
        facold = fmax(err, 1e-4);
        rejected = 0;
        t = tn;
        h = hnew;
#ifdef DK_PROJECT
        if (reset >= 0) {{ memcpy(y, ys, sizeof y); break; }}  /* start again from the projected state there */
#endif
      }} else {{
        ++nrej;
        rejected = 1;
        h = h / fmin(facc1, (err == err ? fac11 : 1e3) / safe);
      }}
    }}
    k = reset >= 0 ? reset : kend;
  }}
  stats[0] = (double)c.nfev; stats[1] = (double)nacc; stats[2] = (double)nrej; stats[3] = (double)stop;
  return status;
}}

typedef struct {{ dk_ctx *c; double *R; }} dk_rec_user;

static void dk_emit_record(void *user, long k, const double *s) {{
  dk_rec_user *u = (dk_rec_user *)user;
  dk_record(u->c, k, s, u->R + (size_t)k * NREC);
}}

int dk_dopri5(const double *s0, const double *W, const double *brk, long N, double dt, double rtol,
              double atol, long max_steps, double *R, double *stats, const double *G) {{
  dk_ctx c;
  memset(&c, 0, sizeof c);
  c.W = W; c.dt = dt; c.G = G;
  dk_rec_user u = {{&c, R}};
  int status = dk_integrate(&c, s0, brk, N, rtol, atol, max_steps, dk_emit_record, &u, stats);
  for (long j = (long)stats[3]; j < N; ++j)
    for (int i = 0; i < NREC; ++i) R[(size_t)j * NREC + i] = NAN;
  return status;
}}
"""
"""The driver's C source, formatted with the sizes of the generated functions (``str.format``)."""
