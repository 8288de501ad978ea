"""CVODES over the whole output grid in one call, for smooth loops, its right-hand side and Jacobian in C.

For a smooth loop (:mod:`designkit.simulation.regime`) on ``numerics.integrator: cvodes`` (given, or chosen for a
stiff loop by :mod:`designkit.simulation.timing`), one CasADi integrator (SUNDIALS' CVODES) integrates the closed
loop ``s' = f(s, r(t), q)`` of :func:`designkit.simulation.dopri5.loop_functions` over the whole output grid:

* **Inputs per output interval** (CasADi's piecewise-constant ``u``, one column per interval ``[t_k, t_k+1]``):
  the interval's start ``t_k``, the reference's three stage columns (``t_k``, ``t_k + dt/2``, ``t_k + dt``) and the
  held inputs ``q`` (noise, disturbance, feedforward, true-plant parameters).  Inside the interval the reference
  is the quadratic through the three stage columns, as for the per-step CVODES step
  (:func:`designkit.simulation.integrate.variable_step`) and the Dormand--Prince pair, so every integrator
  simulates the same loop.  A column equal to the previous one (a constant reference and held values) does not
  stop the integration: CVODES steps across the grid and writes the grid from its interpolating polynomial.  A
  column that changes stops a step exactly on ``t_k`` (CasADi's integrator never steps past a change of ``u``):
  every breakpoint -- a perturbation, a plant change, a jump of the reference, a trial's feedforward -- is
  landed on, and a reference that moves in time stops a step at every grid point.
* **Method** (``numerics.cvodes_method``, :func:`choose_method`): BDF (orders 1-5, Newton iteration on the
  Jacobian) for a stiff loop, Adams--Moulton (orders 1-12) for a loop that is not.  Adams takes fixed-point
  iteration (no Jacobian) when the fastest pole is within :data:`FIXED_POINT_RATIO` of the median, Newton
  iteration otherwise (a fast pole would make the fixed-point iteration limit the step).
* **Compiled** (``numerics.compile`` not ``never`` and a C compiler): the right-hand side (as CasADi's integrator
  calls it, ``daeF``), its Jacobian in the state (``jacF``, only when Newton iteration needs it) and the record
  are generated to C by CasADi and compiled into one library, cached under a hash of its source
  (:func:`designkit.cache.cache_dir` ``("codegen")``); the integrator is built on the library's ``dae`` through
  :func:`casadi.external`, whose ``factory`` takes ``daeF`` and ``jacF`` from the same library.  The right-hand
  side and the record at :data:`FLAGS`; the Jacobian, called only when CVODES sets up its linear solver and
  about eight times the right-hand side's code on the PUMA 560, at :data:`JACOBIAN_FLAGS`.  Otherwise the same
  integrator runs on CasADi's interpreted functions, to the same numbers (compiling buys 6.2 times on the PUMA,
  2.2 times on SIMNOG, whose right-hand side is small).
* **Stretches**: a run is one integrator call per stretch between breakpoints, CVODES started afresh at each
  (:class:`CvodesGrid`).
* **Failure**: CVODES giving up (``CV_TOO_MUCH_WORK`` after :data:`MAX_STEPS_PER_OUTPUT` steps in one output
  interval, an error test or convergence failing at the smallest step, a right-hand side that is not finite)
  ends the run: the records are NaN from the first grid point it did not reach, and the failure says where and
  why.  A state beyond :data:`DIVERGED` makes the right-hand side NaN (a diverged loop), as for the other
  integrators.
"""

from __future__ import annotations

import hashlib
import os
import subprocess
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from designkit.simulation.dopri5 import _compiler, breakpoints, loop_functions
from designkit.simulation.integrate import DIVERGED

__all__ = ["FIXED_POINT_RATIO", "FLAGS", "IGNORED_METHOD", "JACOBIAN_FLAGS", "METHODS", "CvodesGrid", "Method",
           "build_cvodes_grid", "choose_method", "cvodes_for"]

METHODS = ("auto", "adams", "bdf")
"""Values of ``numerics.cvodes_method``."""
IGNORED_METHOD = ("numerics.cvodes_method (it chooses the method of CVODES over the whole grid, which runs only on a "
                  "smooth loop with numerics.integrator: cvodes)")
