"""Command-line interface: thin wrapper over :mod:`designkit.pipeline`.

Exit codes: 0 designed and every check passed; 1 designed but a check failed or is
undecided; 2 bad input: any :class:`~designkit.errors.DesignkitError`, printed as one line
``designkit: error: <key path>: <message>`` on stderr, nothing written; 3 an internal error
(a bug: anything else, one line unless ``--debug``).
Heavy libraries are imported inside the command functions so that ``--help`` is instant.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, NoReturn

from designkit import __version__
from designkit.errors import DesignkitError, OutputError, SpecError

EXIT_OK, EXIT_CHECK_FAILED, EXIT_BAD_INPUT, EXIT_INTERNAL = 0, 1, 2, 3

MAX_ERROR_LINE = 1000
"""Longest error line printed (characters); messages quoting user values are far shorter."""


def _one_line(text: str) -> str:
    """``text`` on one line (line breaks become spaces), cut to :data:`MAX_ERROR_LINE` characters."""
    line = " ".join(text.split("\n")).replace("\r", " ")
    return line if len(line) <= MAX_ERROR_LINE else line[: MAX_ERROR_LINE - 1] + "…"


def _fmt(value: object) -> str:
    if isinstance(value, float):
        return "—" if value != value else f"{value:.4g}"  # NaN: a value a diverged run does not define
    return "" if value is None else str(value)


def _checks_table(checks) -> str:
    rows = [("check", "status", "achieved", "target", "margin")]
    for c in checks:
        achieved = _fmt(c.achieved) if _fmt(c.achieved) in ("", "—") else f"{_fmt(c.achieved)} {c.unit}".strip()
        rows.append((c.name, c.status, achieved, c.target, _fmt(c.margin)))
    widths = [max(len(r[i]) for r in rows) for i in range(5)]
    lines = ["  ".join(cell.ljust(w) for cell, w in zip(r, widths, strict=True)).rstrip() for r in rows]
    for c in checks:
        if c.passed is not True and c.detail:
            lines.append(f"  {c.status} {c.name}: {c.detail}")
    return "\n".join(lines)


def _number(v: object) -> str:
    import numpy as np

    arr = np.asarray(v, dtype=float)
    return f"{float(arr):.6g}" if arr.ndim == 0 else "[" + ", ".join(f"{x:.6g}" for x in arr.ravel()) + "]"


def _poles(poles) -> str:
    return ", ".join(f"{p.real:.4g}{p.imag:+.4g}j" if p.imag else f"{p.real:.4g}" for p in poles)


def _summary(result) -> str:
    d = result.design
    gains = ", ".join(f"{k} = {_number(v)}" for k, v in d.gains.items())
    if d.loops:
        poles = "; ".join(f"{name}: {_poles(loop.poles)}" for name, loop in zip(d.loop_names, d.loops, strict=True))
    else:
        poles = _poles(d.poles)
    verdict = "VERIFIED" if result.verified else "NOT VERIFIED: " + ", ".join(c.name for c in result.failed)
    return "\n".join([
        f"{result.loaded.spec.name}: {d.kind} on a {d.plant.kind} plant",
        f"poles: {poles}",
        f"gains: {gains}",
        *[f"note: {n}" for n in d.notes],
        _checks_table(result.checks),
        verdict,
    ])


def _comparison_summary(result) -> str:
    """The text summary of a comparison: the table (one column per controller), who wins or ties, each controller's
    verdict from its checks' statuses, and every controller's warnings."""
    from designkit.comparison.table import tally

    table = result.table
    header = ("metric", *result.labels)
    rows = [header]
    for m in table.metrics:
        rows.append((f"{m.label} ({table.unit_of(m)})",
                     *(table.cell(m, r.values.get(m.key)).removesuffix(" " + table.unit_of(m)) for r in table.rows)))
    rows.append(("required checks passed", *(f"{sum(c.status == 'PASS' for c in r.checks if c.required)} of "
                                             f"{sum(c.required for c in r.checks)}" for r in table.rows)))
    widths = [max(len(r[i]) for r in rows) for i in range(len(header))]
    lines = [f"{result.loaded.spec.name}: comparison of " + ", ".join(
        f"{label} ({r.design.kind})" for label, r in zip(result.labels, result.results, strict=True))]
    lines += ["  ".join(cell.ljust(w) for cell, w in zip(r, widths, strict=True)).rstrip() for r in rows]
    winners = table.winners()
    lines += [tally(result.labels, winners), *(w.sentence for w in winners)]
    for row, r in zip(table.rows, result.results, strict=True):
        lines.append(row.sentence)
        for c in r.failed:
            if c.detail:
                lines.append(f"  {c.status} {c.name}: {c.detail}")
    warned = [(row.label, w) for row in table.rows for w in row.warnings]
    if warned:
        lines.append("warnings:")
        lines += [f"  {label}: {w}" for label, w in warned]
    lines.append("VERIFIED (every controller)" if result.verified else
                 "NOT VERIFIED: " + ", ".join(dict.fromkeys(label for label, _ in result.failed)))
    return "\n".join(lines)


def _is_comparison(result) -> bool:
    return hasattr(result, "table") and hasattr(result, "results")


def _exit_for(result) -> int:
    return EXIT_OK if result.verified else EXIT_CHECK_FAILED


def _start_solver_process(*, report: bool = False) -> None:
    """Let a second core import cvxpy while this process works (:mod:`designkit.verification.solver_process`);
    with ``report``, import the report's stack while waiting for a solve, if ever."""
    import numpy  # noqa: F401 - imported before the fork, so the solver process inherits them
    import scipy.linalg  # noqa: F401

    from designkit.verification import solver_process

    if solver_process.start(fork=True) is not None and report:
        solver_process.while_waiting(_import_report_stack)


