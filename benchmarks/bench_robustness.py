"""Robust-stability sweep: ``stable_fraction`` (batched Newton + vectorised Routh) over 10^5 sampled plants.

Run apart from the tests:  python benchmarks/bench_robustness.py
Goal: < 5 s for 10^5 plants on 2 cores.

Design: the PID tracker ``designkit.families.pid_tracking.design(LinkPlant(2.0, 0.5), [-1.0, -1.2, -1.5])``,
a slow tracker on a wide box ``Km`` in [0.1, 10], ``tau`` in [0.01, 5], so that both verdicts occur
(about 5 % unstable plants).  Timed: ``stable_fraction(design, {"Km": Km, "tau": tau})`` (the API path,
generic over named plant parameters), median of 5.

Baseline measured in the same run: a per-plant loop building the closed-loop matrix ``A`` of each
plant in NumPy (the law's closed form, ``x = (x1, x2, x3)``)::

    A = [[0, 1, 0], [-Km K1/tau, (Km/Km0 - 1 - Km K2)/tau, -Km K3/tau], [1, 0, 0]]

and calling ``numpy.linalg.eigvals``, timed on a 10^3 subsample and *extrapolated linearly* to
10^5 (the loop's cost per plant is constant).  The NumPy ``A`` is first checked against the one
designkit's sweep builds (``Sweeper.sweep(theta).A``) on the subsample and against
``closed_loop.linearize`` on a few plants, so that the same thing is timed; the two verdicts are
compared on the subsample, away from the stability boundary.  For information, the generic
per-plant path (``linearize(plant.with_params(...), law, r0)`` then ``eigvals``) is timed on a
smaller subsample.

Writes benchmarks/results/robustness.json.
"""

from __future__ import annotations

import cProfile
import json
import os
import platform
import pstats
import statistics
import time
from importlib import metadata
from pathlib import Path

import casadi
import numpy as np

from designkit.families.pid_tracking import design as tracking_design
from designkit.families.pid_tracking import law as tracking_law
from designkit.models.link import LinkPlant
from designkit.synthesis.closed_loop import linearize
from designkit.verification.robustness import Sweeper, stable_fraction

ROOT = Path(__file__).resolve().parents[1]
N, N_BASE, N_GENERIC, SEED = 100_000, 1_000, 200, 0
POLES = [-1.0, -1.2, -1.5]


def closed_loop_matrix(gains: dict[str, float], Km0: float, Km: float, tau: float) -> np.ndarray:
    """The tracker's closed-loop ``A`` on the link ``(Km, tau)``, written out in NumPy."""
    K1, K2, K3 = gains["K1"], gains["K2"], gains["K3"]
    return np.array([[0.0, 1.0, 0.0],
                     [-Km * K1 / tau, (Km / Km0 - 1.0 - Km * K2) / tau, -Km * K3 / tau],
                     [1.0, 0.0, 0.0]])


PROFILED = {  # cProfile entry (file fragment, function) -> label
    ("closed_loop.py", "equilibria"): "equilibria (batched Newton, incl. its Function.map construction)",
    ("closed_loop.py", "state_matrices"): "state_matrices (incl. its Function.map construction)",
    ("~", "<built-in method casadi._casadi.Function_map>"): "Function.map(N) construction (both)",
    ("~", "<built-in method casadi._casadi.Function_call>"): "CasADi evaluation (Function.call)",
    ("casadi.py", "toarray"): "CasADi DM -> NumPy conversion",
    ("_linalg.py", "eigvals"): "numpy.linalg.eigvals",
    ("_linalg.py", "norm"): "numpy.linalg.norm(A, 2) (batched SVD, for the Routh scaling)",
    ("robustness.py", "characteristic_coefficients"): "characteristic_coefficients (Faddeev-LeVerrier)",
    ("routh.py", "routh_batch"): "routh_batch",
}


def profile(design, samples: dict[str, np.ndarray]) -> dict[str, object]:
    """Where one ``stable_fraction`` call spends its time (cProfile cumulative seconds; profiling inflates them)."""
    prof = cProfile.Profile()
    prof.enable()
    stable_fraction(design, samples)
    prof.disable()
    stats = pstats.Stats(prof).stats  # (file, line, name) -> (cc, nc, tottime, cumtime, callers)
    total = max(v[3] for v in stats.values())
    out: dict[str, float] = {}
    for (file, _line, name), (_cc, _nc, _tt, cum, _callers) in stats.items():
        for (frag, fn), label in PROFILED.items():
            if name == fn and (frag == "~" or file.endswith(frag)):
                out[label] = out.get(label, 0.0) + cum
    return {"total_s_under_cprofile": total, "cumulative_s": out}