"""The settings' words when ``numerics.cvodes_method`` is given and does not apply."""
STIFF_RATIO = 100.0
"""A pole faster than this times the median pole is stiff (:data:`designkit.simulation.timing.STIFF_RATIO`)."""
FIXED_POINT_RATIO = 10.0
"""Adams takes fixed-point iteration when ``|p|max <= FIXED_POINT_RATIO |p|med``, else Newton iteration.  Measured
(``benchmarks/bench_cvodes.py``): on the PUMA 560 under computed torque (``|p|max = |p|med = 20 1/s``) fixed-point
iteration takes 0.74 of Newton's time (no Jacobian of 23,500 instructions to evaluate), on the SIMNOG arm under
decentralized PID (``|p|max = 162``, ``|p|med = 5 1/s``) 15 times Newton's (36 times the steps: the fast pole
bounds a fixed-point iteration's step)."""
RECORD_CHUNK = 1024
"""Grid points per evaluation of the mapped record function (CasADi writes the map as a loop: its code does not
grow with the chunk; the last chunk is padded)."""
KEPT_INTEGRATORS = 16
"""Integrators kept per run length (a run with breakpoints needs one per length of its stretches)."""
WORK = ("nsteps", "nfevals", "nlinsetups", "netfails", "nncfails")
"""CVODES' counters summed over a run's stretches."""
MAX_STEPS_PER_OUTPUT = 10_000
"""CVODES' ``mxstep``: at most this many steps between two grid points, then ``CV_TOO_MUCH_WORK`` ends the run."""
FLAGS = ("-O1", "-ffp-contract=off", "-fPIC")
"""Compiler flags of the right-hand side and the record (an object file; linked with ``-shared``)."""
JACOBIAN_FLAGS = ("-O0", "-fPIC")
"""Compiler flags of the Jacobian: called only at CVODES' linear-solver setups (a few hundred times a run), so a
fast compile pays more than fast code once per loop (PUMA 560, ``benchmarks/bench_cvodes.py``: 3.0 s to compile
against 9.5 s at ``-O1``, for an Adams-Newton run of 53 ms against 27 ms; the PUMA's own choice, fixed-point
iteration, compiles no Jacobian)."""


@dataclass(frozen=True)
class Method:
    """The CVODES method of a run.

    Parameters
    ----------
    name : {"adams", "bdf"}
        Linear multistep method.
    iteration : {"functional", "newton"}
        Nonlinear iteration (CasADi's names; ``functional`` is fixed-point iteration, no Jacobian).
    why : str
        Why, in words.
    """

    name: str
    iteration: str
    why: str

    @property
    def words(self) -> str:
        """The method in words."""
        what = "BDF, orders 1-5" if self.name == "bdf" else "Adams-Moulton, orders 1-12"
        how = "fixed-point iteration" if self.iteration == "functional" else "Newton iteration on the Jacobian"
        return f"{what}, {how}"


def choose_method(requested: str, fast: float, median: float) -> Method:
    """The :class:`Method` for ``numerics.cvodes_method = requested`` on a loop whose fastest pole is ``fast`` and
    whose median pole is ``median`` (moduli, 1/s; ``median`` 0 when unknown).

    ``bdf`` always takes Newton iteration.  ``auto`` takes BDF when a pole is stiff (``fast > 100 median``), else
    Adams.  Adams takes fixed-point iteration when ``fast <= FIXED_POINT_RATIO median``, else Newton.
    """
    if requested not in METHODS:
        raise ValueError(f"cvodes method must be one of {METHODS}, got {requested!r}")
    ratio = fast / median if median > 0 else float("inf")
    poles = (f"|p|max = {fast:.4g} 1/s, |p|med = {median:.4g} 1/s" if median > 0
             else f"|p|max = {fast:.4g} 1/s, no median pole known")
    if requested == "bdf" or (requested == "auto" and ratio > STIFF_RATIO):
        why = ("numerics.cvodes_method: bdf" if requested == "bdf" else
               f"numerics.cvodes_method: auto, BDF because the loop is stiff ({poles}: |p|max > {STIFF_RATIO:g} "
               "|p|med)")
        return Method("bdf", "newton", why)
    source = ("numerics.cvodes_method: adams" if requested == "adams" else
              f"numerics.cvodes_method: auto, Adams because no pole is stiff ({poles}: |p|max <= {STIFF_RATIO:g} "
              "|p|med)")
    if ratio <= FIXED_POINT_RATIO:
        return Method("adams", "functional", f"{source}; fixed-point iteration because |p|max <= "
                                             f"{FIXED_POINT_RATIO:g} |p|med (no Jacobian)")
    return Method("adams", "newton", f"{source}; Newton iteration because |p|max > {FIXED_POINT_RATIO:g} |p|med "
                                     "(a fast pole would bound a fixed-point iteration's step)")


