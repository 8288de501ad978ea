"""What the studies cost a report, against running the same variants by hand.

Run apart from the tests:  python benchmarks/bench_studies.py [--repeat N] [--spec NAME ...]

Per spec, in one process and interleaved (median of N, each repeat on a fresh pipeline result so that nothing is
cached between them): the pipeline run (``designkit.run``: design, simulation, checks), every study that applies
(``designkit.studies.run_studies``), and the alternative a user would pick: each variant the studies ran, written as
its own spec and run with ``designkit.run`` (what ``designkit verify variant.yaml`` does after start-up), timed on
the gain study's variants.  Quoted: the studies' seconds per variant and the studies against the by-hand runs.
Writes benchmarks/results/studies.json.
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
SPECS = ["posspeed-link", "mrac-link", "ilc-simnog", "simnog-decentralized-pid"]


def _time(fn) -> tuple[float, object]:
    t = time.perf_counter()
    out = fn()
    return time.perf_counter() - t, out


def _by_hand(result, study) -> list[float]:
    """Each gain-study variant written as its own spec (its YAML changed) and run with designkit.run."""
    import designkit as dk
    from designkit.families import family
    from designkit.runner.variants import changed_spec

    fam = family(result.design.kind)
    out = []
    for entry in study.entries:
        knob = fam.knob(entry.parameter)
        if knob is None or not knob.path:
            continue
        for row in entry.rows:
            if row.factor == 1.0:
                continue
            value = list(row.value) if isinstance(row.value, tuple) else row.value
            loaded = changed_spec(result.loaded, [(knob.path, value)])
            out.append(_time(lambda loaded=loaded: dk.run(loaded))[0])
    return out


def main() -> None:
    import designkit as dk
    from designkit.studies import run_studies

    parser = argparse.ArgumentParser()
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--spec", nargs="*", default=SPECS)
    args = parser.parse_args()
    results_path = ROOT / "benchmarks" / "results" / "studies.json"
    previous = json.loads(results_path.read_text()) if results_path.exists() else {}
    rows = dict(previous.get("specs", {}))
    for name in args.spec:
        loaded = dk.load_spec(ROOT / "specs" / f"{name}.yaml")
        dk.run(loaded)  # warm: the process has run the spec once, as a report does before its studies
        t_run, t1, runs, hand = [], [], 0, []
        for _ in range(args.repeat):
            dt, result = _time(lambda loaded=loaded: dk.run(loaded))
            t_run.append(dt)
            dt, studies = _time(lambda result=result: run_studies(result))
            t1.append(dt)
            runs = sum(s.runs for s in studies)
            gains = next((s for s in studies if s.name == "gains"), None)
            if gains is not None:
                hand += _by_hand(result, gains)
        one = statistics.median(t1)
        per_hand = statistics.median(hand) if hand else None
        rows[name] = {
            "run_s": statistics.median(t_run), "studies_s": one,
            "variants": runs, "per_variant_s": one / runs if runs else None,
            "by_hand_per_variant_s": per_hand,
            "studies_vs_by_hand": (one / runs) / per_hand if runs and per_hand else None,
        }
        print(name, json.dumps(rows[name]))
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else None
    results_path.parent.mkdir(exist_ok=True)
    results_path.write_text(json.dumps({"machine": platform.platform(), "cores": os.cpu_count(), "load": load,
                                        "repeat": args.repeat, "specs": rows}, indent=2) + "\n")


if __name__ == "__main__":
    main()