def main() -> None:
    nominal = LinkPlant(Km=2.0, tau=0.5)
    design = tracking_design(nominal, POLES)
    gains = {k: float(design.gains[k]) for k in ("K1", "K2", "K3")}
    rng = np.random.default_rng(SEED)
    Km = rng.uniform(0.1, 10.0, N)
    tau = rng.uniform(0.01, 5.0, N)

    # the same thing is timed: the NumPy A equals designkit's, on the subsample and via linearize
    sweep_A = Sweeper(design, ("Km", "tau")).sweep(np.column_stack([Km[:N_BASE], tau[:N_BASE]])).A
    ours_A = np.array([closed_loop_matrix(gains, nominal.Km, k, t) for k, t in zip(Km[:N_BASE], tau[:N_BASE],
                                                                                  strict=True)])
    a_diff = float(np.max(np.abs(sweep_A - ours_A) / np.maximum(1.0, np.abs(ours_A))))
    law = tracking_law(design)
    lin_diff = max(float(np.max(np.abs(linearize(nominal.with_params(Km=float(k), tau=float(t)), law,
                                                 [0.0, 0.0, 0.0])[0].A - closed_loop_matrix(gains, nominal.Km, k, t))))
                   for k, t in zip(Km[:5], tau[:5], strict=True))
    assert a_diff < 1e-9 and lin_diff < 1e-9, f"closed-loop matrices differ: {a_diff:g}, {lin_diff:g}"

    samples = {"Km": Km, "tau": tau}
    stable_fraction(design, {"Km": Km[:100], "tau": tau[:100]})  # warm-up (imports, caches)
    times = []
    fast = None
    for _ in range(5):
        t0 = time.perf_counter()
        fast = stable_fraction(design, samples)
        times.append(time.perf_counter() - t0)
    t_fast = statistics.median(times)
    assert fast is not None and fast.shape == (N,)

    t0 = time.perf_counter()
    slow, decidable = [], []
    for k, t in zip(Km[:N_BASE], tau[:N_BASE], strict=True):
        ev = np.linalg.eigvals(closed_loop_matrix(gains, nominal.Km, k, t))
        slow.append(bool(np.all(ev.real < 0)))
        decidable.append(np.min(np.abs(ev.real)) > 1e-6 * np.max(np.abs(ev)))
    t_base = time.perf_counter() - t0
    t_base_extrapolated = t_base * N / N_BASE
    slow, decidable = np.array(slow), np.array(decidable)
    agree = bool(np.array_equal(fast[:N_BASE][decidable], slow[decidable]))

    where = profile(design, samples)

    t0 = time.perf_counter()
    for k, t in zip(Km[:N_GENERIC], tau[:N_GENERIC], strict=True):
        np.linalg.eigvals(linearize(nominal.with_params(Km=float(k), tau=float(t)), law, [0.0, 0.0, 0.0])[0].A)
    t_generic = time.perf_counter() - t0
    t_generic_extrapolated = t_generic * N / N_GENERIC

    results = {
        "plants": N,
        "design": f"pid_tracking on LinkPlant(Km=2.0, tau=0.5), poles {POLES}",
        "box": {"Km": [0.1, 10.0], "tau": [0.01, 5.0], "seed": SEED},
        "stable_fraction": float(fast.mean()),
        "vectorised_routh_seconds_median_of_5": t_fast,
        "vectorised_routh_seconds_all_5": times,
        "baseline": "per-plant loop: closed-loop A written out in NumPy, numpy.linalg.eigvals",
        "baseline_eigvals_loop_seconds_on_subsample": t_base,
        "baseline_subsample": N_BASE,
        "baseline_seconds_extrapolated_to_plants": t_base_extrapolated,
        "speed_up": t_base_extrapolated / t_fast,
        "verdicts_agree_on_subsample": agree,
        "numpy_A_vs_sweeper_A_max_rel_diff": a_diff,
        "numpy_A_vs_linearize_max_abs_diff": lin_diff,
        "generic_per_plant_linearize_loop": {
            "what": "closed_loop.linearize(plant.with_params(Km, tau), law, r0) then eigvals, per plant",
            "seconds_on_subsample": t_generic, "subsample": N_GENERIC,
            "seconds_extrapolated_to_plants": t_generic_extrapolated,
            "ratio_to_stable_fraction": t_generic_extrapolated / t_fast,
        },
        "profile_of_stable_fraction": where,
        "goal_seconds": 5.0,
        "goal_met": t_fast < 5.0,
        "cpu_count": os.cpu_count(),
        "machine": platform.machine(),
        "platform": platform.platform(),
        "load_average_end": list(os.getloadavg()) if hasattr(os, "getloadavg") else None,
        "python": platform.python_version(),
        "numpy": np.__version__,
        "casadi": casadi.__version__,
        "designkit": metadata.version("designkit"),
    }
    print("| sweep | plants | wall time (s) | ratio |")
    print("|---|---|---|---|")
    print(f"| `stable_fraction` (batched Newton + vectorised Routh) | {N} | {t_fast:.4f} | 1 |")
    print(f"| per-plant NumPy `A` + `eigvals` loop (timed on {N_BASE}, extrapolated) | {N} | "
          f"{t_base_extrapolated:.2f} | {t_base_extrapolated / t_fast:.0f} |")
    print(f"| per-plant `linearize` + `eigvals` loop (timed on {N_GENERIC}, extrapolated) | {N} | "
          f"{t_generic_extrapolated:.1f} | {t_generic_extrapolated / t_fast:.0f} |")
    print(f"stable fraction {fast.mean():.4f}; verdicts agree on the subsample: {agree}; goal < 5 s: "
          f"{'met' if t_fast < 5.0 else 'NOT met'}")
    (ROOT / "benchmarks" / "results").mkdir(exist_ok=True)
    (ROOT / "benchmarks" / "results" / "robustness.json").write_text(json.dumps(results, indent=2) + "\n")


if __name__ == "__main__":
    main()
