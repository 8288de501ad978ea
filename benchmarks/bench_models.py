"""Benchmark of the PUMA 560 model: build time, operation counts, the plain NumPy calls.

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
(c) the PLAIN calls a user makes -- ``arm.inverse_dynamics(Q, QD, QDD)``, ``arm.mass_matrix(Q)``,
    ``arm.gravity_torque(Q)``, ``arm.forward_dynamics(Q, QD, TAU)`` on ``(N, 6)`` arrays, N = 1e5
    and 100 -- against Pinocchio called from a Python loop over the same states (``rnea``,
    ``crba``, ``computeGeneralizedGravity``, ``aba``; model read from ``models/robots/puma560.urdf``,
    checked against ours to 1e-10, scaled, first).  Goal: plain call <= 0.5x Pinocchio per state.
    *Cold cache*: a fresh robot with an empty private ``DESIGNKIT_CACHE_DIR`` (temporary folder);
    its first call (lookup, and for N >= ``batch.COMPILE_MIN_STATES`` the compilation) is reported
    apart from the steady per-state cost of the calls after it.  *Warm cache*: the library built
    by the cold run is on disk; the first call of a new process (subprocess, import and build
    not counted) and the steady cost of a fresh robot.  Also: the interpreted fallback (no
    compiler), and the named ``casadi.Function`` called directly (``casadi.DM`` conversions and
    an interpreted ``Function.map``, what ``arm.functions[name]`` gives);
(d) the raw ``casadi.Function.map`` of inverse dynamics on pre-converted ``casadi.DM`` inputs, as
    generated C (``-O3 -march=native``) and interpreted: the floor without any NumPy handling.

Prints markdown tables and writes benchmarks/results/models.json.  Skips SymPy or Pinocchio
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
import shutil  # noqa: E402
import statistics  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from importlib.resources import files  # noqa: E402
from pathlib import Path  # noqa: E402

import casadi  # noqa: E402
import numpy as np  # noqa: E402

from designkit.models import batch, codegen  # noqa: E402
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


PLAIN = {"inverse_dynamics": 3, "mass_matrix": 1, "gravity_torque": 1, "forward_dynamics": 3}
"""The plain calls timed in (c): function -> number of ``(N, 6)`` arguments."""
GOAL_RATIO = 0.5
"""Goal of the plain call: at most this fraction of Pinocchio's time per state (from Python)."""

WARM_SCRIPT = r"""
import sys, time
import numpy as np
from designkit.models.robots import robot
name, count, inputs = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
rng = np.random.default_rng(0)
args = [rng.uniform(-2.0, 2.0, (count, 6)) for _ in range(inputs)]
arm = robot("puma560")
arm.functions[name]  # build (not counted)
start = time.perf_counter()
getattr(arm, name)(*args)
print(time.perf_counter() - start, arm.evaluator(name).compiled)
"""