def _import_report_stack() -> None:
    import importlib

    for name in ("matplotlib.figure", "matplotlib.backends.backend_svg", "designkit.report.figures",
                 "designkit.report.model", "designkit.report.html", "designkit.report.pdf"):
        importlib.import_module(name)


def cmd_synth(args: argparse.Namespace) -> int:
    """Synthesise, verify, simulate and write the HTML + PDF report."""
    if args.jobs > 1:
        _start_solver_process(report=not args.no_report)
    from designkit.pipeline import run
    from designkit.report import write_report
    from designkit.report.comparison_writer import write_comparison_report
    from designkit.schema.loader import load_spec

    loaded = load_spec(args.spec)
    result = run(loaded, budget=args.budget)
    comparison = _is_comparison(result)
    files = None
    if not args.no_report:
        try:
            if comparison:
                files = write_comparison_report(result, Path(args.out), processes=args.jobs,
                                                studies=not args.no_studies)
            else:
                files = write_report(result, Path(args.out), processes=args.jobs, studies=not args.no_studies)
        except OutputError as exc:
            raise OutputError("--out", f"cannot write the report: {exc.message}") from None
        except OSError as exc:  # failed part-way (disk full, ...): the previous report is left as it was
            raise OutputError("--out", f"cannot write the report: {exc.strerror or exc}") from None
    if args.json:
        payload = result.to_json(studies=not args.no_studies)
        if files is not None:
            payload["report"] = {"html": str(files.html), "pdf": str(files.pdf)}
        print(json.dumps(payload, indent=2))
    else:
        print(_comparison_summary(result) if comparison else _summary(result))
        if files is not None:
            print(f"report: {files.html}\nreport: {files.pdf}")
    return _exit_for(result)


def cmd_verify(args: argparse.Namespace) -> int:
    """Synthesise and verify; print the checks; write nothing."""
    if args.jobs > 1:
        _start_solver_process()
    from designkit.pipeline import run
    from designkit.schema.loader import load_spec

    result = run(load_spec(args.spec), budget=args.budget)
    summary = _comparison_summary if _is_comparison(result) else _summary
    print(json.dumps(result.to_json(), indent=2) if args.json else summary(result))
    return _exit_for(result)


