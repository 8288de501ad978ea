"""The closed loop run with the generated C law compiled and called at every step, against the Python law's loop.

``designkit codegen`` writes the designed law as C (:func:`designkit.synthesis.codegen.generate_law_code`).  The
``generated_code`` check runs that C in the verified loop: :func:`compare_generated_code`

1. writes the law's C exactly as ``designkit codegen`` does (the spec's name as prefix) and compiles it with the
   system C compiler into a shared library, loaded function by function with :func:`casadi.external`;
2. builds the spec's loop as the verdict's run builds it (:func:`designkit.simulation.run.build`: the plant, the
   reference, the sampling, the delay, the nonlinear element, the noise, the perturbation, the time grid), and
   two steps of it (:attr:`~designkit.simulation.run.Simulator.restep`): one whose law functions are the calls of
   the compiled C (``C law``), one whose law functions are the Python law's CasADi functions (``Python law``),
   both as MX graphs with the law as a called function;
3. generates both rolled steps to C (``mapaccum``) in one file, compiles it with the law's C file into one library
   (``-O1 -ffp-contract=off``: no reassociation, no fused multiply-add), cached in
   :func:`designkit.cache.cache_dir` ``("codegen")`` under the hash of the law's C text, the two steps'
   serialization, the run's length, the compiler, the flags and CasADi's version;
4. runs both loops on the same inputs with the same fixed-step RK4 on the verdict's output grid -- the family's
   trials with their learning update between them for a learning design -- and compares them: the largest
   difference of the states (plant and controller) and of the command over every step of every run.

A stiff loop the verdict integrates with CVODES is integrated by CVODES inside every step of the grid instead, the
loop interpreted by CasADi's virtual machine (it cannot generate C of a CVODES step) and the law still the compiled
library; the Jacobians CVODES needs are finite differences of the law's functions, for the C law (a library has no
derivatives) and the Python law (an SX function kept as a call) alike, so both Newton iterations see the same
numbers.

**Tolerance** (:data:`TOLERANCE`): each difference relative to the largest magnitude of that quantity over the
Python law's run, at most ``1e-9``.  The two loops execute the same operations in the same order -- the Python
law's functions generated to C by CasADi as part of the loop's file, the C law's being the written file's --
compiled by the same compiler with the same flags into one library, so at most rounding could part them (an
operation the written file orders otherwise); on every example spec they are bit-identical (difference 0,
measured), so a switching law's sign never meets a rounding-level tie between them.  ``1e-9`` leaves room for such
rounding amplified over a run, and is far below a change of a gain that matters: a gain changed in its seventh
significant digit moves the command by about ``1e-7`` of its size at the first step.  Were a switching law to flip
at a tie, the loops would part from that step on: the check reports the first instant at which any difference
appears, with the largest differences, so such a flip is seen for what it is.

The verdict's own run may use another integrator (the compiled Dormand--Prince pair of a smooth loop); the
comparison is made with RK4 for both laws because the compiled pair embeds the law's expressions in its own
generated C and cannot call a library.  The certificate also gives the difference between the C law's run and
the verdict's run (zero where the verdict's run is RK4 on the same grid; the integrators' difference otherwise).
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import os
import shutil
import subprocess
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from designkit.models.codegen import find_compiler
from designkit.simulation.compiled import COMPILE_FLAGS, COMPILED_CHUNK_NUMBERS
from designkit.synthesis.codegen import LAW_ROLES, c_identifier
from designkit.synthesis.codegen import law_source as generated_source

__all__ = ["TOLERANCE", "CompileError", "GeneratedLoops", "LoopComparison", "NoCompilerError", "compare_generated_code",
           "generated_loops", "law_source"]

TOLERANCE = 1e-9
"""Largest relative difference of the states and of the command between the C law's loop and the Python law's
(module docstring)."""
COMPILER_LINES = 4
"""Lines of the compiler's message kept in a failure."""


class NoCompilerError(Exception):
    """No C compiler found: the generated code cannot be run."""


class CompileError(Exception):
    """The compiler refused the generated code; the message holds its first lines."""


