"""Benchmark of the PUMA 560 model: build time, operation counts, batched inverse dynamics.

Run apart from the tests:  python benchmarks/bench_models.py  [--quick]
Pinned to one core (``os.sched_setaffinity``, like ``taskset -c 0``; BLAS/OpenMP threads = 1).
Baselines measured in the same run:

(a) build time of FK, Jacobian, M, C, g, RNEA and regressor against SymPy deriving the same
    Euler--Lagrange model (FK, link Jacobians, M, Christoffel C, g; no simplification), each
    SymPy derivation in a subprocess capped at ``--sympy-timeout`` seconds, for the first 2, 3
    and all 6 joints;
(b) operation counts against the course notes' figures (Lagrange--Euler 66,271 multiplications
    and 51,548 additions for n = 6) and the recursive Newton--Euler of Luh, Walker & Paul (1980),
    150n - 48 = 852 multiplications and 131n - 48 = 738 additions;
(c) inverse dynamics over 1e5 states: generated C (``casadi.Function.map``, serial) and the
    interpreted CasADi map against ``pinocchio.rnea`` called from Python in a loop, Pinocchio's
    model read from ``models/robots/puma560.urdf`` (same parameters, checked to 1e-10 first).

Prints a markdown table and writes benchmarks/results/models.json.  Skips SymPy or Pinocchio
with a message when they are not installed.
"""

from __future__ import annotations

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import platform  # noqa: E402
import statistics  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from importlib.resources import files  # noqa: E402
from pathlib import Path  # noqa: E402

import casadi  # noqa: E402
import numpy as np  # noqa: E402

from designkit.models.codegen import compile_function  # noqa: E402
from designkit.models.robots import robot  # noqa: E402
from designkit.models.summary import operation_counts  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
FUNCTIONS = ("fkine", "jacobian", "mass_matrix", "coriolis_matrix", "gravity_torque", "inverse_dynamics",
             "regressor")
NOTES_LE = {"multiplications": 66_271, "additions": 51_548}
LUH_RNEA = {"multiplications": 150 * 6 - 48, "additions": 131 * 6 - 48}

SYMPY_SCRIPT = r'''
import sys, time
import sympy as sp
from designkit.models.robots import robot
start = time.perf_counter()
n = int(sys.argv[1])
d = robot("puma560").description
links = d.links[:n]
q = sp.symbols(f"q1:{n + 1}")
qd = sp.symbols(f"qd1:{n + 1}")
def dh(a, alpha, dd, theta):  # standard DH
    ct, st, ca, sa = sp.cos(theta), sp.sin(theta), sp.cos(alpha), sp.sin(alpha)
    return sp.Matrix([[ct, -st * ca, st * sa, a * ct], [st, ct * ca, -ct * sa, a * st], [0, sa, ca, dd], [0, 0, 0, 1]])
def num(x):
    return sp.nsimplify(x, [sp.pi]) if abs(x - round(x)) > 0 else sp.Integer(round(x))
T = sp.eye(4)
frames = []
for i, l in enumerate(links):
    T = T * dh(num(l.a), num(l.alpha), num(l.d), q[i] + num(l.offset))
    frames.append(T)
g = sp.Matrix([num(v) for v in d.gravity])
M = sp.zeros(n, n)
V = 0
for i, (l, F) in enumerate(zip(links, frames)):
    R, p = F[:3, :3], F[:3, 3]
    c = sp.Matrix([sp.Float(v) for v in l.com])
    Ixx, Iyy, Izz, Ixy, Ixz, Iyz = (sp.Float(v) for v in l.inertia)
    Ic = sp.Matrix([[Ixx, Ixy, Ixz], [Ixy, Iyy, Iyz], [Ixz, Iyz, Izz]])
    m = sp.Float(l.mass)
    pc = p + R * c
    Jv = pc.jacobian(q)
    z = [sp.Matrix([0, 0, 1])] + [frames[k][:3, 2] for k in range(i)]
    Jw = sp.zeros(3, n)
    for k in range(i + 1):
        Jw[:, k] = z[k]
    M += m * Jv.T * Jv + Jw.T * R * Ic * R.T * Jw
    V += -m * (g.T * pc)[0]
G = sp.Matrix([sp.diff(V, qi) for qi in q])
C = sp.zeros(n, n)
for i in range(n):
    for j in range(n):
        C[i, j] = sum(sp.Rational(1, 2) * qd[k]
                      * (sp.diff(M[i, j], q[k]) + sp.diff(M[i, k], q[j]) - sp.diff(M[j, k], q[i]))
                      for k in range(n))
tau_ops = sp.count_ops(M) + sp.count_ops(C) + sp.count_ops(G)
print(time.perf_counter() - start, tau_ops)
'''