def cmd_simulate(args: argparse.Namespace) -> int:
    """Synthesise and simulate; print a summary or write the trajectories as CSV."""
    import numpy as np

    from designkit.pipeline import design, single
    from designkit.schema.loader import load_spec
    from designkit.simulation.run import simulate

    loaded = load_spec(args.spec)
    single(loaded, "designkit simulate")
    dsn = design(loaded)
    sim = simulate(loaded.spec, dsn)
    columns = np.column_stack([
        sim.time, sim.desired, sim.state, sim.controller_state, sim.u_command, sim.u_applied, sim.perturbation,
    ])
    n = sim.n_joints
    header = ",".join(["t", *(["xD"] if n == 1 else [f"xD{j + 1}" for j in range(n)]), *sim.state_names,
                       *sim.controller_state_names, *[f"{u}_command" for u in sim.input_names],
                       *[f"{u}_applied" for u in sim.input_names], *sim.disturbance_names])
    if args.csv:
        try:
            np.savetxt(args.csv, columns, delimiter=",", header=header, comments="")
        except OSError as exc:
            raise OutputError("--csv", f"cannot write {args.csv}: {exc.strerror or exc}") from None
        print(f"wrote {len(sim.time)} samples to {args.csv}")
    else:
        print(f"{loaded.spec.name}: simulated {sim.time[-1]:.4g} s in {len(sim.time) - 1} steps")
        for j in range(sim.n_joints):
            name = sim.state_names[sim.positions[j]]
            err = sim.tracking_errors[:, j]
            print(f"final {name} = {sim.joint_positions[-1, j]:.6g} rad, final |{name} - xD| = {abs(err[-1]):.3g} rad, "
                  f"max |{name} - xD| = {np.max(np.abs(err)):.4g} rad")
        print(f"peak |u_command| = {np.max(np.abs(sim.u_command)):.4g}, "
              f"peak |u_applied| = {np.max(np.abs(sim.u_applied)):.4g}")
    return EXIT_OK


def cmd_schema(args: argparse.Namespace) -> int:
    """Print the JSON Schema of the spec format (``--form``: one controller, a comparison, or either)."""
    from designkit.schema.comparison import json_schema

    print(json.dumps(json_schema(args.form), indent=2))
    return EXIT_OK


def cmd_model(args: argparse.Namespace) -> int:
    """Print a summary of a zoo robot's symbolic model."""
    from designkit.models.summary import model_command

    print(model_command(args.robot))
    return EXIT_OK


def cmd_codegen(args: argparse.Namespace) -> int:
    """Check the spec as ``verify`` does (budget, design, the simulation's bounds), then write its control law (with
    its model terms) as C code; a refused spec writes nothing."""
    from designkit.pipeline import codegen
    from designkit.schema.loader import load_spec

    options = {"out_dir": "--out", "name": "--name"}
    loaded = load_spec(args.spec)
    try:
        code = codegen(loaded, Path(args.out), name=args.name, budget=args.budget)
    except SpecError as exc:
        if exc.path in options:
            raise SpecError(options[exc.path], exc.message) from None
        raise
    print(f"{loaded.spec.name}: {code.kind} law as C, functions "
          + ", ".join(f.symbol for f in code.functions))
    for path in code.files:
        print(f"wrote {path}")
    return EXIT_OK


