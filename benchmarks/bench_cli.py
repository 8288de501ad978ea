"""End-to-end CLI timings: `designkit --help` latency and `designkit synth` on the POSSPEED spec.

Run apart from the tests:  python benchmarks/bench_cli.py
Baseline measured in the same run: `python -c pass` (interpreter start-up), so the figures are
also quoted as ratios against it.  Writes benchmarks/results/cli.json.
"""

from __future__ import annotations

import json
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
        subprocess.run(cmd, check=False, capture_output=True)
        times.append(time.perf_counter() - start)
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
    shutil.rmtree(out, ignore_errors=True)
    base = results["python -c pass (baseline)"]
    print("| command | median wall time (s) | ratio to `python -c pass` |")
    print("|---|---|---|")
    for name, seconds in results.items():
        print(f"| {name} | {seconds:.3f} | {seconds / base:.1f} |")
    (ROOT / "benchmarks" / "results").mkdir(exist_ok=True)
    (ROOT / "benchmarks" / "results" / "cli.json").write_text(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
