"""Benchmark: the hierarchy of control's proven sup|xi_i| on the PUMA 560 (six joints), and how it scales.

Scenario: ``specs/hierarchy-puma560.yaml`` -- the PUMA 560 with its friction and rotor inertias, the workspace
box, velocity and acceleration limits of the spec, each joint's acceleration box from the hierarchy (the later
joints at their sliding motion's acceleration).  The proven bound
(:func:`designkit.models.bounds.perturbation_enclosure`, at the spec's work limit of 150 boxes per joint) against
the alternative a user would pick: sampling ``|xi_i|`` by Newton--Euler at random points of the same box (20,000
points per joint, half on the velocity and acceleration vertices), an inner estimate with no guarantee.  Both in
the same run, interleaved, median of ``REPEAT`` rounds.

Also in the same run: the bound against the work limit (60, 150, 300 boxes per joint), and the scaling with the
number of joints: planar chains of 2, 3, 4 and 6 revolute links without friction (every joint in [-0.5, 0.5]
rad, 1 rad/s, 5 rad/s^2, 150 boxes per joint): time, boxes, the ball tapes' size, and the bound against the
attained value.

Goal: the PUMA 560's six bounds in at most 30 s on this 2-core machine (shared with other jobs: the load average
is recorded).

Run: ``python benchmarks/bench_hierarchy.py [--out PATH]``; writes ``benchmarks/results/hierarchy.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import time
from pathlib import Path
from typing import Any

import numpy as np

import designkit as dk
from designkit.models.bounds import perturbation_enclosure
from designkit.pipeline import run
from designkit.schema.loader import load_spec

ROOT = Path(__file__).resolve().parent
RESULTS = ROOT / "results" / "hierarchy.json"
SPEC = ROOT.parent / "specs" / "hierarchy-puma560.yaml"
PAYLOAD_SPEC = ROOT.parent / "specs" / "hierarchy-puma560-payload.yaml"
GOAL_S = 30.0
REPEAT = 3
SAMPLES = 20000


def _inputs(design: Any) -> dict[str, Any]:
    info = design.data
    ws = info.workspace
    return {"q": (np.array(ws["low"]), np.array(ws["high"])), "qd_limit": np.array(ws["velocity"]),
            "qdd_limits": np.array(info.acceleration_rows),
            "inertia": [lk.inertia for lk in info.links], "damping": [lk.damping for lk in info.links],
            "coulomb": info.coulomb, "gravity": info.gravity_feedforward == "none"}


def _sampled(plant: Any, kw: dict[str, Any], count: int, seed: int) -> tuple[float, list[float]]:
    """Largest |xi_i| by Newton--Euler at ``count`` random points per joint (half on the vertices)."""
    t0 = time.perf_counter()
    arm, p, n = plant.robot, plant.model_parameters(), plant.n_joints
    lo, hi = kw["q"]
    V, Dh, f = kw["qd_limit"], np.array(kw["inertia"]), np.array(kw["damping"])
    rng = np.random.default_rng(seed)
    best = []
    for i in range(n):
        A = kw["qdd_limits"][i]
        q = lo + (hi - lo) * rng.random((count, n))
        qd, qdd = V * rng.uniform(-1, 1, (count, n)), A * rng.uniform(-1, 1, (count, n))
        qd[: count // 2], qdd[: count // 2] = V * np.sign(qd[: count // 2]), A * np.sign(qdd[: count // 2])
        tau = arm.inverse_dynamics(q, qd, qdd, p=p).reshape(count, n)
        if not kw["gravity"]:
            tau = tau - arm.gravity_torque(q, p=p).reshape(count, n)
        best.append(float(np.max(np.abs(Dh[i] * qdd[:, i] + f[i] * qd[:, i] - tau[:, i]))))
    return time.perf_counter() - t0, best


def _chain(n: int) -> Any:
    links = [{"a": 0.5 - 0.05 * k, "mass": 4.0 - 0.5 * k, "com": [-(0.25 - 0.025 * k), 0, 0],
              "inertia": [0, (4.0 - 0.5 * k) * (0.5 - 0.05 * k) ** 2 / 12, (4.0 - 0.5 * k) * (0.5 - 0.05 * k) ** 2 / 12,
                          0, 0, 0]} for k in range(n)]
    return dk.robot_from_dh(name=f"planar{n}r", links=links)


def _payload() -> dict[str, Any]:
    """The design of ``specs/hierarchy-puma560-payload.yaml`` (the six bounds over the workspace, velocity and
    acceleration boxes and the payload's mass interval: the uncertain parameter is one more side of the enclosure),
    timed whole."""
    from designkit.pipeline import design, plant

    loaded = load_spec(PAYLOAD_SPEC)
    arm = plant(loaded)
    t, c = time.perf_counter(), time.process_time()
    d = design(loaded, arm)
    seconds, cpu = time.perf_counter() - t, time.process_time() - c
    info = d.data
    return {"seconds": seconds, "cpu_seconds": cpu, "goal_s": GOAL_S,
            "box": {k: list(v) for k, v in loaded.spec.plant.uncertainty.intervals.items()},
            "bound": list(info.bound), "attained": list(info.sampled), "boxes": info.enclosure.boxes}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=RESULTS)
    args = parser.parse_args()
    load = os.getloadavg()
    result = run(load_spec(SPEC), simulate=False)
    design = result.design
    plant = design.plant
    kw = _inputs(design)
    p = plant.model_parameters()
    limit_spec = int(design.data["work_limit"])
    proven, sampled = [], []
    cpu = []
    for r in range(REPEAT):  # interleaved
        t, c = time.perf_counter(), time.process_time()
        e = perturbation_enclosure(plant.robot, p=p, max_boxes=limit_spec, rel_tol=1e-3, **kw)
        proven.append((time.perf_counter() - t, e))
        cpu.append(time.process_time() - c)
        sampled.append(_sampled(plant, kw, SAMPLES, r))
    t_proven = statistics.median(x[0] for x in proven)
    t_cpu = statistics.median(cpu)
    t_sampled = statistics.median(x[0] for x in sampled)
    e = proven[0][1]
    puma = {"seconds": t_proven, "cpu_seconds": t_cpu, "goal_s": GOAL_S, "meets_goal": t_proven <= GOAL_S,
            "boxes": e.boxes,
            "bound": list(e.upper), "attained": list(e.sampled), "sampled_newton_euler": sampled[0][1],
            "sampled_seconds": t_sampled, "ratio_proven_over_sampled": t_proven / t_sampled,
            "gap": [u / s for u, s in zip(e.upper, e.sampled, strict=True)]}
    work = []
    for limit in (60, 150, 300):
        t, c = time.perf_counter(), time.process_time()
        w = perturbation_enclosure(plant.robot, p=p, max_boxes=limit, rel_tol=1e-3, **kw)
        work.append({"work_limit": limit, "seconds": time.perf_counter() - t, "cpu_seconds": time.process_time() - c,
                     "boxes": w.boxes,
                     "bound": list(w.upper), "attained": list(w.sampled)})
    payload = _payload()
    scaling = []
    for n in (2, 3, 4, 6):
        arm = _chain(n)
        lo, hi = np.full(n, -0.5), np.full(n, 0.5)
        Dh = np.diag(arm.mass_matrix(np.zeros(n)))
        t, c = time.perf_counter(), time.process_time()
        s = perturbation_enclosure(arm, q=(lo, hi), qd_limit=np.ones(n), qdd_limits=np.full((n, n), 5.0),
                                   inertia=Dh, damping=np.zeros(n), coulomb=np.zeros(n), gravity=False,
                                   max_boxes=150, rel_tol=1e-3, samples=500)
        scaling.append({"links": n, "seconds": time.perf_counter() - t, "cpu_seconds": time.process_time() - c,
                        "boxes": s.boxes,
                        "instructions": int(sum(arm.functions[k].n_instructions()
                                                for k in ("mass_matrix", "christoffel"))),
                        "bound": list(s.upper), "attained": list(s.sampled),
                        "largest_gap": max(u / a for u, a in zip(s.upper, s.sampled, strict=True))})
    out = {"benchmark": "hierarchy", "machine": {"cpus": os.cpu_count(), "python": platform.python_version(),
                                                 "load_average_at_start": load, "load_average_at_end": os.getloadavg()},
           "puma560": puma, "puma560_payload_box": payload, "work_limit": work, "scaling": scaling}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(out, indent=2) + "\n")
    print(f"PUMA 560, six bounds: {t_proven:.2f} s wall, {t_cpu:.2f} s CPU (goal {GOAL_S:g} s; sampling {SAMPLES} "
          "points per joint "
          f"{t_sampled:.2f} s, ratio {t_proven / t_sampled:.2f}); {e.boxes} boxes")
    print("  bound   ", " ".join(f"{v:8.3f}" for v in e.upper))
    print("  attained", " ".join(f"{v:8.3f}" for v in e.sampled))
    print(f"  with the payload box {payload['box']}: {payload['seconds']:.2f} s wall, {payload['cpu_seconds']:.2f} s "
          "CPU (the whole design)")
    for w in work:
        print(f"  work limit {w['work_limit']:5d}: {w['seconds']:6.2f} s ({w['cpu_seconds']:.2f} s CPU), "
              f"{w['boxes']} boxes, bound "
              + " ".join(f"{v:.3f}" for v in w["bound"]))
    for s in scaling:
        print(f"  {s['links']} links: {s['seconds']:6.2f} s ({s['cpu_seconds']:.2f} s CPU), {s['boxes']} boxes, "
              f"{s['instructions']} instructions; bound " + " ".join(f"{v:.3f}" for v in s["bound"]) + "; attained "
              + " ".join(f"{v:.3f}" for v in s["attained"]))
    print(f"load average {load} -> {os.getloadavg()}")


if __name__ == "__main__":
    main()