def loop_dae(rhs: ca.Function, n_ref: int, dt: float, *, jacobian: bool) -> dict[str, ca.Function]:
    """CasADi's integrator functions of the loop ``rhs(s, a, q)``: ``dae`` (the oracle, SX), and for the generated
    library ``dae_mx`` (the oracle calling ``daeF``, so the C holds the right-hand side once), ``daeF`` and, with
    ``jacobian``, ``jacF`` (the names and signatures the integrator's ``factory`` asks for).

    ``u = (t_k, a0, am, a1, q)``: the reference is the quadratic through ``a0, am, a1`` at ``tau = (t - t_k) / dt``
    (clamped to ``[0, 1]``).
    """
    ns, nq = rhs.size1_in(0), rhs.size1_in(2)
    t, x, u = ca.SX.sym("t"), ca.SX.sym("x", ns), ca.SX.sym("u", 1 + 3 * n_ref + nq)
    z, p = ca.SX.sym("z", 0), ca.SX.sym("p", 0)
    tk, a0, am, a1, q = ca.vertsplit(u, np.cumsum([0, 1, n_ref, n_ref, n_ref, nq]).tolist())
    tau = ca.fmin(ca.fmax((t - tk) / dt, 0.0), 1.0)
    a = 2 * (tau - 0.5) * (tau - 1) * a0 - 4 * tau * (tau - 1) * am + 2 * tau * (tau - 0.5) * a1
    finite = ca.sum1(ca.fabs(x)) < DIVERGED  # False for NaN and inf: a diverged state stops CVODES
    ode = ca.if_else(finite, rhs(x, a, q), ca.DM(np.full(ns, np.nan)), True)
    names = ["t", "x", "z", "p", "u"]
    dae_f = ca.Function("daeF", [t, x, z, p, u], [ode, ca.SX(0, 1)], names, ["ode", "alg"])
    mx = [ca.MX.sym(n, dae_f.sparsity_in(i)) for i, n in enumerate(names)]
    ode_mx, alg_mx = dae_f(*mx)
    outs = ["ode", "alg", "quad", "zero"]
    out = {"dae": ca.Function("dae", [t, x, z, p, u], [ode, ca.SX(0, 1), ca.SX(0, 1), ca.SX(0, 1)], names, outs),
           "dae_mx": ca.Function("dae", mx, [ode_mx, alg_mx, ca.MX(0, 1), ca.MX(0, 1)], names, outs),
           "daeF": dae_f}
    if jacobian:
        blocks = [ca.jacobian(ode, x), ca.SX(0, ns), ca.SX(ns, 0), ca.SX(0, 0)]
        out["jacF"] = ca.Function("jacF", [t, x, z, p, u], blocks, names,
                                  ["jac_ode_x", "jac_alg_x", "jac_ode_z", "jac_alg_z"])
    return out


def _source(name: str, functions: list[ca.Function]) -> str:
    """CasADi's C of ``functions``; ``name`` prefixes its helper symbols (two parts link into one library)."""
    gen = ca.CodeGenerator(f"{name}.c", {"with_header": False, "verbose": False})
    for f in functions:
        gen.add(f)
    return gen.dump()