@dataclass(frozen=True)
class LoopComparison:
    """The two loops compared (module docstring).

    Parameters
    ----------
    state_difference, command_difference : float
        Largest absolute difference of the states (plant and controller, their units) and of the command
        (the inputs' units, N*m) over every step of every run.
    state_scale, command_scale : float
        Largest magnitude of the states and of the command over the Python law's runs.
    first_difference : float or None
        Time (s) of the first step at which the states or the command differ at all (None: bit-identical).
    runs, steps : int
        Runs compared (trials of a learning design) and output steps of each.
    symbols : tuple of str
        The C functions called by the loop.
    library : str
        The shared library run.
    compiled_now : bool
        The compiler ran (False: the library was cached).
    verdict_state_difference, verdict_command_difference : float or None
        Largest differences between the C law's (last) run and the verdict's run (None: no verdict run given).
    integrator : str
        The verdict run's integrator in words.
    method : str
        How both loops were integrated and evaluated, in words.
    seconds : dict
        Wall time (s) of ``compile`` (with writing the code and building the steps), ``c_run`` and ``python_run``.
    """

    state_difference: float
    command_difference: float
    state_scale: float
    command_scale: float
    first_difference: float | None
    runs: int
    steps: int
    symbols: tuple[str, ...]
    library: str
    compiled_now: bool
    verdict_state_difference: float | None
    verdict_command_difference: float | None
    integrator: str
    method: str
    seconds: dict[str, float]

    @property
    def state_relative(self) -> float:
        """``state_difference`` relative to ``state_scale``."""
        return _relative(self.state_difference, self.state_scale)

    @property
    def command_relative(self) -> float:
        """``command_difference`` relative to ``command_scale``."""
        return _relative(self.command_difference, self.command_scale)


def _relative(diff: float, scale: float) -> float:
    if diff == 0:
        return 0.0
    return diff / scale if scale > 0 else float("inf")


def law_source(design: Any, law: Any, name: str, spec_name: str) -> str:
    """The text of ``<name>.c`` that ``designkit codegen`` writes for ``law`` of the spec ``spec_name`` under the
    prefix ``name`` (:func:`designkit.synthesis.codegen.law_source`)."""
    return generated_source(design, law, name=name, spec_name=spec_name)


def _compile(content: dict[str, str], cc: str, stem: str,
             sources: Callable[[], dict[str, str]] | None = None) -> tuple[Path, bool]:
    """The shared library of ``sources()`` (file name -> text; default ``content``), cached under the hash of
    ``content`` (which determines the sources), the compiler, the flags and CasADi's version; ``(path, compiled
    now)``.  The sources are generated only when the library is not cached."""
    from designkit.cache import cache_dir

    key = "\0".join([*(f"{k}\0{v}" for k, v in content.items()), cc, *COMPILE_FLAGS, ca.__version__])
    cache = cache_dir("codegen")
    library = cache / f"{stem}_{hashlib.sha256(key.encode()).hexdigest()[:16]}.so"
    if library.exists():
        return library, False
    sources = content if sources is None else sources()
    try:
        cache.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory(prefix="designkit-generated-code-") as tmp:
            files = []
            for name, text in sources.items():
                (Path(tmp) / name).write_text(text, encoding="utf-8")
                files.append(str(Path(tmp) / name))
            built = str(Path(tmp) / "library.so")
            proc = subprocess.run([cc, *COMPILE_FLAGS, *files, "-o", built, "-lm"], capture_output=True, text=True,
                                  cwd=tmp)
            if proc.returncode != 0:
                lines = [line for line in (proc.stderr or proc.stdout).strip().splitlines() if line.strip()]
                raise CompileError(f"{Path(cc).name} exited with {proc.returncode}: "
                                     + " | ".join(lines[:COMPILER_LINES] or ["no message"]))
            fd, staged = tempfile.mkstemp(suffix=".so", dir=cache)  # then renamed: safe with concurrent builders
            os.close(fd)
            try:
                shutil.copyfile(built, staged)  # the temporary folder may be on another file system
                os.replace(staged, library)
            except OSError:
                with contextlib.suppress(OSError):
                    os.unlink(staged)
                raise
    except OSError as exc:
        raise CompileError(f"{Path(cc).name} could not build the library in {cache}: {exc}") from None
    return library, True


_FD = {"enable_fd": True, "enable_forward": False, "enable_reverse": False, "enable_jacobian": False}
"""Options of a law function inside a CVODES step: derivatives by finite differences (a compiled library has no
others), the same for the C law and the Python law so that both Newton iterations see the same Jacobians."""


def _opaque(f: ca.Function, name: str, cvodes: bool) -> ca.Function:
    """``f`` as a called function, as the C law's functions are: an MX function calling it, or inside a CVODES step
    an SX function never inlined, with finite-difference derivatives (:data:`_FD`)."""
    if cvodes:
        args = f.sx_in()
        return ca.Function(name, args, f.call(args), f.name_in(), f.name_out(), {"never_inline": True, **_FD})
    args = f.mx_in()
    return ca.Function(name, args, f.call(args), f.name_in(), f.name_out())


