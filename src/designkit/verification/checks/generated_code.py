"""Check ``generated_code``: the C code ``designkit codegen`` ships, compiled and called at every step of the
verified loop, gives the loop the Python law gives.

The law's C is written as ``designkit codegen`` writes it, compiled by the system C compiler and run in the spec's
closed loop -- the family's trials for a learning design -- beside the Python law's loop, both with RK4 on the
verdict's output grid in one compiled library (:mod:`designkit.verification.generated_loop`).  It passes when the
largest differences of the states and of the command, relative to their largest magnitudes over the run, are at
most :data:`~designkit.verification.generated_loop.TOLERANCE` (``1e-9``; the two loops execute the same operations,
so only rounding could separate them, and they are bit-identical on every example spec).  A compiler refusing the
generated code is a failure with the compiler's first lines; without a C compiler the check is undecided.
Offered on every design with a law and a simulation (universal), in the run that gives the spec's verdict
(:attr:`~designkit.verification.suite.Context.verdict_run`): a study's variant, a fix's re-run or a box re-run has
other gains or another plant, and its code is not the code ``designkit codegen`` writes for the spec.
"""

from __future__ import annotations

from typing import Any

from designkit.verification.suite import CheckRule, Context


def _format(value: float) -> str:
    return "0" if value == 0 else f"{value:.3g}"


def _run(design: Any, ctx: Context) -> tuple:
    from designkit.errors import DesignkitError
    from designkit.verification.check import Check
    from designkit.verification.generated_loop import (
        TOLERANCE,
        CompileError,
        NoCompilerError,
        compare_generated_code,
    )

    target = (f"states and command of the loop with the compiled C law within {TOLERANCE:g} (relative to their "
              "largest magnitudes) of the loop with the Python law")
    try:
        cmp = compare_generated_code(ctx.spec, design, plant=ctx.plant, law=ctx.law, verdict=ctx.simulation,
                                     simulator=ctx.simulator)
    except NoCompilerError as exc:
        return (Check(name="generated_code", passed=None, target=target, detail=f"not run: {exc}; the generated C "
                      "cannot be compiled here (install cc, gcc or clang)", certificate={"compiler": None}),)
    except CompileError as exc:
        return (Check(name="generated_code", passed=False, target=target, detail=f"the generated C does not "
                      f"compile: {exc}", certificate={"compiler_message": str(exc)}),)
    except DesignkitError:
        raise
    except Exception as exc:  # noqa: BLE001 -- a loop that cannot be run with the C law decides nothing, with why
        first = (str(exc).strip().splitlines() or [""])[0]
        return (Check(name="generated_code", passed=None, target=target, detail=f"the loop with the compiled C law "
                      f"could not be run: {type(exc).__name__}: {first}",
                      certificate={"error": f"{type(exc).__name__}: {exc}"}),)
    worst = max(cmp.state_relative, cmp.command_relative)
    passed = worst <= TOLERANCE
    runs = f"{cmp.runs} trials" if cmp.runs > 1 else "the run"
    diffs = (f"largest state difference {_format(cmp.state_difference)} (relative {_format(cmp.state_relative)}), "
             f"largest command difference {_format(cmp.command_difference)} (relative "
             f"{_format(cmp.command_relative)})")
    where = ("bit-identical at every step" if cmp.first_difference is None
             else f"first difference at t = {cmp.first_difference:.6g} s")
    detail = (f"{cmp.symbols[0]} and the other law functions compiled and called at every step of {runs} "
              f"({cmp.steps:,} steps; {cmp.method}): {diffs}; {where}")
    if not passed:
        detail = f"the generated C gives another loop: {diffs}; {where}"
    cert = {
        "state_difference": cmp.state_difference, "command_difference": cmp.command_difference,
        "state_scale": cmp.state_scale, "command_scale": cmp.command_scale,
        "state_relative": cmp.state_relative, "command_relative": cmp.command_relative, "tolerance": TOLERANCE,
        "first_difference_s": cmp.first_difference, "runs": cmp.runs, "steps": cmp.steps,
        "functions": list(cmp.symbols),
        "method": cmp.method, "verdict_integrator": cmp.integrator,
        "verdict_state_difference": cmp.verdict_state_difference,
        "verdict_command_difference": cmp.verdict_command_difference,
    }  # no timing, cache path or cache state: the same spec gives the same report on any run
    return (Check(name="generated_code", passed=passed, target=target, achieved=worst, margin=TOLERANCE - worst,
                  unit="relative difference", detail=detail, certificate=cert),)


RULE = CheckRule(
    name="generated_code", order=148,
    applies=lambda d, c: c.verdict_run and c.simulation is not None and (c.law is not None
                                                                          or getattr(d, "law", None) is not None),
    run=_run, label="The generated C code in the closed loop", universal=True,
    glossary=(("generated C code", "the control law as C written by designkit codegen (CasADi's code generator), "
               "compiled by the system C compiler"),
              ("relative difference", "the largest difference between the loop with the compiled C law and the loop "
               "with the Python law, divided by the largest magnitude of the quantity over the run")),
)