def cmd_sweep(args: argparse.Namespace) -> int:
    """Monte Carlo of the nonlinear closed loop over the spec's uncertainty, on Dask (:mod:`designkit.sweep`)."""
    from designkit.sweep.api import sweep

    out = Path(args.out)
    name = _spec_name(args.spec)
    progress = not args.json and sys.stderr.isatty()
    folder = out / name if name else out
    try:
        result = sweep(args.spec, args.samples, seed=args.seed, scheduler=args.scheduler, workers=args.workers,
                       out=folder, chunk=args.chunk, progress=progress)
    except KeyboardInterrupt:
        done = len(list((folder / "chunks").glob("chunk-*.npz"))) if (folder / "chunks").is_dir() else 0
        print(f"designkit: interrupted: {done} chunks are written in {folder / 'chunks'}; run the same command "
              "again to resume", file=sys.stderr)
        return 130
    if args.json:
        print(json.dumps(result.to_json(), indent=2, allow_nan=False))
    else:
        lo, hi = result.confidence
        print(f"{result.name}: {result.n_passed:,} of {result.samples:,} samples met every requirement "
              f"(pass fraction {result.pass_fraction:.6g}, 95 % Clopper-Pearson interval [{lo:.6g}, {hi:.6g}])")
        for req, s in result.requirement_summary().items():
            q = s["margin_quantiles"]
            print(f"  {req}: met in {s['passed']:,}; worst margin {_fmt(q['q0'])} {s['unit']}, median "
                  f"{_fmt(q['q0.5'])} {s['unit']}")
        f = result.falsification
        if f is not None:
            print(f"falsification: worst {f.requirement} margin {_fmt(f.margins.get(f.requirement))} at "
                  + ", ".join(f"{d.name} = {v:.6g}" for d, v in zip(result.dimensions, f.values, strict=True))
                  + (" (breaks the requirement)" if f.broken else " (still met)"))
        for key in ("html", "pdf"):
            if key in result.files:
                print(f"report: {result.files[key]}")
        print("VERIFIED" if result.verified else "NOT VERIFIED")
    return EXIT_OK if result.verified else EXIT_CHECK_FAILED


def cmd_tune(args: argparse.Namespace) -> int:
    """Tune the controller's knobs for the spec's requirements over its uncertainty box (:mod:`designkit.tuning`)."""
    from designkit.schema.loader import load_spec
    from designkit.tuning import tune
    from designkit.tuning.report import summary_lines

    result = tune(load_spec(args.spec), out=Path(args.out), budget=args.budget, sweep_samples=args.sweep_samples,
                  scheduler=args.scheduler, method=args.method)
    if args.json:
        print(json.dumps(result.to_json(), indent=2, default=str))
        return EXIT_OK if result.verified else EXIT_CHECK_FAILED
    s, best, initial = result.search, result.best, result.initial
    lines = [f"{result.loaded.spec.name}: {s.method}; {s.iterations} iterations, {len(s.evaluations)} candidates, "
             f"{s.simulations} simulations, {s.seconds:.1f} s ({s.stopped})",
             f"why this search: {result.choice}", f"plants: the nominal and {len(result.points)} points of the box"]
    for req in best.margins:
        mark = " (active)" if req == best.active else ""
        lines.append(f"  {req}: worst normalised margin {initial.margins[req]:.3g} -> {best.margins[req]:.3g}{mark}")
    for knob in best.values:
        lines.append(f"  {knob}: {_number_or_poles(initial.values[knob])} -> {_number_or_poles(best.values[knob])}")
    if result.at_bounds:
        lines.append("at an end of its range (widen tune.ranges to go further): " + ", ".join(result.at_bounds))
    lines.extend(summary_lines(result))
    if result.conflict is not None:
        lines.append("conflict: " + result.conflict.sentence)
    if result.bound is not None:
        lines.append("minimum time: " + result.bound.sentence)
    if not best.certified and best.failed:
        lines.append("certificates failing at the best compromise: " + ", ".join(best.failed))
    if result.verify is not None:
        lines.append(_checks_table(result.verify.checks))
    for key in ("spec", "html"):
        if key in result.files:
            lines.append(f"{'tuned spec' if key == 'spec' else 'report'}: {result.files[key]}")
    lines.append("TUNED AND VERIFIED" if result.verified else
                 "NOT VERIFIED: the tuned spec's checks fail" if result.met else
                 "NOT MET: no tuning found meets every requirement")
    print("\n".join(lines))
    return EXIT_OK if result.verified else EXIT_CHECK_FAILED