def _library(parts: list[tuple[str, tuple[str, ...]]], cc: str) -> tuple[Path, bool] | str:
    """The cached shared library of the C sources ``parts`` (each with its flags), built now if needed, and
    whether it was built now; or why it could not be."""
    from designkit.cache import cache_dir

    key = "\0".join([cc, ca.__version__, *(f"{text}\0{' '.join(flags)}" for text, flags in parts)])
    digest = hashlib.sha256(key.encode()).hexdigest()[:16]
    folder = cache_dir("codegen")
    library = folder / f"dk_cvodes_{digest}.so"
    if library.exists():
        return library, False
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory(dir=folder) as tmp:
            objects = []
            for k, (text, flags) in enumerate(parts):
                c_file, o_file = Path(tmp) / f"part{k}.c", Path(tmp) / f"part{k}.o"
                c_file.write_text(text)
                proc = subprocess.run([cc, *flags, "-c", str(c_file), "-o", str(o_file)], capture_output=True,
                                      text=True)
                if proc.returncode != 0:
                    first = (proc.stderr.strip().splitlines() or ["unknown error"])[0]
                    return f"compilation failed ({cc}): {first}"
                objects.append(str(o_file))
            built = Path(tmp) / "lib.so"
            proc = subprocess.run([cc, "-shared", *objects, "-o", str(built), "-lm"], capture_output=True, text=True)
            if proc.returncode != 0:
                return f"linking failed ({cc}): {(proc.stderr.strip().splitlines() or ['unknown error'])[0]}"
            os.replace(built, library)  # atomic: safe with concurrent builders
    except OSError as exc:
        return f"cannot write to the cache directory {folder}: {exc}"
    return library, True


FAILURES = {
    "CV_TOO_MUCH_WORK": f"more than {MAX_STEPS_PER_OUTPUT:,} steps between two grid points",
    "CV_ERR_FAILURE": "the error test failed repeatedly or at the smallest step",
    "CV_CONV_FAILURE": "the nonlinear iteration failed to converge repeatedly or at the smallest step",
    "CV_LSETUP_FAIL": "the linear solver's setup failed (a singular Jacobian)",
    "CV_LSOLVE_FAIL": "the linear solver failed",
    "CV_RHSFUNC_FAIL": "the right-hand side failed (a state that is not finite, or beyond 1e150: a diverged loop)",
    "CV_FIRST_RHSFUNC_ERR": "the right-hand side failed at the first call (a state that is not finite)",
    "CV_REPTD_RHSFUNC_ERR": "the right-hand side failed repeatedly (a state that is not finite, or beyond 1e150)",
    "CV_UNREC_RHSFUNC_ERR": "the right-hand side failed (a state that is not finite, or beyond 1e150)",
}
"""CVODES' return flags in words."""


def failure_words(message: str) -> str:
    """CasADi's error message of a CVODES failure in words: the flag CVODES returned and what it means."""
    flag = next((word.strip('".,') for word in message.split() if word.strip('".,').startswith("CV_")), "")
    if flag:
        return f"CVODES returned {flag}: {FAILURES.get(flag, 'see the CVODES documentation')}"
    lines = [line.strip() for line in message.strip().splitlines() if line.strip()]
    return lines[-1] if lines else "CVODES failed"


