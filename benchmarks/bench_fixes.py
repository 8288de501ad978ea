"""What re-simulating every proposed fix costs a report, on the failing examples of the core.

Run apart from the tests:  python benchmarks/bench_fixes.py [--repeat N] [--spec NAME ...]

``--spec`` measures only the named specs and replaces their entries in the results, keeping the others.

Per spec, in one process and interleaved (median of N): the pipeline run (``designkit.run``), the diagnosis
without re-simulation (``diagnose(result, resimulate=False)``: the report's cost without the re-runs), the fix
re-runs themselves (``check_fixes`` on the diagnosis' sentences: what the report pays for them on top, timed
directly, since the difference of two diagnoses drowns in the relay analysis' noise on a loaded machine), and
the alternative a user would pick: each proposed remedy applied to the spec by hand and run with ``designkit.run`` (what
``designkit synth fixed.yaml --no-report`` does after start-up).  The ratios are quoted: the extra against the
pipeline run alone, and against doing it by hand.  Writes benchmarks/results/fixes.json.
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
    from designkit.analysis.diagnosis.fixes import check_fixes
    from designkit.runner.variants import changed_spec

    parser = argparse.ArgumentParser()
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--spec", action="append", choices=SPECS, help="measure only this spec (repeatable)")
    args = parser.parse_args()
    path = ROOT / "benchmarks" / "results" / "fixes.json"
    machine = {"python": platform.python_version(), "cpus": os.cpu_count(), "load_1min": os.getloadavg()[0]}
    out = {"machine": machine, "specs": {}}
    if args.spec and path.exists():
        out = json.loads(path.read_text(encoding="utf-8"))
    for name in args.spec or SPECS:
        loaded = dk.load_spec(ROOT / "specs" / f"{name}.yaml")
        result = dk.run(loaded)
        diag = diagnose(result)
        remedies = [t.remedy for t in {id(t): t for p in diag.proposed for t in p.trials}.values()]
        sentences = tuple(dict.fromkeys(s for f in diag.findings for s in f.fixes))
        declared = {sentence: changes for f in diag.findings for sentence, changes in f.changes}
        infeasible = bool(diag.root_cause)
        rows: dict[str, list[float]] = {"run": [], "diagnose_without": [], "fix_reruns": [], "by_hand": []}
        for _ in range(args.repeat):
            rows["run"].append(_time(lambda: dk.run(loaded)))  # noqa: B023
            rows["diagnose_without"].append(_time(lambda: diagnose(result, resimulate=False)))  # noqa: B023
            rows["fix_reruns"].append(_time(lambda: check_fixes(result, sentences, infeasible,  # noqa: B023
                                                                declared=declared)))  # noqa: B023
            rows["by_hand"].append(_time(lambda: [dk.run(changed_spec(loaded, r.changes)) for r in remedies]))  # noqa: B023
        med = {k: statistics.median(v) for k, v in rows.items()}
        extra = med["fix_reruns"]
        out["specs"][name] = {
            "remedies_re_run": len(remedies), "median_s": med, "machine": machine,
            "extra_s": extra,
            "extra_over_run": extra / med["run"],
            "resimulation_over_by_hand": extra / med["by_hand"] if remedies else None,
        }
        print(f"{name}: {len(remedies)} re-runs; run {med['run']:.2f} s, diagnosis {med['diagnose_without']:.2f} s, "
              f"fix re-runs +{extra:.2f} s ({extra / med['run']:.2f} x the run); "
              f"by hand {med['by_hand']:.2f} s" + (f" (ratio {extra / med['by_hand']:.2f})" if remedies else ""))
    path.write_text(json.dumps(out, indent=2) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
