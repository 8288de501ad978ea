"""`designkit synth specs/posspeed-link.yaml --out DIR` (HTML + PDF) end to end, against the import of its stack.

Run apart from the tests:  python benchmarks/bench_synth.py [--repeat N] [--phases] [--imports] [--before REF]

The whole CLI is timed in fresh subprocesses (median of N runs), with the study-free command (``--no-studies``)
next to the default one (which runs the studies), and two baselines timed in the same run: `python -c pass` and
**the stack**, the third-party modules the command imports, imported by themselves in a fresh interpreter (recorded
from one ``--jobs 1`` run, in the order it imported them; the ``scipy.stats`` that designkit spares cvxpy's import
stays unimported when the run did not import it).  The budget is a ratio: the study-free command
within :data:`BUDGET_RATIO` times the stack's import, a figure less sensitive to a loaded machine than seconds; the
children's CPU time (user + system) is reported next to it.  The default
command (``--jobs 2``: cvxpy imported by a solver process, figures drawn on two cores) is timed
interleaved with ``--jobs 1`` (everything in one process), and the machine's parallel speed-up is
measured in the same run (two CPU-bound Python processes at once against one after the other),
since what two processes can gain depends on it.  designkit's bytecode is compiled first
(``compileall``), as ``pip install`` does and as Python does on a first run: a sandbox that sets
``PYTHONDONTWRITEBYTECODE`` would otherwise recompile the package on every run.  Every synth
run must exit 0 and write both reports, else the benchmark fails: a broken command is not timed.
``--phases`` adds one in-process breakdown (imports, design + simulation + checks, report model
with its figures, HTML, PDF); ``--imports`` lists the modules whose import costs the most in a
synth run (``python -X importtime``, cumulative); ``--before REF`` times the ``src/`` of a git
revision too, interleaved with the working tree.  Writes benchmarks/results/synth.json.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SPEC = ROOT / "specs" / "posspeed-link.yaml"
BUDGET_RATIO = 1.5
"""The study-free synth's median wall time, at most this many times the stack's import (same run)."""
SYNTH = [sys.executable, "-m", "designkit.cli", "synth", str(SPEC)]

_RECORD = r"""
import json, sys
from designkit.cli import main
main(["synth", sys.argv[1], "--out", sys.argv[2], "--jobs", "1", "--no-studies"])
third = [m for m in sys.modules if m.split(".")[0] not in sys.stdlib_module_names
         and not m.startswith(("designkit", "__main__"))]
print(json.dumps(third))
"""

_REPLAY = r"""
import importlib, importlib.abc, importlib.machinery, json, sys, types
names, deferred = json.loads(sys.argv[1]), set(json.loads(sys.argv[2]))


class _Unimported(types.ModuleType):
    def __getattr__(self, name):
        if name.startswith("__"):
            raise AttributeError(name)
        return lambda *args, **kwargs: None


class _Loader(importlib.abc.Loader):
    def create_module(self, spec):
        return _Unimported(spec.name)

    def exec_module(self, module):
        pass


