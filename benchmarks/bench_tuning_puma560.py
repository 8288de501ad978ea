"""What ``designkit tune`` costs on the PUMA 560: computed torque's error poles for a tracking-error bound over a
payload box.

Run apart from the tests:  python benchmarks/bench_tuning_puma560.py [--budget S]

The problem: specs/puma560-computed-torque-payload.yaml (six joints, rotor inertias, the controller's model carrying a
2.0 kg payload while the true one is 2.5 kg, m6 anywhere in [2.34, 2.84] kg: the nominal, two corners and four seeded
samples), its error poles given as ``poles: [-20, -20]`` (every joint alike) instead of damping 1 and natural frequency
20 rad/s, and the law computed every 5 ms (the sampling that bounds how fast the poles may go), asked for
|q - qD| <= 1 mrad on every joint over the box.  One ``designkit.tune`` call, as ``designkit tune`` runs it (the search
within the budget, then the tuned spec's full verify); the goal is a tuned, verified spec within 5 minutes of wall time.
Writes benchmarks/results/tuning_puma560.json.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def spec_text() -> str:
    """The payload spec with poles instead of damping and natural frequency, sampled at 5 ms."""
    import yaml

    data = yaml.safe_load((ROOT / "specs" / "puma560-computed-torque-payload.yaml").read_text(encoding="utf-8"))
    data["name"] = "puma560-computed-torque-tune"
    data.pop("description")
    ctrl = data["controller"]
    del ctrl["damping"], ctrl["natural_frequency"]
    ctrl["poles"] = [-20, -20]
    data["simulation"]["sampling_period"] = 0.005
    return yaml.safe_dump(data, sort_keys=False)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--budget", type=float, default=240.0, help="the search's wall time (s)")
    args = parser.parse_args()
    import designkit as dk

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "spec.yaml"
        path.write_text(spec_text(), encoding="utf-8")
        start, cpu = time.perf_counter(), time.process_time()
        result = dk.tune(path, out=tmp, budget=args.budget)
        wall, cpu = time.perf_counter() - start, time.process_time() - cpu
        payload = result.to_json()
    out = {"problem": "PUMA 560 computed torque, error poles tuned for |q - qD| <= 1 mrad over m6 in [2.34, 2.84] kg, "
                      "5 ms sampling",
           "budget_seconds": args.budget, "wall_seconds": round(wall, 1), "cpu_seconds": round(cpu, 1),
           "verified": payload["verified"], "met": payload["met"],
           **{k: payload[k] for k in ("iterations", "restarts", "candidates", "simulations", "stopped", "at_bounds")},
           "points": len(payload["points"]) + 1,
           "initial": payload["initial"], "tuned": payload["tuned"],
           "tuned_checks": {c["name"]: c["achieved"] for c in payload["checks"]
                            if c["name"] in ("tracking_error", "tracking_bounds", "torque_limits")},
           "machine": {"cpus": os.cpu_count(), "python": platform.python_version(),
                       "load_average": os.getloadavg()}}
    target = ROOT / "benchmarks" / "results" / "tuning_puma560.json"
    target.write_text(json.dumps(out, indent=2) + "\n", encoding="utf-8")
    print(json.dumps({k: out[k] for k in ("wall_seconds", "verified", "simulations", "tuned_checks")}, indent=2))


if __name__ == "__main__":
    main()
