"""End-to-end CLI timings: `designkit --help` latency and `designkit synth` on the POSSPEED spec.

Run apart from the tests:  python benchmarks/bench_cli.py
Baseline measured in the same run: `python -c pass` (interpreter start-up), so the figures are
also quoted as ratios against it.  Every command must exit 0 (the POSSPEED spec verifies), and the
report run must write its HTML and PDF, else the benchmark fails: a broken command is not timed.
Writes benchmarks/results/cli.json (seconds per command, plus exit codes and the machine).
"""

from __future__ import annotations

import json
import os
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SPEC = ROOT / "specs" / "posspeed-link.yaml"
DESIGNKIT = shutil.which("designkit") or "designkit"


def _median_seconds(cmd: list[str], repeat: int) -> float:
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        proc = subprocess.run(cmd, check=False, capture_output=True, text=True)
        times.append(time.perf_counter() - start)
        if proc.returncode != 0:
            tail = (proc.stderr or proc.stdout).strip().splitlines()[-3:]
            raise SystemExit(f"{' '.join(cmd)} exited {proc.returncode}: " + " | ".join(tail))
    return statistics.median(times)


def main() -> None:
    out = Path(tempfile.mkdtemp())
    results = {
        "python -c pass (baseline)": _median_seconds([sys.executable, "-c", "pass"], 7),
        "designkit --help": _median_seconds([DESIGNKIT, "--help"], 7),
        "designkit synth posspeed --no-report": _median_seconds(
            [DESIGNKIT, "synth", str(SPEC), "--no-report"], 3),
        "designkit synth posspeed (HTML + PDF)": _median_seconds(
            [DESIGNKIT, "synth", str(SPEC), "--out", str(out)], 3),
    }
    written = sorted({p.suffix for p in out.rglob("*") if p.suffix in (".html", ".pdf")})
    shutil.rmtree(out, ignore_errors=True)
    if ".html" not in written or ".pdf" not in written:
        raise SystemExit(f"designkit synth --out wrote {written}, expected an HTML and a PDF report")
    base = results["python -c pass (baseline)"]
    print("| command | median wall time (s) | ratio to `python -c pass` |")
    print("|---|---|---|")
    for name, seconds in results.items():
        print(f"| {name} | {seconds:.3f} | {seconds / base:.1f} |")
    (ROOT / "benchmarks" / "results").mkdir(exist_ok=True)
    record = {**results, "ratios_to_python_c_pass": {k: v / base for k, v in results.items()},
              "all_exit_codes_zero": True, "reports_written": written,
              "machine": {"python": platform.python_version(), "platform": platform.platform(),
                          "cpu_count": os.cpu_count(),
                          "load_average_end": list(os.getloadavg()) if hasattr(os, "getloadavg") else None}}
    (ROOT / "benchmarks" / "results" / "cli.json").write_text(json.dumps(record, indent=2) + "\n")


if __name__ == "__main__":
    main()