class _Finder(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name in deferred and name not in names:  # deferred by designkit and not imported by the run
            return importlib.machinery.ModuleSpec(name, _Loader())
        return None


sys.meta_path.insert(0, _Finder())
for name in names:
    try:
        importlib.import_module(name)
    except Exception:
        pass
"""
_SPIN = "s = 0\nfor i in range(6_000_000):\n    s += i\n"

_PHASES = r"""
import json, sys, tempfile, time
t = [time.perf_counter()]
from designkit.pipeline import run
from designkit.report.html import render_html
from designkit.report.model import build_report_model
from designkit.report.pdf import compile_pdf
from designkit.schema.loader import load_spec
t.append(time.perf_counter())
result = run(load_spec(sys.argv[1]))
t.append(time.perf_counter())
model = build_report_model(result)
t.append(time.perf_counter())
render_html(model)
t.append(time.perf_counter())
compile_pdf(model)
t.append(time.perf_counter())
names = ["import designkit (pipeline, report)", "run: design, simulation, checks (lazy imports included)",
         "report model (figures rendered to SVG)", "HTML", "PDF (Typst)"]
print(json.dumps({n: b - a for n, a, b in zip(names, t, t[1:])}))
"""


def _cpu_children() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def _checkout(ref: str, into: Path) -> Path:
    """``src/`` of git revision ``ref`` extracted under ``into`` (for a before/after comparison)."""
    into.mkdir(parents=True, exist_ok=True)
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", ref, "src"], check=True, capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(into)], input=archive, check=True)
    return into / "src"


def _times(cmd: list[str], repeat: int, *, check_reports: Path | None = None,
           cpu: list[float] | None = None, env: dict[str, str] | None = None) -> list[float]:
    """Wall times (s) of ``repeat`` runs; CPU times (user + system, s) appended to ``cpu``."""
    out = []
    for _ in range(repeat):
        if check_reports is not None:
            shutil.rmtree(check_reports, ignore_errors=True)
        start, cpu0 = time.perf_counter(), _cpu_children()
        proc = subprocess.run(cmd, check=False, capture_output=True, text=True, env=env)
        out.append(time.perf_counter() - start)
        if cpu is not None:
            cpu.append(_cpu_children() - cpu0)
        if proc.returncode != 0:
            tail = (proc.stderr or proc.stdout).strip().splitlines()[-3:]
            raise SystemExit(f"{' '.join(cmd)} exited {proc.returncode}: " + " | ".join(tail))
        if check_reports is not None:
            written = sorted({p.suffix for p in check_reports.rglob("*") if p.suffix in (".html", ".pdf")})
            if written != [".html", ".pdf"]:
                raise SystemExit(f"designkit synth --out wrote {written}, expected an HTML and a PDF report")
    return out


def _parallel_speedup(repeat: int = 3) -> float:
    """Two CPU-bound Python processes at once vs one after the other: the wall-time ratio (2.0 is two
    full cores; SMT siblings or a shared host give less)."""
    cmd = [sys.executable, "-c", _SPIN]
    serial, parallel = [], []
    for _ in range(repeat):
        start = time.perf_counter()
        subprocess.run(cmd, check=True)
        subprocess.run(cmd, check=True)
        serial.append(time.perf_counter() - start)
        start = time.perf_counter()
        procs = [subprocess.Popen(cmd) for _ in range(2)]
        for p in procs:
            p.wait()
        parallel.append(time.perf_counter() - start)
    return statistics.median(serial) / statistics.median(parallel)


def _stack(out: Path) -> list[str]:
    """The third-party modules a study-free ``--jobs 1`` synth run imports, in import order."""
    proc = subprocess.run([sys.executable, "-c", _RECORD, str(SPEC), str(out)], check=True, capture_output=True,
                          text=True)
    return json.loads(proc.stdout.strip().splitlines()[-1])


def _phases() -> dict[str, float]:
    proc = subprocess.run([sys.executable, "-c", _PHASES, str(SPEC)], check=True, capture_output=True, text=True)
    return json.loads(proc.stdout.strip().splitlines()[-1])


def _imports(out: Path, top: int = 15) -> list[tuple[str, float]]:
    """Modules with the largest cumulative import time (s) in one synth run (top-level imports first)."""
    proc = subprocess.run([sys.executable, "-X", "importtime", *SYNTH[1:], "--out", str(out)], check=False,
                          capture_output=True, text=True)
    rows = []
    for line in proc.stderr.splitlines():
        if not line.startswith("import time:") or "|" not in line[12:]:
            continue
        _self, cumulative, name = (part.strip() for part in line[12:].split("|"))
        if cumulative.isdigit():
            rows.append((name, int(cumulative) / 1e6))
    rows.sort(key=lambda r: -r[1])
    return rows[:top]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5, help="runs per command (median reported)")
    parser.add_argument("--phases", action="store_true", help="add an in-process breakdown by phase")
    parser.add_argument("--imports", action="store_true", help="list the most expensive imports of a synth run")
    parser.add_argument("--before", metavar="REF", help="also time the src/ of git revision REF (e.g. HEAD), "
                        "interleaved with the working tree, for a before/after comparison")
    args = parser.parse_args()
    env_note = os.environ.get("MPLBACKEND", "")
    import compileall

    compileall.compile_dir(str(ROOT / "src" / "designkit"), quiet=1)
    out = Path(tempfile.mkdtemp())
    try:
        base_cpu: list[float] = []
        synth_cpu: list[float] = []
        before_src = _checkout(args.before, out.parent / f"{out.name}-before") if args.before else None
        if before_src is not None:
            compileall.compile_dir(str(before_src), quiet=1)
        before: list[float] = []
        before_cpu: list[float] = []
        base = _times([sys.executable, "-c", "pass"], max(args.repeat, 5), cpu=base_cpu)
        stack_modules = _stack(out)
        from designkit.verification.solver_process import DEFERRED_AT_CVXPY_IMPORT

        stack_cmd = [sys.executable, "-c", _REPLAY, json.dumps(stack_modules), json.dumps(DEFERRED_AT_CVXPY_IMPORT)]
        synth, serial, serial_cpu, lean, lean_cpu, stack, stack_cpu = [], [], [], [], [], [], []
        lean_before: list[float] = []
        lean_before_cpu: list[float] = []
        env = {**os.environ, "PYTHONPATH": str(before_src)} if before_src is not None else None
        for _ in range(args.repeat):  # interleaved, so all see the same load
            stack += _times(stack_cmd, 1, cpu=stack_cpu)
            lean += _times([*SYNTH, "--out", str(out), "--no-studies"], 1, check_reports=out, cpu=lean_cpu)
            synth += _times([*SYNTH, "--out", str(out)], 1, check_reports=out, cpu=synth_cpu)
            serial += _times([*SYNTH, "--out", str(out), "--jobs", "1"], 1, check_reports=out, cpu=serial_cpu)
            if before_src is not None:
                lean_before += _times([*SYNTH, "--out", str(out), "--no-studies"], 1, check_reports=out,
                                      cpu=lean_before_cpu, env=env)
                before += _times([*SYNTH, "--out", str(out)], 1, check_reports=out, cpu=before_cpu, env=env)
        speedup = _parallel_speedup()
        phases = _phases() if args.phases else None
        imports = _imports(out) if args.imports else None
    finally:
        shutil.rmtree(out, ignore_errors=True)
        shutil.rmtree(out.parent / f"{out.name}-before", ignore_errors=True)
    b, s = statistics.median(base), statistics.median(synth)
    bc, sc = statistics.median(base_cpu), statistics.median(synth_cpu)
    k, kc = statistics.median(stack), statistics.median(stack_cpu)
    n, nc = statistics.median(lean), statistics.median(lean_cpu)

    def row(name: str, runs: list[float], cpu: float | None) -> str:
        m = statistics.median(runs)
        return (f"| {name} | {m:.3f} | {', '.join(f'{x:.2f}' for x in runs)} | {m / b:.1f} | {m / k:.2f} | "
                f"{'' if cpu is None else f'{cpu:.3f}'} |")

    print("| command | median wall time (s) | runs (s) | ratio to `python -c pass` | ratio to the stack's import | "
          "median CPU time (s) |")
    print("|---|---|---|---|---|---|")
    print(row("python -c pass (baseline)", base, bc))
    print(row(f"import the stack ({len(stack_modules)} modules)", stack, kc))
    print(row("designkit synth posspeed-link --out DIR --no-studies (HTML + PDF)", lean, nc))
    if lean_before:
        print(row(f"same, src/ of {args.before} (before)", lean_before, statistics.median(lean_before_cpu)))
    print(row("designkit synth posspeed-link --out DIR (with the studies)", synth, sc))
    ss, ssc = statistics.median(serial), statistics.median(serial_cpu)
    print(row("same with --jobs 1 (one process)", serial, ssc))
    if before:
        bsc = statistics.median(before_cpu)
        print(row(f"same as the default, src/ of {args.before} (before)", before, bsc))
    print("\nCPU time (user + system of the command and the processes it forks: the solver process and the "
          "figure process) is less sensitive than wall time to other load on the machine.")
    print(f"\n--jobs 2 vs --jobs 1: {ss / s:.2f}x faster; this machine runs two CPU-bound processes "
          f"{speedup:.2f}x faster at once than one after the other (2.0 = two full cores).")
    verdict = "within" if n / k <= BUDGET_RATIO else "OVER"
    load = os.getloadavg() if hasattr(os, "getloadavg") else None
    print(f"\nbudget: the study-free synth within {BUDGET_RATIO:.1f}x the stack's import: {verdict} ({n / k:.2f}x, "
          f"{n:.2f} s against {k:.2f} s); load average at the end "
          f"{', '.join(f'{x:.2f}' for x in load) if load else 'n/a'} on {os.cpu_count()} cores")
    if phases:
        print("\n| phase (one in-process run) | seconds |\n|---|---|")
        for name, sec in phases.items():
            print(f"| {name} | {sec:.3f} |")
    if imports:
        print("\n| module (synth run, -X importtime) | cumulative import (s) |\n|---|---|")
        for name, sec in imports:
            print(f"| {name} | {sec:.3f} |")
    (ROOT / "benchmarks" / "results").mkdir(exist_ok=True)
    record = {
        "python -c pass (baseline)": b, "import the stack": k,
        "designkit synth posspeed-link --no-studies (HTML + PDF)": n,
        "designkit synth posspeed-link (HTML + PDF, studies)": s, "designkit synth --jobs 1": ss,
        "stack": stack_modules,
        "runs": {"baseline": base, "stack": stack, "synth_no_studies": lean, "synth": synth, "synth_jobs_1": serial},
        "cpu_s": {"baseline": bc, "stack": kc, "synth_no_studies": nc, "synth": sc, "synth_jobs_1": ssc},
        "cpu_runs": {"baseline": base_cpu, "stack": stack_cpu, "synth_no_studies": lean_cpu, "synth": synth_cpu,
                     "synth_jobs_1": serial_cpu},
        "ratio_to_python_c_pass": s / b, "ratio_no_studies_to_stack": n / k, "ratio_to_stack": s / k,
        "parallel_speedup_of_two_processes": speedup,
        "before": {"ref": args.before, "runs": before, "cpu_runs": before_cpu, "runs_no_studies": lean_before,
                   "cpu_runs_no_studies": lean_before_cpu,
                   "ratio_no_studies_to_stack": statistics.median(lean_before) / k if lean_before else None,
                   "ratio_to_stack": statistics.median(before) / k} if before else None,
        "budget_ratio_to_stack": BUDGET_RATIO,
        "within_budget": n / k <= BUDGET_RATIO, "phases": phases, "imports": imports,
        "machine": {"python": platform.python_version(), "platform": platform.platform(),
                    "cpu_count": os.cpu_count(), "load_average_end": list(load) if load else None,
                    "MPLBACKEND": env_note},
    }
    (ROOT / "benchmarks" / "results" / "synth.json").write_text(json.dumps(record, indent=2) + "\n")


if __name__ == "__main__":
    main()