ROLLED_CHUNK = 500
"""Most steps per call of the compiled loop: CasADi builds an MX ``mapaccum`` of up to about 500 steps in a
millisecond, and of 1,250 in 45 ms (measured); a call costs microseconds, so short chunks cost nothing."""


def _rolled(step: ca.Function, name: str, n_steps: int) -> ca.Function:
    """``step`` rolled over a chunk of steps: at most :data:`ROLLED_CHUNK` (fewer when the state and record are
    large), as even as the run's ``n_steps`` allow, so that the last chunk pads few steps."""
    numbers = COMPILED_CHUNK_NUMBERS // (step.size1_in(0) + step.size1_out(1))
    largest = max(1, min(ROLLED_CHUNK, numbers))
    chunks = -(-n_steps // largest)
    return step.mapaccum(name, max(1, -(-n_steps // chunks)))


def _runs(simulator: Any, design: Any) -> tuple[Any, ...]:
    learning = design.learning
    if learning is None:
        return (simulator.run(),)
    from designkit.simulation.trials import run_trials

    return run_trials(simulator, learning.trials, learning.update).results


def _difference(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``|a - b|`` per step (rows: steps), with equal non-finite entries (NaN of a diverged run) counted equal."""
    same = (a == b) | (np.isnan(a) & np.isnan(b))
    with np.errstate(invalid="ignore"):
        d = np.where(same, 0.0, np.abs(a - b))
    d = np.where(np.isnan(d), np.inf, d)
    return d.reshape(d.shape[0], -1).max(axis=1) if d.size else np.zeros(d.shape[0])


def _scale(values: np.ndarray) -> float:
    finite = np.abs(values[np.isfinite(values)])
    return float(finite.max()) if finite.size else 0.0


def _states(res: Any) -> np.ndarray:
    return np.hstack([res.state, res.controller_state])


@dataclass(frozen=True, eq=False)
class GeneratedLoops:
    """The two loops of :func:`compare_generated_code`, built and ready to run.

    Parameters
    ----------
    c, python : Simulator
        The loop calling the compiled C law, and the loop calling the Python law (``Simulator.run``).
    verdict : Simulator
        The loop as the verdict's run builds it (its own integrator).
    symbols : tuple of str
        The C functions of the law, in :data:`~designkit.synthesis.codegen.LAW_ROLES` order.
    library : str
        The shared library the loops run.
    compiled_now : bool
        The compiler ran (False: cached).
    cvodes : bool
        The loops are stepped by CVODES (interpreted loop, compiled law).
    """

    c: Any
    python: Any
    verdict: Any
    symbols: tuple[str, ...]
    library: str
    compiled_now: bool
    cvodes: bool

    @property
    def method(self) -> str:
        """How both loops are integrated and evaluated, in words."""
        if self.cvodes:
            return ("CVODES inside every step of the verdict's grid, the loop interpreted (CasADi cannot generate C "
                    "of a CVODES step), the law's derivatives by finite differences")
        return "RK4 on the verdict's grid, both loops compiled in one library"


def generated_loops(spec: Any, design: Any, *, plant: Any = None, law: Any = None,
                    simulator: Any = None) -> GeneratedLoops:
    """Compile the generated C of ``law`` and build the loop of ``spec`` with it and with ``law`` (module docstring).

    Parameters
    ----------
    spec : Spec
        The validated spec (its ``simulation`` and ``numerics``; its ``name`` is the C prefix).
    design : Design
        The design.
    plant : Plant, optional
        The true plant (default the design's).
    law : Law, optional
        The simulated law (default ``design.law``).
    simulator : Simulator, optional
        The verdict's built simulation of this spec, design, plant and law (default: built here, as the verdict's
        run builds it).

    Raises
    ------
    NoCompilerError
        No C compiler on ``PATH``.
    CompileError
        The compiler refused the law's C or the loop's.
    """
    from designkit.simulation.run import build

    cc = find_compiler()
    if cc is None:
        raise NoCompilerError("no C compiler found on PATH (cc, gcc or clang)")
    law = design.law if law is None else law
    name = c_identifier(spec.name)
    learning = design.learning
    if simulator is None:
        simulator = build(spec, design, plant=plant, law=law, expected_runs=learning.trials if learning else 1)
    text = law_source(design, law, name, spec.name)
    law_library, law_now = _compile({f"{name}.c": text}, cc, f"dk_law_{name}")
    symbols = tuple(f"{name}_{role}" for role in LAW_ROLES)
    cvodes = str(simulator.settings.get("integrator", "")).startswith("cvodes")
    options = _FD if cvodes else {}
    laws = {"c": dataclasses.replace(law, **{role: ca.external(sym, str(law_library), options)
                                             for role, sym in zip(LAW_ROLES, symbols, strict=True)}),
            "python": dataclasses.replace(law, **{role: _opaque(getattr(law, role), f"dk_python_{role}", cvodes)
                                                  for role in LAW_ROLES})}
    steps = {k: simulator.restep(v) for k, v in laws.items()}
    if cvodes:  # CasADi cannot generate C of a CVODES step: the loop runs interpreted, the law compiled
        library, compiled_now = law_library, law_now
        loaded: dict[str, Any] = {"c": None, "python": None}
    else:
        def sources() -> dict[str, str]:
            gen = ca.CodeGenerator("dk_generated_loop.c", {"with_header": False, "verbose": False})
            for k, s in steps.items():
                gen.add(_rolled(s, f"dk_loop_{k}", simulator.time.size))
            return {"dk_generated_loop.c": gen.dump(), f"{name}.c": text}

        # keyed by the steps' serialization (which names the law's library, itself keyed by the law's text) and the
        # run's length (the chunk): rolling and generating them costs more than a cached run
        content = {"steps": "\0".join(s.serialize() for s in steps.values()), "n": str(simulator.time.size),
                   f"{name}.c": text}
        library, compiled_now = _compile(content, cc, f"dk_loop_{name}", sources)
        loaded = {k: ca.external(f"dk_loop_{k}", str(library)) for k in steps}
    loops = {k: dataclasses.replace(simulator, step=steps[k], accumulated=loaded[k], dopri5=None, cvodes=None,
                                    law=laws[k], _flat={}) for k in laws}
    return GeneratedLoops(c=loops["c"], python=loops["python"], verdict=simulator, symbols=symbols,
                          library=str(library), compiled_now=compiled_now, cvodes=cvodes)


def compare_generated_code(spec: Any, design: Any, *, plant: Any = None, law: Any = None, verdict: Any = None,
                           simulator: Any = None) -> LoopComparison:
    """Run the loop of ``spec`` with the generated C of ``law`` and with ``law`` itself, and compare (module docstring).

    Parameters
    ----------
    spec, design, plant, law, simulator
        As for :func:`generated_loops`.
    verdict : SimulationResult, optional
        The verdict's run, compared with the C law's for the record.

    Returns
    -------
    LoopComparison

    Raises
    ------
    NoCompilerError
        No C compiler on ``PATH``.
    CompileError
        The compiler refused the law's C or the loop's.
    """
    start = time.perf_counter()
    loops = generated_loops(spec, design, plant=plant, law=law, simulator=simulator)
    seconds = {"compile": time.perf_counter() - start}
    results = {}
    for k, loop in (("c", loops.c), ("python", loops.python)):
        t0 = time.perf_counter()
        results[k] = _runs(loop, design)
        seconds[f"{k}_run"] = time.perf_counter() - t0
    state_d, command_d, first = 0.0, 0.0, None
    for c, p in zip(results["c"], results["python"], strict=True):
        ds, du = _difference(_states(c), _states(p)), _difference(c.u_command, p.u_command)
        state_d, command_d = max(state_d, float(ds.max(initial=0.0))), max(command_d, float(du.max(initial=0.0)))
        moved = np.flatnonzero((ds > 0) | (du > 0))
        if moved.size and (first is None or p.time[moved[0]] < first):
            first = float(p.time[moved[0]])
    v_state = v_command = None
    if verdict is not None and verdict.state.shape == results["c"][-1].state.shape:
        last = results["c"][-1]
        v_state = float(_difference(_states(last), _states(verdict)).max(initial=0.0))
        v_command = float(_difference(last.u_command, verdict.u_command).max(initial=0.0))
    py = results["python"]
    return LoopComparison(
        state_difference=state_d, command_difference=command_d,
        state_scale=max(_scale(_states(r)) for r in py), command_scale=max(_scale(r.u_command) for r in py),
        first_difference=first, runs=len(py), steps=int(py[0].time.size), symbols=loops.symbols,
        library=loops.library, compiled_now=loops.compiled_now, verdict_state_difference=v_state,
        verdict_command_difference=v_command, integrator=str(loops.verdict.settings.get("integrator", "")),
        method=loops.method, seconds={k: round(v, 4) for k, v in seconds.items()})