def per_state(fn, count: int, samples: int) -> float:
    """Median seconds per state of ``fn`` (which evaluates ``count`` states), calls grouped to >= 2e4 states."""
    inner = max(1, 20_000 // count)

    def group() -> None:
        for _ in range(inner):
            fn()

    return median_time(group, samples) / (inner * count)


def pinocchio_baselines(arm, rows: dict[str, list[np.ndarray]]) -> dict[str, object]:
    """Pinocchio's loop per function (``loop(count)`` over the first ``count`` states), checked against ours."""
    try:
        import pinocchio as pin
    except ImportError:
        return {"status": "skipped: pinocchio not installed"}
    path = files("designkit.models.robots") / "puma560.urdf"
    model = pin.buildModelFromUrdf(str(path))
    model.gravity.linear = np.array([0.0, 0.0, -9.81])
    data = model.createData()
    assert all(joint.nq == 1 for joint in model.joints[1:]), "PUMA URDF joints are revolute with limits"
    calls = {"inverse_dynamics": pin.rnea, "mass_matrix": pin.crba, "gravity_torque": pin.computeGeneralizedGravity,
             "forward_dynamics": pin.aba}
    loops, checks = {}, {}
    for name, fn in calls.items():
        args = rows[name]
        ours = getattr(arm, name)(*(a[:100] for a in args))
        theirs = np.array([fn(model, data, *(a[k] for a in args)).copy() for k in range(100)])
        if name == "mass_matrix":  # crba fills the upper triangle
            theirs = np.triu(theirs) + np.transpose(np.triu(theirs, 1), (0, 2, 1))
        checks[name] = float((np.abs(ours - theirs) / (1.0 + np.abs(theirs))).max())  # scaled, as in the tests
        if len(args) == 3:
            def loop(count: int, fn=fn, args=args) -> None:
                for x, y, z in zip(args[0][:count], args[1][:count], args[2][:count]):  # noqa: B905
                    fn(model, data, x, y, z)
        else:
            def loop(count: int, fn=fn, args=args) -> None:
                for x in args[0][:count]:
                    fn(model, data, x)
        loops[name] = loop
    if max(checks.values()) > 1e-10:
        return {"status": f"model mismatch {checks}"}
    return {"status": "ok", "version": pin.__version__, "check_max_scaled_diff": checks, "loops": loops}


def warm_first_call(name: str, count: int, inputs: int, cache: str) -> dict[str, object]:
    """First plain call of a new process whose cache holds the library (subprocess; import and build not counted)."""
    env = {**os.environ, "DESIGNKIT_CACHE_DIR": cache}
    proc = subprocess.run([sys.executable, "-c", WARM_SCRIPT, name, str(count), str(inputs)], capture_output=True,
                          text=True, check=True, env=env)
    seconds, compiled = proc.stdout.split()
    return {"seconds": float(seconds), "compiled": compiled == "True"}


def plain_calls(rows: dict[str, list[np.ndarray]], sizes: tuple[int, ...], pin: dict[str, object],
                samples: int) -> dict[str, object]:
    """(c): the plain NumPy calls, cold and warm cache, the fallback and the direct ``casadi.DM`` + ``map`` call."""
    results: dict[str, object] = {}
    saved = os.environ.get("DESIGNKIT_CACHE_DIR")
    roots = []
    try:
        for name, inputs in PLAIN.items():
            per_size: dict[str, object] = {}
            built = None  # cache folder of the largest batch's cold run
            for count in sorted(sizes, reverse=True):
                args = [a[:count] for a in rows[name]]
                entry: dict[str, object] = {"states": count}
                # cold cache: a fresh robot, an empty private cache
                cold_dir = tempfile.mkdtemp(prefix="bench-models-cold-")
                roots.append(cold_dir)
                os.environ["DESIGNKIT_CACHE_DIR"] = cold_dir
                arm = robot("puma560")
                arm.functions[name]  # build (timed in (a))
                method = getattr(arm, name)
                start = time.perf_counter()
                method(*args)
                first = time.perf_counter() - start
                evaluator = arm.evaluator(name)
                entry["cold"] = {"first_call_s": first, "path": evaluator.why, "compiled": evaluator.compiled,
                                 "us_per_state": per_state(lambda m=method, a=args: m(*a), count, samples) * 1e6}
                if built is None and evaluator.compiled:
                    built = cold_dir
                # warm cache: the library built above is on disk
                if built is not None:
                    os.environ["DESIGNKIT_CACHE_DIR"] = built
                    warm = robot("puma560")
                    warm_method = getattr(warm, name)
                    warm_out = warm_method(*args)
                    entry["warm"] = {
                        "first_call_new_process": warm_first_call(name, count, inputs, built),
                        "path": warm.evaluator(name).why, "compiled": warm.evaluator(name).compiled,
                        "us_per_state": per_state(lambda m=warm_method, a=args: m(*a), count, samples) * 1e6,
                    }
                # interpreted fallback (no compiler) and the direct casadi.DM + map call
                real_find = codegen.find_compiler
                codegen.find_compiler = lambda: None
                try:
                    plain = robot("puma560")
                    plain_method = getattr(plain, name)
                    interpreted_out = plain_method(*args)
                    entry["no_compiler_us_per_state"] = per_state(lambda m=plain_method, a=args: m(*a), count,
                                                                  samples) * 1e6
                finally:
                    codegen.find_compiler = real_find
                if "warm" in entry:
                    entry["compiled_equals_interpreted"] = bool(np.array_equal(warm_out, interpreted_out))
                f = plain.functions[name]
                mapped = f.map(count)
                shape = f.size_out(0)

                def dm_map(a=args, mapped=mapped, shape=shape, count=count) -> np.ndarray:
                    out = mapped.call([casadi.DM(x.T) for x in a])
                    return np.array(out[0]).reshape(shape[0], count, shape[1]).transpose(1, 0, 2)

                entry["dm_map_us_per_state"] = per_state(dm_map, count, samples) * 1e6
                if name == "inverse_dynamics":
                    dm = [casadi.DM(x.T) for x in args]
                    out = mapped.call(dm)
                    entry["dm_map_breakdown_us_per_state"] = {
                        "DM conversion of the inputs": per_state(lambda a=args: [casadi.DM(x.T) for x in a], count,
                                                                 samples) * 1e6,
                        "interpreted map call": per_state(lambda m=mapped, d=dm: m.call(d), count, samples) * 1e6,
                        "output to NumPy": per_state(lambda o=out: np.array(o[0]), count, samples) * 1e6,
                    }
                if pin.get("status") == "ok":
                    loop = pin["loops"][name]
                    pin_us = per_state(lambda lp=loop, c=count: lp(c), count, samples) * 1e6
                    entry["pinocchio_us_per_state"] = pin_us
                    for case in ("cold", "warm"):
                        if case in entry:
                            entry[case]["ratio_to_pinocchio"] = entry[case]["us_per_state"] / pin_us
                    if "warm" in entry:
                        entry["goal_met_warm"] = entry["warm"]["ratio_to_pinocchio"] <= GOAL_RATIO
                per_size[str(count)] = entry
            results[name] = per_size
    finally:
        if saved is None:
            os.environ.pop("DESIGNKIT_CACHE_DIR", None)
        else:
            os.environ["DESIGNKIT_CACHE_DIR"] = saved
        for root in roots:
            shutil.rmtree(root, ignore_errors=True)
    return results


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="1e4 states and SymPy only up to 3 joints")
    parser.add_argument("--sympy-timeout", type=float, default=300.0)
    args = parser.parse_args()
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    states = 10_000 if args.quick else 100_000
    sizes = (100, states)

    # (a) build time
    build_puma()  # warm-up: imports, first-call caches
    build = {f"designkit, {n} joints": median_time(lambda n=n: build_puma(n), 5) for n in (2, 3, 6)}
    sympy = {n: sympy_build(n, args.sympy_timeout) for n in ((2, 3) if args.quick else (2, 3, 6))}

    # (b) operation counts
    arm = robot("puma560")
    counts = {name: operation_counts(arm.functions[name]).__dict__ for name in
              ("inverse_dynamics", "mass_matrix", "coriolis_matrix", "gravity_torque", "regressor")}

    # (c) the plain calls
    rng = np.random.default_rng(0)
    q = rng.uniform(-math.pi, math.pi, (states, 6))
    qd, qdd = rng.uniform(-2, 2, (states, 6)), rng.uniform(-2, 2, (states, 6))
    tau = rng.uniform(-20, 20, (states, 6))
    rows = {"inverse_dynamics": [q, qd, qdd], "mass_matrix": [q], "gravity_torque": [q],
            "forward_dynamics": [q, qd, tau]}
    pin = pinocchio_baselines(arm, rows)
    plain = plain_calls(rows, sizes, pin, samples=5)

    # (d) the raw map on casadi.DM inputs
    dm = [casadi.DM(x.T) for x in (q, qd, qdd)]
    f = arm.functions["inverse_dynamics"]
    with tempfile.TemporaryDirectory(prefix="bench-models-raw-") as raw_cache:
        start = time.perf_counter()
        compiled = compile_function(f, directory=raw_cache)
        compile_seconds = time.perf_counter() - start
        reference = np.asarray(f.map(states)(*dm)).T
        interpreted = time_map(f, dm, 3)
        generated = time_map(compiled.function, dm, 5) if compiled.compiled else None
        diff = float(np.abs(np.asarray(compiled.function.map(states)(*dm)).T - reference).max()) \
            if compiled.compiled else None

    results = {
        "machine": {"python": platform.python_version(), "casadi": casadi.__version__, "cpu": platform.processor(),
                    "cores_used": 1},
        "build_seconds": build,
        "sympy_euler_lagrange": {str(k): v for k, v in sympy.items()},
        "operation_counts": counts,
        "notes_lagrange_euler_n6": NOTES_LE,
        "luh_walker_paul_rnea_n6": LUH_RNEA,
        "plain_call": {
            "goal": f"plain call <= {GOAL_RATIO}x Pinocchio (Python loop) per state",
            "block": batch.BLOCK, "compile_min_states": batch.COMPILE_MIN_STATES,
            "flags": " ".join(codegen.EXACT_FLAGS),
            "pinocchio": {k: v for k, v in pin.items() if k != "loops"},
            "functions": plain,
        },
        "raw_map_inverse_dynamics": {
            "states": states,
            "casadi_interpreted_us": interpreted * 1e6,
            "generated_c_us": None if generated is None else generated * 1e6,
            "generated_c_status": "ok" if compiled.compiled else compiled.reason,
            "generated_c_flags": " ".join(codegen.DEFAULT_FLAGS),
            "compile_seconds": compile_seconds,
            "generated_vs_interpreted_max_abs_diff": diff,
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
    print(f"| raw map of inverse dynamics on casadi.DM, interpreted | {interpreted * 1e6:.3f} us/eval | | | |")
    if generated is not None:
        print(f"| raw map of inverse dynamics on casadi.DM, generated C (-O3) | {generated * 1e6:.3f} us/eval | | | |")
    else:
        print(f"| generated C | {compiled.reason} | | | |")

    print(f"\n## Plain calls on (N, 6) arrays vs Pinocchio from a Python loop (goal <= {GOAL_RATIO}x per state)\n")
    if pin.get("status") != "ok":
        print(f"pinocchio: {pin['status']}\n")
    print("| call | N | cache | first call | per state | Pinocchio per state | ratio | goal met |")
    print("|---|---|---|---|---|---|---|---|")
    labels = {"inverse_dynamics": "arm.inverse_dynamics(Q, QD, QDD)", "mass_matrix": "arm.mass_matrix(Q)",
              "gravity_torque": "arm.gravity_torque(Q)", "forward_dynamics": "arm.forward_dynamics(Q, QD, TAU)"}
    for name, per_size in plain.items():
        for entry in per_size.values():
            n = entry["states"]
            pin_us = entry.get("pinocchio_us_per_state")
            pin_text = f"{pin_us:.3f} us" if pin_us else "-"
            for case in ("cold", "warm"):
                e = entry.get(case)
                if e is None:
                    continue
                first = e["first_call_s"] if case == "cold" else e["first_call_new_process"]["seconds"]
                ratio = e.get("ratio_to_pinocchio")
                kind = "compiled" if e["compiled"] else "interpreted"
                met = "" if ratio is None else ("yes" if ratio <= GOAL_RATIO else "no")
                print(f"| {labels[name]} | {n:.0e} | {case} ({kind}) | {first * 1e3:.1f} ms | "
                      f"{e['us_per_state']:.3f} us | {pin_text} | {'' if ratio is None else f'{ratio:.2f}x'} | "
                      f"{met} |")
            fallback = entry["no_compiler_us_per_state"]
            fallback_ratio = f"{fallback / pin_us:.2f}x" if pin_us else ""
            print(f"| {labels[name]} | {n:.0e} | no compiler (interpreted) | | {fallback:.3f} us | {pin_text} | "
                  f"{fallback_ratio} | |")
            print(f"| {labels[name]} | {n:.0e} | casadi.DM + interpreted map | | "
                  f"{entry['dm_map_us_per_state']:.3f} us | {pin_text} | | |")
    breakdown = plain["inverse_dynamics"][str(states)].get("dm_map_breakdown_us_per_state", {})
    if breakdown:
        print("\nWhere the direct casadi.DM + map call spends its time (inverse dynamics, per state): "
              + "; ".join(f"{k} {v:.3f} us" for k, v in breakdown.items()))
    met = [entry.get("goal_met_warm") for entry in plain["inverse_dynamics"].values()]
    print(f"\nGoal (warm cache, inverse dynamics, N = {', '.join(plain['inverse_dynamics'])}): "
          f"{'met' if all(met) else 'NOT met'} ({met})")
    out = ROOT / "benchmarks" / "results"
    out.mkdir(exist_ok=True)
    (out / "models.json").write_text(json.dumps(results, indent=2, default=str))
    print(f"\nwritten {out / 'models.json'}")


if __name__ == "__main__":
    main()