def _number_or_poles(value: object) -> str:
    import numpy as np

    arr = np.asarray(value)
    if np.iscomplexobj(arr):
        return "[" + _poles(arr.ravel()) + "]"
    return _number(arr)


def _spec_name(path: str) -> str | None:
    """The spec's ``name`` (the sweep's folder under ``--out``), None when it cannot be read (the sweep says why)."""
    try:
        import yaml

        doc = yaml.safe_load(Path(path).read_text(encoding="utf-8"))
        name = doc.get("name") if isinstance(doc, dict) else None
        return name if isinstance(name, str) and name and "/" not in name and not name.startswith(".") else None
    except (OSError, UnicodeDecodeError, ValueError, Exception):  # noqa: BLE001 - the sweep reports the error
        return None


def _samples(text: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be an integer, got {text!r}") from None


def _sweep_samples(text: str) -> int:
    if not re.fullmatch(r"\d{1,5}", text) or int(text) > 10_000:
        raise argparse.ArgumentTypeError(f"must be an integer from 0 to 10000, got {text[:40]!r}")
    return int(text)


def _jobs(text: str) -> int:
    if text not in ("1", "2"):
        raise argparse.ArgumentTypeError(f"must be 1 or 2, got {text!r}")
    return int(text)


def _seconds(text: str) -> float:
    import math

    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a number of seconds, got {text[:40]!r}") from None
    if not math.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"must be a positive number of seconds, got {text[:40]!r}")
    return value


def _budget_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--budget", type=_seconds, default=None, metavar="SECONDS",
                   help="seconds of estimated work the spec may ask for (default 60): the work is estimated before "
                   "any model is built and a spec beyond the budget is refused (exit 2) naming the field that drives "
                   "the cost; see docs/budget.md")


def _jobs_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--jobs", type=_jobs, default=2, metavar="{1,2}",
                   help="processes to use (default 2 on a machine with two cores or more: a solver process "
                   "imports cvxpy while this one designs, and the figures are drawn on two cores; same results); "
                   "1 runs everything in this process")


_ARGUMENT = re.compile(r"^argument ([^:]+): (.*)$", re.DOTALL)


def usage_error(message: str, prog: str = "designkit") -> str:
    """argparse's error ``message`` as ``<argument>: <reason>``, the argument first as in every bad-input line.

    ``argument --samples: must be an integer, got 'x'`` -> ``--samples: must be an integer, got 'x'``;
    ``the following arguments are required: spec, --samples`` -> ``spec: required (missing: spec, --samples)``;
    ``unrecognized arguments: --foo 3`` -> ``--foo: unrecognized argument (got: --foo 3)``.
    """
    m = _ARGUMENT.match(message)
    if m:
        names, reason = m.group(1), m.group(2)
        return f"{names.split('/')[-1]}: {reason}"
    required = "the following arguments are required: "
    if message.startswith(required):
        missing = message.removeprefix(required)
        return f"{missing.split(', ')[0]}: required (missing: {missing})"
    unknown = "unrecognized arguments: "
    if message.startswith(unknown):
        given = message.removeprefix(unknown)
        first = given.split(" ")[0] or "argument"
        return f"{first}: unrecognized argument (got: {given}); see {prog} --help"
    m = re.match(r"^ambiguous option: (\S+) (.*)$", message)
    if m:
        return f"{m.group(1)}: ambiguous option ({m.group(2)})"
    return f"arguments: {message}"


