"""What re-simulating every proposed fix costs a report, on the failing examples of the core.

Run apart from the tests:  python benchmarks/bench_fixes.py [--repeat N]

Per spec, in one process and interleaved (median of N): the pipeline run (``designkit.run``), the diagnosis
without re-simulation (``diagnose(result, resimulate=False)``: what the report cost before), the diagnosis with
it (``diagnose(result)``), and the alternative a user would pick: each proposed remedy applied to the spec by
hand and run with ``designkit.run`` (what ``designkit synth fixed.yaml --no-report`` does after start-up).
The ratios are quoted: the extra the report pays (with / without re-simulation, and against the pipeline run
alone), and the re-simulation against doing it by hand.  Writes benchmarks/results/fixes.json.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SPECS = ["infeasible-requirements", "posspeed-relay", "puma560-computed-torque-payload", "scara-decentralized-pid"]


def _time(fn) -> float:
    t = time.perf_counter()
    fn()
    return time.perf_counter() - t


def main() -> None:
    import designkit as dk
    from designkit.analysis.diagnosis import diagnose
    from designkit.analysis.diagnosis.resimulate import changed_spec

    parser = argparse.ArgumentParser()
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    out = {"machine": {"python": platform.python_version(), "cpus": os.cpu_count(),
                       "load_1min": os.getloadavg()[0]}, "specs": {}}
    for name in SPECS:
        loaded = dk.load_spec(ROOT / "specs" / f"{name}.yaml")
        result = dk.run(loaded)
        remedies = [t.remedy for t in {id(t): t for p in diagnose(result).proposed for t in p.trials}.values()]
        rows: dict[str, list[float]] = {"run": [], "diagnose_without": [], "diagnose_with": [], "by_hand": []}
        for _ in range(args.repeat):
            rows["run"].append(_time(lambda: dk.run(loaded)))  # noqa: B023
            rows["diagnose_without"].append(_time(lambda: diagnose(result, resimulate=False)))  # noqa: B023
            rows["diagnose_with"].append(_time(lambda: diagnose(result)))  # noqa: B023
            rows["by_hand"].append(_time(lambda: [dk.run(changed_spec(loaded, r.changes)) for r in remedies]))  # noqa: B023
        med = {k: statistics.median(v) for k, v in rows.items()}
        extra = med["diagnose_with"] - med["diagnose_without"]
        out["specs"][name] = {
            "remedies_re_run": len(remedies), "median_s": med,
            "extra_s": extra,
            "extra_over_run": extra / med["run"],
            "resimulation_over_by_hand": extra / med["by_hand"] if remedies else None,
        }
        print(f"{name}: {len(remedies)} re-runs; run {med['run']:.2f} s, diagnosis {med['diagnose_without']:.2f} s "
              f"-> {med['diagnose_with']:.2f} s (+{extra:.2f} s = {extra / med['run']:.2f} x the run); "
              f"by hand {med['by_hand']:.2f} s" + (f" (ratio {extra / med['by_hand']:.2f})" if remedies else ""))
    path = ROOT / "benchmarks" / "results" / "fixes.json"
    path.write_text(json.dumps(out, indent=2) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