def median_time(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def build_puma(n: int = 6) -> None:
    arm = robot("puma560")
    if n < 6:
        from designkit.models.robot import robot_from_dh

        arm = robot_from_dh(arm.description, links=arm.description.links[:n])
    for name in FUNCTIONS:
        arm.functions[name]


def sympy_build(n: int, timeout: float) -> dict[str, object]:
    try:
        import sympy  # noqa: F401
    except ImportError:
        return {"status": "skipped: sympy not installed"}
    try:
        proc = subprocess.run([sys.executable, "-c", SYMPY_SCRIPT, str(n)], capture_output=True, text=True,
                              timeout=timeout, check=True)
    except subprocess.TimeoutExpired:
        return {"status": f"did not finish within {timeout:.0f} s", "seconds": None}
    except subprocess.CalledProcessError as exc:
        return {"status": f"failed: {exc.stderr.strip().splitlines()[-1]}"}
    seconds, ops = proc.stdout.split()
    return {"status": "ok", "seconds": float(seconds), "sympy_count_ops": int(ops)}


def time_map(f: casadi.Function, args: list[casadi.DM], repeat: int) -> float:
    """Seconds per evaluation of ``f`` mapped (serial) over the columns of ``args``."""
    count = args[0].shape[1]
    mapped = f.map(count, "serial")
    mapped.call(args)
    return median_time(lambda: mapped.call(args), repeat) / count


def pinocchio_loop(q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, reference: np.ndarray) -> dict[str, object]:
    try:
        import pinocchio as pin
    except ImportError:
        return {"status": "skipped: pinocchio not installed"}
    path = files("designkit.models.robots") / "puma560.urdf"
    model = pin.buildModelFromUrdf(str(path))
    model.gravity.linear = np.array([0.0, 0.0, -9.81])
    data = model.createData()
    assert all(joint.nq == 1 for joint in model.joints[1:]), "PUMA URDF joints are revolute with limits"
    rows = [np.ascontiguousarray(x) for x in (q, qd, qdd)]
    check = max(np.abs(pin.rnea(model, data, rows[0][k], rows[1][k], rows[2][k]) - reference[k]).max()
                for k in range(100))
    if check > 1e-10:
        return {"status": f"model mismatch {check:.2e}"}

    def loop() -> None:
        rnea = pin.rnea
        for a, b, c in zip(*rows, strict=True):
            rnea(model, data, a, b, c)

    seconds = median_time(loop, 3) / q.shape[0]
    return {"status": "ok", "us_per_eval": seconds * 1e6, "check_max_abs_diff": check, "version": pin.__version__}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="1e4 states and SymPy only up to 3 joints")
    parser.add_argument("--sympy-timeout", type=float, default=300.0)
    args = parser.parse_args()
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    states = 10_000 if args.quick else 100_000

    # (a) build time
    build_puma()  # warm-up: imports, first-call caches
    build = {f"designkit, {n} joints": median_time(lambda n=n: build_puma(n), 5) for n in (2, 3, 6)}
    sympy = {n: sympy_build(n, args.sympy_timeout) for n in ((2, 3) if args.quick else (2, 3, 6))}

    # (b) operation counts
    arm = robot("puma560")
    counts = {name: operation_counts(arm.functions[name]).__dict__ for name in
              ("inverse_dynamics", "mass_matrix", "coriolis_matrix", "gravity_torque", "regressor")}

    # (c) batched inverse dynamics
    rng = np.random.default_rng(0)
    q = rng.uniform(-math.pi, math.pi, (states, 6))
    qd, qdd = rng.uniform(-2, 2, (states, 6)), rng.uniform(-2, 2, (states, 6))
    dm = [casadi.DM(x.T) for x in (q, qd, qdd)]
    f = arm.functions["inverse_dynamics"]
    start = time.perf_counter()
    compiled = compile_function(f)
    compile_seconds = time.perf_counter() - start
    reference = np.asarray(f.map(states)(*dm)).T
    interpreted = time_map(f, dm, 3)
    generated = time_map(compiled.function, dm, 5) if compiled.compiled else None
    if compiled.compiled:
        diff = float(np.abs(np.asarray(compiled.function.map(states)(*dm)).T - reference).max())
    pin_result = pinocchio_loop(q, qd, qdd, reference)

    results = {
        "machine": {"python": platform.python_version(), "casadi": casadi.__version__, "cpu": platform.processor(),
                    "cores_used": 1},
        "build_seconds": build,
        "sympy_euler_lagrange": {str(k): v for k, v in sympy.items()},
        "operation_counts": counts,
        "notes_lagrange_euler_n6": NOTES_LE,
        "luh_walker_paul_rnea_n6": LUH_RNEA,
        "inverse_dynamics_batch": {
            "states": states,
            "casadi_interpreted_us": interpreted * 1e6,
            "generated_c_us": None if generated is None else generated * 1e6,
            "generated_c_status": "ok" if compiled.compiled else compiled.reason,
            "compile_seconds": compile_seconds,
            "generated_vs_interpreted_max_abs_diff": diff if compiled.compiled else None,
            "pinocchio_python_loop": pin_result,
        },
    }

    print("## PUMA 560 model benchmark (one core)\n")
    print("| measurement | designkit | baseline | ratio | goal |")
    print("|---|---|---|---|---|")
    b6 = build["designkit, 6 joints"]
    for n in sympy:
        s = sympy[n]
        ours = build[f"designkit, {n} joints"]
        goal = "< 0.2 s" if n == 6 else ""
        if s.get("seconds"):
            print(f"| build FK, J, M, C, g, RNEA, W ({n} joints) | {ours:.3f} s | SymPy E-L {s['seconds']:.1f} s | "
                  f"{s['seconds'] / ours:.0f}x | {goal} |")
        else:
            print(f"| build FK, J, M, C, g, RNEA, W ({n} joints) | {ours:.3f} s | SymPy E-L: {s['status']} "
                  f"| | {goal} |")
    if 6 not in sympy:
        print(f"| build FK, J, M, C, g, RNEA, W (6 joints) | {b6:.3f} s | | | < 0.2 s |")
    c = counts["inverse_dynamics"]
    print(f"| inverse dynamics, CasADi instructions | {c['instructions']} | | | <= 730 |")
    print(f"| inverse dynamics, multiplications / additions | {c['multiplications']} / {c['additions']} | "
          f"RNEA (Luh et al.) {LUH_RNEA['multiplications']} / {LUH_RNEA['additions']}; notes' L-E "
          f"{NOTES_LE['multiplications']} / {NOTES_LE['additions']} | "
          f"{LUH_RNEA['multiplications'] / c['multiplications']:.1f}x fewer mult. than RNEA | |")
    le = [counts[k] for k in ("mass_matrix", "coriolis_matrix", "gravity_torque")]
    print(f"| our E-L route (M, C, g) mult. / add. | {sum(x['multiplications'] for x in le)} / "
          f"{sum(x['additions'] for x in le)} | notes' L-E {NOTES_LE['multiplications']} / "
          f"{NOTES_LE['additions']} | | |")
    print(f"| inverse dynamics, CasADi interpreted map | {interpreted * 1e6:.3f} us/eval | | | |")
    if generated is not None:
        line = f"| inverse dynamics, generated C map ({states:.0e} states) | {generated * 1e6:.3f} us/eval | "
        if pin_result.get("status") == "ok":
            ratio = pin_result["us_per_eval"] / (generated * 1e6)
            line += f"pinocchio.rnea Python loop {pin_result['us_per_eval']:.3f} us/eval | {ratio:.1f}x | <= 0.7 us |"
        else:
            line += f"pinocchio: {pin_result['status']} | | <= 0.7 us |"
        print(line)
    else:
        print(f"| generated C | {compiled.reason} | | | |")
    out = ROOT / "benchmarks" / "results"
    out.mkdir(exist_ok=True)
    (out / "models.json").write_text(json.dumps(results, indent=2, default=str))
    print(f"\nwritten {out / 'models.json'}")


if __name__ == "__main__":
    main()
