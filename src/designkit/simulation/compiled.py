"""How a rolled RK4 or CVODES step is evaluated: compiled to C, or by CasADi's virtual machine.

:func:`evaluator` decides (``numerics.compile``, the estimated interpreted cost against what compiling costs, the
cache) and builds the compiled ``mapaccum`` the simulator runs (:func:`designkit.simulation.integrate.run_steps`).
"""

from __future__ import annotations

from typing import Any

import casadi as ca

__all__ = ["CACHE_LOOKUP_FLOOR", "CHUNK", "COMPILED_CHUNK", "COMPILE_BREAK_EVEN", "COMPILE_FLAGS",
           "INTERPRETED_SECONDS_PER_INSTRUCTION", "evaluator"]

CHUNK = 200
"""Steps per ``mapaccum`` evaluation of the interpreted step (see :func:`~designkit.simulation.integrate.run_steps`:
building an interpreted ``mapaccum`` costs more the more steps it rolls)."""
COMPILED_CHUNK, COMPILED_CHUNK_NUMBERS = 2000, 1 << 18
"""Steps per evaluation of the compiled step: at most ``COMPILED_CHUNK``, and at most ``COMPILED_CHUNK_NUMBERS``
numbers of state and record per call (a long delay line makes the state large); compiling costs the same for any
number of steps (CasADi writes the roll as a loop), and fewer calls cost less from Python."""
COMPILE_BREAK_EVEN = 0.25
"""Compile (``numerics.compile: auto``) when the interpreted run is estimated above this (s): about what
compiling the rolled two-link step costs with ``cc -O1`` (0.21-0.25 s measured, ``benchmarks/bench_simnog.py``)."""
CACHE_LOOKUP_FLOOR = 0.01
"""Below this estimated interpreted cost (s) the compiled cache is not even looked up (generating the C source
to hash it costs a few milliseconds)."""
INTERPRETED_SECONDS_PER_INSTRUCTION = 6e-9
"""Measured cost of one CasADi virtual-machine instruction in a rolled step on a quiet machine (SIMNOG:
56 ms for 10^4 steps of 882 instructions; -O1 C runs the same steps in 5.5 ms)."""
COMPILE_FLAGS = ("-O1", "-ffp-contract=off", "-fPIC", "-shared")
"""No reassociation and no fused multiply-add: the compiled step gives the interpreted step's numbers."""


def evaluator(step: ca.Function, n_steps: int, mode: str, runs: int = 1) -> tuple[ca.Function | None, dict[str, Any]]:
    """The compiled ``mapaccum`` to run ``step`` with, or None for the interpreted one, and why."""
    from designkit.models.codegen import cached_library, compile_function, find_compiler

    estimate = runs * n_steps * step.n_instructions() * INTERPRETED_SECONDS_PER_INSTRUCTION
    info: dict[str, Any] = {"mode": mode, "interpreted_estimate_s": round(estimate, 4)}
    if mode == "never":
        return None, {**info, "compiled": False, "why": "numerics.compile: never"}
    if not step.is_a("SXFunction"):
        return None, {**info, "compiled": False, "why": "a CVODES step is not compiled"}
    if find_compiler() is None:
        return None, {**info, "compiled": False, "why": "no C compiler on PATH"}
    if mode == "auto" and estimate < CACHE_LOOKUP_FLOOR:
        return None, {**info, "compiled": False,
                      "why": f"interpreted run estimated at {estimate:.3g} s: nothing to gain"}
    m = max(CHUNK, min(COMPILED_CHUNK, COMPILED_CHUNK_NUMBERS // (step.size1_in(0) + step.size1_out(1))))
    acc = step.mapaccum(f"{step.name()}_acc", m)
    cached = cached_library(acc, flags=COMPILE_FLAGS) is not None
    if mode == "auto" and not cached and estimate < COMPILE_BREAK_EVEN and runs <= 1:
        return None, {**info, "compiled": False,
                      "why": f"interpreted run estimated at {estimate:.3g} s, below the {COMPILE_BREAK_EVEN:g} s "
                             "it costs to compile"}
    compiled = compile_function(acc, flags=COMPILE_FLAGS)
    if not compiled.compiled:
        return None, {**info, "compiled": False, "why": compiled.reason}
    return compiled.function, {**info, "compiled": True, "why": "cached library" if cached else "compiled now",
                               "flags": " ".join(COMPILE_FLAGS)}
