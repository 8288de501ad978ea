"""Dormand--Prince 5(4) with error control and dense output, compiled, over the whole output grid.

For a smooth loop (:mod:`designkit.simulation.regime`) the closed loop's right-hand side
``s' = f(s, r(t), q)`` (``s = (x, xc)``, ``r`` the reference, ``q`` the held inputs: noise, disturbance,
feedforward, true-plant parameters) and its record at a grid point are generated to C by CasADi, and a C
driver (:mod:`designkit.simulation.dopri5_c`) integrates the whole run in one call: adaptive steps that cross
grid points freely, the grid written from the pair's continuous extension, every breakpoint (an instant where
a held input changes: a perturbation, a plant change, a jump of the reference; found from the per-step inputs
by :func:`breakpoints`) ended on exactly.  No Python per step, and no fixed step: the number of evaluations is
set by the tolerances, not by the grid.

Tolerances: ``numerics.rtol`` and ``numerics.atol`` when the spec gives them, else :data:`RTOL` and
:data:`ATOL` (about what RK4 on the default grid, ``dt |p|max = 0.02``, reaches).  The library is built by the
system C compiler (:data:`FLAGS`) and cached under a hash of its source (:func:`designkit.cache.cache_dir`
``("codegen")``).  The loop's constants (the law's gains, the element's limits, the numbers of the reference's
interpolation) are lifted out of the generated code into an array the run passes
(:func:`designkit.simulation.lifted.lift_constants`), so loops of one structure -- a study's variants of a law --
share one library, compiled once, and give the numbers their own library would.  With ``numerics.compile:
never`` or without a compiler the same algorithm runs interpreted
(:mod:`designkit.simulation.dopri5_py`: CasADi's virtual machine for the right-hand side, a Python loop per
step).
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import shutil
import subprocess
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from designkit.simulation.dopri5_c import DRIVER
from designkit.simulation.step import _feedforward, layout

__all__ = ["ATOL", "FLAGS", "RTOL", "Dopri5", "breakpoints", "build_dopri5"]

RTOL = 1e-10
"""Default relative tolerance of the pair (``numerics.rtol`` not given)."""
ATOL = 1e-12
"""Default absolute tolerance (state units: rad, rad/s, and the controller's states)."""
FLAGS = ("-O1", "-ffp-contract=off", "-fPIC", "-shared")
"""Compiler flags: ``-O1`` compiles a two-link right-hand side in a few tenths of a second (higher levels cost
more to compile than they save on a run of a few thousand evaluations); no fused multiply-add, so the compiled
run gives the interpreted driver's numbers (:mod:`designkit.simulation.dopri5_py`)."""
MAX_STEPS_PER_SAMPLE = 50
"""Step budget: at most this many attempted steps per output step (plus 10,000), then the run stops."""


@dataclass(frozen=True, eq=False)
class Dopri5:
    """A compiled Dormand--Prince run over a grid.

    Parameters
    ----------
    library : pathlib.Path or None
        The shared library; None: the interpreted driver (:mod:`designkit.simulation.dopri5_py`) runs.
    rhs, rec : casadi.Function
        ``dk_rhs(s, a, q) -> s_dot`` and ``dk_rec(s, a, q) -> record`` (interpreted).
    ns, nw, nrec : int
        Sizes of the integrated state ``(x, xc)``, of a per-step input column and of a record.
    n_ref : int
        Rows of the reference in each of the three stage blocks of ``w`` (``3 n``).
    dt : float
        Output step (s).
    rtol, atol : float
        Tolerances.
    compiled_now : bool
        True when this build ran the compiler (False: the library was cached).
    proj : casadi.Function or None
        ``dk_proj(s) -> s``: the law's projection of the controller states (``Law.project_resets``), applied at
        every grid instant; where it moves the state, the run starts again from the projected state there (a
        fresh derivative, as at a breakpoint).  None: no projection.
    constants : ndarray
        The loop's constants the library reads (the last input of its lifted ``dk_rhs`` and ``dk_rec``); empty for
        a library compiled with its constants written in.
    """

    library: Path | None
    rhs: ca.Function
    rec: ca.Function
    ns: int
    nw: int
    nrec: int
    n_ref: int
    dt: float
    rtol: float
    atol: float
    compiled_now: bool = False
    proj: ca.Function | None = None
    constants: np.ndarray = field(default_factory=lambda: np.zeros(0))
    stats: dict[str, float] = field(default_factory=dict)
    _lib: list = field(default_factory=list, repr=False)
    _prepared: dict = field(default_factory=dict, repr=False)

    def _entry(self) -> Any:
        if not self._lib:
            lib = ctypes.CDLL(str(self.library))
            fn = lib.dk_dopri5
            vec = np.ctypeslib.ndpointer(dtype=np.float64, flags="C_CONTIGUOUS")
            fn.argtypes = [vec, vec, vec, ctypes.c_long, ctypes.c_double, ctypes.c_double, ctypes.c_double,
                           ctypes.c_long, vec, vec, vec]
            fn.restype = ctypes.c_int
            self._lib.extend([lib, fn])
        return self._lib[1]

    def run(self, z0: np.ndarray, inputs: np.ndarray, failure: dict[str, Any] | None = None) -> np.ndarray:
        """Records ``(nrec, N)`` of the run from ``z0`` (its first ``ns`` entries) over the columns of ``inputs``.

        ``failure`` (when given) receives ``step`` and ``error`` if the integration stopped early (step size
        underflow, step budget, a state beyond 1e150): the records are NaN from there.  The same array object
        passed again is taken as unchanged (its transpose and breakpoints are kept: a simulator's own inputs,
        run again); after changing an array in place, pass a new view of it (``buf.T`` is one per call).
        """
        nw, n = inputs.shape
        prepared = self._prepared.get("inputs")
        if prepared is not None and prepared[0] is inputs:  # the simulator's own inputs, run again
            W, brk = prepared[1], prepared[2]
        else:
            W, brk = np.ascontiguousarray(inputs.T, dtype=float), breakpoints(inputs, self.n_ref)
            self._prepared["inputs"] = (inputs, W, brk)
        s0 = np.ascontiguousarray(np.asarray(z0, dtype=float)[: self.ns])
        R = np.empty((n, self.nrec))
        stats = np.zeros(4)
        budget = MAX_STEPS_PER_SAMPLE * n + 10_000
        if self.library is None:
            from designkit.simulation.dopri5_py import run_interpreted

            R, count, stop = run_interpreted(self.rhs, self.rec, s0, W, brk, self.dt, self.rtol, self.atol, budget,
                                             proj=self.proj)
            self.stats.update(count)
            status = int(stop < n)
        else:
            G = np.ascontiguousarray(self.constants if self.constants.size else np.zeros(1), dtype=float)
            status = self._entry()(s0, W, brk, n, self.dt, self.rtol, self.atol, budget, R, stats, G)
            self.stats.update(evaluations=int(stats[0]), accepted=int(stats[1]), rejected=int(stats[2]))
            stop = int(stats[3])
        if status and failure is not None:
            failure.update(step=stop - 1, error="the Dormand-Prince step size fell below 1e-14 s or its "
                           f"budget of {budget} steps ran out (a diverging or stiff loop)")
        return R.T


def breakpoints(inputs: np.ndarray, n_ref: int) -> np.ndarray:
    """``1.0`` at every grid index where a held input changes (the integration must stop there), else 0.

    A held input is any row of ``w`` after the reference (noise, disturbance, sample flag, feedforward,
    parameters); the reference jumps where a step's start differs from the previous step's end.
    """
    n = inputs.shape[1]
    brk = np.zeros(n)
    if n < 2:
        return brk
    held = inputs[3 * n_ref:]
    changed = np.any(held[:, 1:] != held[:, :-1], axis=0)
    r0, r1 = inputs[:n_ref, 1:], inputs[2 * n_ref:3 * n_ref, :-1]
    scale = 1.0 + np.abs(r0)
    jump = np.any(np.abs(r0 - r1) > 1e-12 * scale, axis=0)
    brk[1:] = (changed | jump).astype(float)
    return brk


def projection_function(ns: int, law: Any) -> ca.Function:
    """``dk_proj(s) -> s``: the integrated state ``s = (x, xc)`` with the law's projection of ``xc`` (``x``
    unchanged)."""
    s = ca.SX.sym("s", ns)
    nc = law.project.size1_in(0)
    x, xc = s[:ns - nc], s[ns - nc:]
    return ca.Function("dk_proj", [s], [ca.vertcat(x, law.project(xc))], ["s"], ["s_projected"])


def loop_functions(plant: Any, law: Any, element: Any) -> tuple[ca.Function, ca.Function, int, int]:
    """``(rhs, rec, nw, n_ref)``: ``dk_rhs(s, a, q) -> s_dot`` and ``dk_rec(s, a, q) -> record`` of the loop."""
    L = layout(plant, law, element, 0)
    n_ref = 3 * L.n
    nq = L.nx + L.nd + 1 + L.nu + L.np_
    s, a, q = ca.SX.sym("s", L.nx + L.nc), ca.SX.sym("a", n_ref), ca.SX.sym("q", nq)
    _noise, dist, _flag, uff, p = ca.vertsplit(q, np.cumsum([0, L.nx, L.nd, 1, L.nu, L.np_]).tolist())
    x, xc = s[:L.nx], s[L.nx:]
    m, e = ca.SX(0, 1), ca.SX(0, 1)
    # The pair runs only loops without measurement noise (regime_of), so the law measures the state itself: its
    # terms of x (the gravity feed-forward's sines) are then the plant's, which the common-subexpression pass
    # below computes once.  The noise rows stay in the held inputs' layout, unread.
    y = x
    command = law.command(y, xc, m, a) + _feedforward(law, y, xc, m, a, uff)
    u = element.function(command, e)[0]
    gate = law.gate(y, xc, m, a)
    s_dot = ca.vertcat(plant.ode()(x, u, dist, p), law.derivative(y, xc, m, a, gate))
    signals = law.signals(y, xc, m, a) if law.signals is not None else ca.SX(0, 1)
    record = ca.vertcat(x, xc, command, u, y, dist, signals)
    rhs = ca.Function("dk_rhs", [s, a, q], [ca.cse(s_dot)], ["s", "a", "q"], ["s_dot"])
    rec = ca.Function("dk_rec", [s, a, q], [ca.cse(record)], ["s", "a", "q"], ["record"])
    return rhs, rec, n_ref + n_ref + n_ref + nq, n_ref


def source(rhs: ca.Function, rec: ca.Function, nw: int, n_ref: int, extra: tuple[ca.Function, ...] = (),
           proj: ca.Function | None = None) -> str:
    """The C source of the library: CasADi's code of ``rhs``, ``rec`` (and of the ``extra`` functions, and of
    the projection ``proj``, in the same generated unit), then the driver."""
    gen = ca.CodeGenerator("dk_loop.c", {"with_header": False, "verbose": False})
    for f in (rhs, rec, *extra, *((proj,) if proj is not None else ())):
        gen.add(f)
    sizes = {"ns": rhs.size1_in(0), "na": n_ref, "nw": nw, "nrec": rec.size1_out(0)}
    for tag, f in (("rhs", rhs), ("rec", rec)):
        sizes.update({f"{tag}_arg": f.sz_arg(), f"{tag}_res": f.sz_res(), f"{tag}_iw": f.sz_iw(),
                      f"{tag}_w": f.sz_w()})
    head = ""
    if proj is not None:
        head = (f"#define DK_PROJECT\n#define PROJ_ARG {proj.sz_arg()}\n#define PROJ_RES {proj.sz_res()}\n"
                f"#define PROJ_IW {proj.sz_iw()}\n#define PROJ_W {proj.sz_w()}\n")
    return gen.dump() + head + DRIVER.format(**sizes)


def _compiler() -> str | None:
    for name in ("cc", "gcc", "clang"):
        path = shutil.which(name)
        if path:
            return path
    return None


def _library(text: str, cc: str, flags: tuple[str, ...] = FLAGS) -> tuple[Path, bool] | str:
    """The cached library of ``text`` built with ``flags`` (built now if needed) and whether it was built now, or
    why not."""
    from designkit.cache import cache_dir

    digest = hashlib.sha256("\0".join([text, cc, *flags, ca.__version__]).encode()).hexdigest()[:16]
    folder = cache_dir("codegen")
    library = folder / f"dk_dopri5_{digest}.so"
    if library.exists() and _hold(library):
        return library, False
    try:
        folder.mkdir(parents=True, exist_ok=True)
        c_file = library.with_suffix(".c")
        c_file.write_text(text)
        fd, tmp = tempfile.mkstemp(suffix=".so", dir=folder)
        os.close(fd)
        proc = subprocess.run([cc, *flags, str(c_file), "-o", tmp, "-lm"], capture_output=True, text=True)
        if proc.returncode != 0:
            os.unlink(tmp)
            return f"compilation failed ({cc}): {(proc.stderr.strip().splitlines() or ['unknown error'])[0]}"
        os.replace(tmp, library)  # atomic: safe with concurrent builders
    except OSError as exc:
        return f"cannot write to the cache directory {folder}: {exc}"
    if not _hold(library):
        return f"the library built in {folder} was removed before it could be loaded"
    return library, True


_HELD: dict[str, ctypes.CDLL] = {}
"""Every library handed out, loaded in this process and kept loaded: the cache folder is shared, and another
process pruning it (``designkit.models.codegen`` removes the oldest libraries by modification time) must not
take a library between the moment it is found and the moment a run loads it (``ctypes`` finds a loaded library
by its path)."""


def _hold(library: Path) -> bool:
    """Load ``library`` and keep it loaded (:data:`_HELD`), its modification time renewed so that a pruning of
    the cache takes older ones first; False when it cannot be loaded (removed meanwhile)."""
    key = str(library)
    if key in _HELD:
        return True
    try:
        os.utime(library)
        _HELD[key] = ctypes.CDLL(key)
    except OSError:
        return False
    return True


def build_dopri5(plant: Any, law: Any, element: Any, dt: float, *, rtol: float = RTOL, atol: float = ATOL,
                 compile: bool = True, resets: bool = False, lift: bool = True) -> tuple[Dopri5, str]:
    """The :class:`Dopri5` of the smooth loop ``plant`` under ``law`` with ``element``, compiled when it can be.

    Parameters
    ----------
    plant, law, element
        The true plant, the law and the nonlinear element (a continuous memoryless one).
    dt : float
        Output step (s).
    rtol, atol : float
        Tolerances of the error control (atol in state units).
    compile : bool
        Build (or load) the C library; False: the interpreted driver.
    resets : bool
        Apply the law's projection at every grid instant (``Dopri5.proj``; ``Law.project_resets``).
    lift : bool
        Compile the loop with its constants lifted into an input (module docstring), so that a loop of the same
        structure reuses the library; False writes them into the code (one library per loop).

    Returns
    -------
    (Dopri5, str)
        The runner, and how it runs: ``"compiled now"``, ``"cached library"``, or why it is interpreted
        (``numerics.compile: never``, no C compiler, compilation failed).
    """
    rhs, rec, nw, n_ref = loop_functions(plant, law, element)
    proj = projection_function(rhs.size1_in(0), law) if resets else None
    sizes = {"ns": rhs.size1_in(0), "nw": nw, "nrec": rec.size1_out(0), "n_ref": n_ref, "dt": float(dt),
             "rtol": float(rtol), "atol": float(atol)}
    cc = _compiler()
    why = "numerics.compile: never" if not compile else "no C compiler on PATH" if cc is None else ""
    if why or cc is None:
        return Dopri5(library=None, rhs=rhs, rec=rec, proj=proj, **sizes), why
    constants = np.zeros(0)
    code = (rhs, rec)
    if lift:
        from designkit.simulation.lifted import lift_constants

        code, constants = lift_constants((rhs, rec))
    built = _library(source(*code, nw, n_ref, proj=proj), cc)
    if isinstance(built, str):
        return Dopri5(library=None, rhs=rhs, rec=rec, proj=proj, **sizes), built
    library, now = built
    return (Dopri5(library=library, rhs=rhs, rec=rec, compiled_now=now, proj=proj, constants=constants,
                   **sizes),
            "compiled now" if now else "cached library")