class _Parser(argparse.ArgumentParser):
    """An ``ArgumentParser`` whose errors are one line, ``designkit: error: <argument>: <reason>``, exit 2 (no usage
    block: ``--help`` prints it).  The subcommands' parsers are of this class too (argparse's default).  Options
    are not abbreviated (``--sa`` is refused, not read as ``--samples``)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("allow_abbrev", False)
        super().__init__(*args, **kwargs)

    def error(self, message: str) -> NoReturn:  # noqa: D102 - argparse's hook
        self.exit(EXIT_BAD_INPUT, f"designkit: error: {_one_line(usage_error(message, self.prog))}\n")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser (exposed for documentation and tests)."""
    parser = _Parser(
        prog="designkit",
        description="Design and verify robot manipulator controllers from a YAML spec.",
        epilog="Exit codes: 0 designed and verified; 1 designed but a check failed or is undecided; "
        "2 bad input.",
    )
    parser.add_argument("--version", action="version", version=f"designkit {__version__}")
    parser.add_argument("--debug", action="store_true", help="show tracebacks of internal errors")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    p = sub.add_parser("synth", help="synthesise, verify, simulate and write the HTML + PDF report")
    p.add_argument("spec", help="path of the YAML spec")
    p.add_argument("--out", default="reports", help="report directory (default: reports/); the report "
                   "goes to OUT/<spec name>/report.html and report.pdf")
    p.add_argument("--json", action="store_true", help="print one JSON object (gains, verified, checks; for a "
                   "comparison spec: a comparison list, one object per controller, and passed)")
    p.add_argument("--no-report", action="store_true", help="do not write the report")
    p.add_argument("--no-studies", action="store_true", help="run no study (gain study, boundary, lab answers): "
                   "the report and --json give the run's own verdict, checks and figures only")
    _jobs_option(p)
    _budget_option(p)
    p.set_defaults(func=cmd_synth)

    p = sub.add_parser("verify", help="synthesise and run every check; write nothing")
    p.add_argument("spec")
    p.add_argument("--json", action="store_true")
    _jobs_option(p)
    _budget_option(p)
    p.set_defaults(func=cmd_verify)

    p = sub.add_parser("simulate", help="simulate the designed closed loop on the nonlinear model")
    p.add_argument("spec")
    p.add_argument("--csv", help="write the trajectories to this CSV file")
    p.set_defaults(func=cmd_simulate)

    p = sub.add_parser("schema", help="print the JSON Schema of the spec format")
    p.add_argument("--form", choices=("single", "comparison", "any"), default="single",
                   help="single: a spec with one controller (default); comparison: a spec comparing several "
                   "(controllers:); any: either form (oneOf)")
    p.set_defaults(func=cmd_schema)

    p = sub.add_parser("codegen", help="write the designed control law (and its model terms) as C code")
    p.add_argument("spec", help="path of the YAML spec")
    p.add_argument("--out", default="codegen", help="output directory (default: codegen/); the code goes "
                   "to OUT/<spec name>/<NAME>.c and <NAME>.h")
    p.add_argument("--name", help="C prefix of the generated symbols and base name of the files (default: "
                   "the spec name with - and . replaced by _)")
    _budget_option(p)
    p.set_defaults(func=cmd_codegen)

    p = sub.add_parser("sweep", help="Monte Carlo of the nonlinear closed loop over the spec's uncertainty, "
                       "on Dask: pass fraction, margins, worst cases, falsification, HTML + PDF report")
    p.add_argument("spec", help="path of the YAML spec (with an optional sweep: section)")
    p.add_argument("--samples", type=_samples, required=True, help="number of samples (1 to 10,000,000)")
    p.add_argument("--seed", type=_samples, default=0, help="seed of the samples (default 0)")
    p.add_argument("--scheduler", help="address of a running Dask scheduler (tcp://host:8786); default: a "
                   "LocalCluster on this machine")
    p.add_argument("--workers", type=_samples, help="workers of the LocalCluster (default one per core)")
    p.add_argument("--chunk", type=_samples, help="samples per chunk (default N/64, 10 to 1000); the results do not "
                   "depend on it")
    p.add_argument("--out", default="sweeps", help="output directory (default: sweeps/); the sweep goes to "
                   "OUT/<spec name>/ (chunks/, samples.csv, worst/, sweep.json, report.html, report.pdf); an "
                   "interrupted sweep re-run with the same arguments resumes from its chunks")
    p.add_argument("--json", action="store_true", help="print one JSON object (samples, passed, pass_fraction, "
                   "confidence, requirements, worst)")
    p.set_defaults(func=cmd_sweep)

    p = sub.add_parser("tune", help="tune the controller's knobs (poles, zeros, gains) so that every requirement "
                       "holds with the largest worst-case margin over plant.uncertainty, every certificate passing; "
                       "write the tuned spec and an HTML report")
    p.add_argument("spec", help="path of the YAML spec (with requirements; an optional tune: section)")
    p.add_argument("--out", default=".", help="output directory (default: the current folder): <name>-tuned.yaml "
                   "<name>-tuning.html and .pdf")
    p.add_argument("--budget", type=_seconds, default=60.0, metavar="SECONDS",
                   help="processor time the search may take (default 60 s)")
    p.add_argument("--sweep-samples", type=_sweep_samples, default=64, metavar="N",
                   help="samples of the confirming sweep of the tuned spec over plant.uncertainty (default 64; 0: "
                   "none)")
    p.add_argument("--scheduler", metavar="ADDRESS", help="run the confirming sweep on the Dask scheduler at this "
                   "address (tcp://host:8786, or tls:// with the Dask TLS configuration); default: in this process")
    p.add_argument("--method", choices=("auto", "gradient", "nelder-mead"), default="auto", help="the search: "
                   "gradient on a smooth loop, Nelder-Mead on any other (auto, default), or the one named")
    p.add_argument("--json", action="store_true", help="print one JSON object (method, margins before and after, "
                   "tuned values, checks, conflict, sweep, trade_off)")
    p.set_defaults(func=cmd_tune)

    p = sub.add_parser("model", help="summarise a zoo robot's model (joints, parameters, cost)")
    p.add_argument("robot", help="zoo robot name, e.g. planar2r or puma560")
    p.set_defaults(func=cmd_model)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``designkit`` console script; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    func: Callable[[argparse.Namespace], int] = args.func
    try:
        return func(args)
    except DesignkitError as exc:  # every user mistake, whatever the layer that found it: exit 2, one line
        print(f"designkit: error: {_one_line(str(exc))}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except BrokenPipeError:  # output piped into e.g. `head`
        return EXIT_OK
    except KeyboardInterrupt:
        print("designkit: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # a bug, not bad input: say so in one line unless --debug
        if args.debug:
            raise
        print(f"designkit: internal error: {type(exc).__name__}: {_one_line(str(exc))} (rerun with --debug for "
              "the traceback)", file=sys.stderr)
        return EXIT_INTERNAL


def entry() -> None:
    """The ``designkit`` console script: :func:`main`, then leave without the interpreter's teardown.

    Finalizing the interpreter after a ``synth`` run (matplotlib, CasADi, SciPy, pydantic loaded)
    takes about 0.5 s, and nothing designkit needs happens then: every file is closed when it is
    written and the solver process is stopped here.  So once the standard streams are flushed,
    the process ends with :func:`os._exit`.  (A tool that saves its data at exit, e.g. coverage,
    should call :func:`main` instead.)  ``--help``, ``--version`` and ``--debug`` tracebacks leave
    through the normal path.
    """
    import contextlib
    import os

    code = main()
    solver_process = sys.modules.get("designkit.verification.solver_process")
    if solver_process is not None:
        solver_process.stop()
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(BrokenPipeError, ValueError):  # output piped into e.g. `head`, or closed
            stream.flush()
    os._exit(code)


if __name__ == "__main__":  # pragma: no cover
    entry()