@dataclass(frozen=True, eq=False)
class CvodesGrid:
    """CVODES over an output grid ``t_k = k dt`` (module docstring), compiled or interpreted.

    A run is one integrator call per stretch of the grid between breakpoints
    (:func:`designkit.simulation.dopri5.breakpoints`: a held input that changes, a jump of the reference): each call
    starts CVODES afresh (``CVodeReInit``) from the state the previous one reached.  CasADi's integrator stops on a
    change of ``u`` but keeps CVODES' history across it, and a jump of the right-hand side there makes the BDF's
    error test fail at tight tolerances (``CV_ERR_FAILURE`` at ``rtol = 1e-8`` on a PID link with a load step).
    The loop is autonomous in ``u`` (the reference's ``t_k`` is in ``u``), so the integrator of a stretch of ``L``
    intervals runs on ``0, dt, ..., L dt`` and serves every stretch of that length (kept, at most
    :data:`KEPT_INTEGRATORS`).

    Parameters
    ----------
    oracle : casadi.Function
        The DAE (:func:`loop_dae`'s ``dae``, or the library's through :func:`casadi.external`).
    options : dict
        CasADi's CVODES options.
    records : casadi.Function
        The record ``rec(s, a, q)`` mapped over :data:`RECORD_CHUNK` grid points.
    ns, n_ref : int
        Sizes of the state and of the reference's stage block.
    dt : float
        Output step (s).
    rtol, atol : float
        CVODES' tolerances.
    method : Method
    library : pathlib.Path or None
        The compiled library; None when the functions are interpreted.
    how : str
        ``"compiled now"``, ``"cached library"``, or why the functions are interpreted.
    source, mode : str
        Where the tolerances come from, and ``numerics.compile``, for the settings.
    """

    oracle: ca.Function
    options: dict[str, Any]
    records: ca.Function
    ns: int
    n_ref: int
    dt: float
    rtol: float
    atol: float
    method: Method
    library: Path | None
    how: str
    source: str = "numerics.rtol and numerics.atol"
    mode: str = "auto"
    stats: dict[str, Any] = field(default_factory=dict)
    _kept: dict[int, Any] = field(default_factory=dict, repr=False)
    _records: list[Any] = field(default_factory=list, repr=False)
    _prepared: dict[str, Any] = field(default_factory=dict, repr=False)

    @property
    def compiled_now(self) -> bool:
        """True when this build ran the compiler."""
        return self.how == "compiled now"

    def integrator(self, length: int) -> tuple[ca.Function, Any, Any]:
        """``(integrator, buffer, evaluate)`` over ``0, dt, ..., length dt`` (built once per length, kept)."""
        if length not in self._kept:
            if len(self._kept) >= KEPT_INTEGRATORS:
                self._kept.pop(next(iter(self._kept)))
            f = ca.integrator("dk_cvodes", "cvodes", self.oracle, 0.0, [k * self.dt for k in range(length + 1)],
                              self.options)
            self._kept[length] = (f, *f.buffer())  # kept: the evaluation closure needs its buffer alive
        return self._kept[length]

    def segments(self, inputs: np.ndarray) -> list[tuple[int, int, np.ndarray]]:
        """``(a, b, U)`` per stretch ``[t_a, t_b]`` between breakpoints: ``U`` the integrator's ``u``, C-contiguous
        ``(b - a + 1, 1 + nw)`` (row ``j``: CasADi's column ``j``, which holds over ``(t_a+j-1, t_a+j]``).

        Interval ``k`` carries ``(t_k - t_a, w_k)``; row 0 (an empty interval) repeats row 1.  An interval whose three
        stage columns are equal (a constant reference) carries the previous interval's ``t_k``: its reference does
        not depend on ``tau``, and an unchanged column does not stop the integration.
        """
        nw, n = inputs.shape
        a0, am, a1 = (inputs[j * self.n_ref:(j + 1) * self.n_ref] for j in range(3))
        moving = np.any(a0 != am, axis=0) | np.any(a0 != a1, axis=0)
        origin = np.maximum.accumulate(np.where(moving, np.arange(n), 0))
        cuts = [0, *np.flatnonzero(breakpoints(inputs, self.n_ref)).tolist(), n - 1]
        out = []
        for a, b in zip(cuts[:-1], cuts[1:], strict=True):
            if b <= a:
                continue
            U = np.empty((b - a + 1, 1 + nw))
            U[1:, 0] = (np.maximum(origin[a:b], a) - a) * self.dt
            U[1:, 1:] = inputs[:, a:b].T
            U[0] = U[1]
            out.append((a, b, U))
        return out

    def _prepare(self, inputs: np.ndarray) -> tuple[list[tuple[int, int, np.ndarray]], np.ndarray, np.ndarray]:
        """``(segments, A, Q)``: the stretches and the record's reference and held inputs, one row per grid point
        (padded to whole chunks of :data:`RECORD_CHUNK`).  The same array object passed again is taken as unchanged
        (a simulator's own inputs, run again)."""
        prepared = self._prepared.get("inputs")
        if prepared is not None and prepared[0] is inputs:
            return prepared[1]
        n = inputs.shape[1]
        rows = -(-n // RECORD_CHUNK) * RECORD_CHUNK
        A, Q = (np.zeros((rows, m)) for m in (self.n_ref, inputs.shape[0] - 3 * self.n_ref))
        A[:n], Q[:n] = inputs[:self.n_ref].T, inputs[3 * self.n_ref:].T
        self._prepared["inputs"] = (inputs, (self.segments(inputs), A, Q))
        return self._prepared["inputs"][1]

    def run(self, z0: np.ndarray, inputs: np.ndarray, failure: dict[str, Any] | None = None) -> np.ndarray:
        """Records ``(nrec, N)`` of the run from ``z0`` (its first ``ns`` entries) over the columns of ``inputs``.

        ``failure`` (when given) receives ``step`` (the first grid index not reached) and ``error`` when CVODES
        stopped early; the records are NaN from there.  Without it the error propagates.  After changing an
        inputs array in place, pass a new view of it (the prepared stretches of the same object are reused).
        """
        n = inputs.shape[1]
        segments, A, Q = self._prepare(inputs)
        X = np.full((A.shape[0], self.ns), np.nan)  # CasADi writes each grid point as it reaches it
        X[0] = np.asarray(z0, dtype=float)[:self.ns]
        totals = dict.fromkeys(WORK, 0)
        error = ""
        for a, b, U in segments:
            _, buf, evaluate = self.integrator(b - a)
            s0 = X[a].copy()
            buf.set_arg(0, memoryview(s0))
            buf.set_arg(3, memoryview(U.ravel()))
            buf.set_res(0, memoryview(X[a:b + 1].ravel()))
            try:
                evaluate()
            except RuntimeError as exc:
                if failure is None:
                    raise
                error = failure_words(str(exc))
            stats = buf.stats()
            for key in WORK:
                totals[key] += int(stats.get(key, 0))
            if error:
                break
        self.stats.clear()
        self.stats.update(totals, segments=len(segments), failed=bool(error))
        bad = ~(np.abs(X[:n]).sum(axis=1) < DIVERGED)  # NaN compares False
        stop = int(np.argmax(bad)) if bad.any() else n
        if stop < n and failure is not None:
            failure.update(step=stop, error=error or f"the state left {DIVERGED:g} in magnitude (a diverged loop)")
        X[stop:] = 0.0  # the records there are NaN; the record function is not evaluated on NaN
        R = np.empty((A.shape[0], self.records.size1_out(0)))
        if not self._records:  # kept: the evaluation closure needs its buffer alive
            self._records.extend(self.records.buffer())
        rbuf, revaluate = self._records
        for j in range(0, A.shape[0], RECORD_CHUNK):
            for k, arg in enumerate((X, A, Q)):
                rbuf.set_arg(k, memoryview(arg[j:j + RECORD_CHUNK].ravel()))
            rbuf.set_res(0, memoryview(R[j:j + RECORD_CHUNK].ravel()))
            revaluate()
        R[stop:] = np.nan
        return R[:n].T

    def work_words(self, n_steps: int) -> str:
        """The last run's work, in words."""
        s = self.stats
        jac = (f" and {int(s.get('nlinsetups', 0)):,} of its Jacobian (each factorized)"
               if self.method.iteration == "newton" else "")
        parts = int(s.get("segments", 1))
        restarts = ("" if parts < 2 else ", CVODES started afresh at the breakpoint" if parts == 2
                    else f", CVODES started afresh at each of {parts - 1:,} breakpoints")
        return (f"{int(s.get('nfevals', 0)):,} evaluations of the right-hand side{jac} in {int(s.get('nsteps', 0)):,} "
                f"CVODES steps ({int(s.get('netfails', 0)):,} error-test failures, {int(s.get('nncfails', 0)):,} "
                f"convergence failures) over the {n_steps:,} output steps{restarts}"
                + ("; counted up to the last grid point reached" if s.get("failed") else ""))

    @property
    def compile_info(self) -> dict[str, Any]:
        """How it is evaluated, for :attr:`designkit.simulation.run.Simulator.compiled`."""
        info = {"mode": self.mode, "compiled": self.library is not None, "integrator": "cvodes", "why": self.how}
        if self.library is not None:
            info["flags"] = " ".join(FLAGS)
            if self.method.iteration == "newton":
                info["jacobian_flags"] = " ".join(JACOBIAN_FLAGS)
        return info

    @property
    def settings_words(self) -> str:
        """The integrator in words, for the settings."""
        ran = "compiled C" if self.library is not None else f"interpreted: {self.how}"
        return (f"cvodes (CVODES over the whole output grid in one call: {self.method.words}; rtol {self.rtol:g}, "
                f"atol {self.atol:g}, {self.source}; the grid written from CVODES' interpolating polynomial, every "
                f"breakpoint and every change of the reference's interval ended on exactly; {self.method.why}; "
                f"{ran})")


def build_cvodes_grid(plant: Any, law: Any, element: Any, time: np.ndarray, *, rtol: float, atol: float,
                      method: Method, compile: bool = True, source: str = "numerics.rtol and numerics.atol",
                      mode: str = "auto") -> CvodesGrid:
    """The :class:`CvodesGrid` of the smooth loop ``plant`` under ``law`` with ``element`` over the grid ``time``.

    Parameters
    ----------
    plant, law, element
        The true plant, the law and the nonlinear element (a continuous memoryless one).
    time : ndarray, shape (N,)
        The output grid ``t_k = k dt`` (s).
    rtol, atol : float
        CVODES' tolerances (atol in state units).
    method : Method
        From :func:`choose_method`.
    compile : bool
        Generate and compile the C library (or load it from the cache); False: interpreted.
    source, mode : str
        Where the tolerances come from, and ``numerics.compile``, for the settings.
    """
    rhs, rec, _, n_ref = loop_functions(plant, law, element)
    n = int(time.size)
    dt = float(time[1] - time[0]) if n > 1 else 1.0
    newton = method.iteration == "newton"
    functions = loop_dae(rhs, n_ref, dt, jacobian=newton)
    cc = _compiler()
    how = "numerics.compile: never" if not compile else "no C compiler on PATH" if cc is None else ""
    library = None
    if not how and cc is not None:
        records = rec.map("dk_records", "serial", RECORD_CHUNK, [], [])
        parts = [(_source("dk_cvodes_rhs", [functions["daeF"], functions["dae_mx"], records]), FLAGS)]
        if newton:
            parts.append((_source("dk_cvodes_jac", [functions["jacF"]]), JACOBIAN_FLAGS))
        built = _library(parts, cc)
        if isinstance(built, str):
            how = built
        else:
            library, now = built
            how = "compiled now" if now else "cached library"
    opts = {"reltol": float(rtol), "abstol": float(atol), "linear_multistep_method": method.name,
            "nonlinear_solver_iteration": method.iteration, "max_num_steps": MAX_STEPS_PER_OUTPUT,
            "show_eval_warnings": False, "disable_internal_warnings": True}
    if library is not None:
        # the oracle's factory takes daeF and jacF from the library; without Newton iteration no Jacobian is ever
        # evaluated (CVODES sets up no linear solver), and enable_fd only lets CasADi build its unused jacF
        oracle = ca.external("dae", str(library), {"enable_fd": not newton})
        records = ca.external("dk_records", str(library))
    else:
        oracle, records = functions["dae"], rec.map("dk_records", "serial", RECORD_CHUNK, [], [])
    return CvodesGrid(oracle=oracle, options=opts, records=records, ns=rhs.size1_in(0), n_ref=n_ref, dt=dt,
                      rtol=float(rtol), atol=float(atol), method=method, library=library, how=how, source=source,
                      mode=mode)


def cvodes_for(numerics: Any, timing: Any, regime: Any, rates: Any, plant: Any, law: Any, element: Any,
               time: np.ndarray) -> CvodesGrid | None:
    """The :class:`CvodesGrid` of a smooth loop (``regime.smooth``) on ``numerics.integrator: cvodes`` (given, or
    chosen by ``timing``), else None: its method chosen from ``numerics.cvodes_method`` and the loop's ``rates``
    (:class:`designkit.simulation.timing.Rates`), its tolerances ``numerics.rtol`` and ``numerics.atol``, compiled
    unless ``numerics.compile: never``."""
    if timing.integrator != "cvodes" or not regime.smooth or getattr(regime, "resets", False):
        return None
    method = choose_method(numerics.cvodes_method, rates.fast, rates.median)
    source = ("numerics.rtol and numerics.atol" if {"rtol", "atol"} & numerics.model_fields_set
              else "the numerics defaults")
    return build_cvodes_grid(plant, law, element, time, rtol=numerics.rtol, atol=numerics.atol, method=method,
                             compile=numerics.compile != "never", source=source, mode=numerics.compile)
