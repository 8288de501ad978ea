"""Benchmark: the learning certificate of a sampled linear plant -- the lifted map from its Markov parameters, the
norm ``rho = ||I - Q H||_2`` with its proved bracket and the spectral radius -- against the dense NumPy route, in
the same run.

Two sizes, each from cold caches (the lifted model and the contraction rebuilt every round), median of the rounds:

(a) **50 samples**: Moore's discrete two-state plant (``specs/ilc-moore-asymptotic.yaml``: A = [[-0.8, -0.22],
    [1, 0]], B = [0.5, 1], C = [1, 0.5]), the P-type update with gamma = 1.5 -- ``sampled_lifted`` and
    ``contraction`` (Lanczos, the power-iteration re-check, the symbol bound);
(b) **2,000 samples**: the continuous plant 2/(s^2 + 3 s + 2) sampled by the zero-order hold at 5 ms, the adjoint
    update with alpha = 1/sigma_max(H)^2 -- both sigma_max(H) and sigma_min(H) = 1/||H^-1||, each with its
    re-check and bracket -- and the P-type update with gamma = 100.

The baseline, in the same run and on the same matrices: the lifted matrix built densely from the Markov
parameters (``scipy.linalg.toeplitz``), ``numpy.linalg.norm(., 2)`` (a full SVD) and ``numpy.linalg.eigvals``;
the two routes' ``rho`` are compared (relative difference recorded).  The ratio quoted is the certificate's time
over the dense route's, both measured here.

Run: ``python benchmarks/bench_ilc_lifted.py [--repeat N]``; writes ``benchmarks/results/ilc_lifted.json``.  On a
loaded machine run it with ``OPENBLAS_NUM_THREADS=1`` (recorded in the results): LAPACK's threaded SVD of the dense
baseline then does not fight the other processes for the cores (with threads, at a load average of 15 on two cores,
the 2,000-sample dense norm took 158 s).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import time
from pathlib import Path

import numpy as np
import scipy.linalg as sl
from scipy.signal import cont2discrete

from designkit.families.ilc.lifted import sampled_lifted
from designkit.families.ilc.operators import Adjoint, PType, contraction

ROOT = Path(__file__).resolve().parents[1]


def _case(Phi: np.ndarray, Gamma: np.ndarray, C: np.ndarray, dt: float, samples: int, operator_of, repeat: int,
          dense_repeat: int) -> dict:
    args = (tuple(map(tuple, Phi)), tuple(Gamma), tuple(C), dt, samples, "bench")
    times, c = [], None
    for _ in range(repeat):
        sampled_lifted.cache_clear()
        contraction.cache_clear()
        t0 = time.perf_counter()
        lifted = sampled_lifted(*args)
        op = operator_of(lifted)
        c = contraction(lifted, op)
        times.append(time.perf_counter() - t0)
    L = lifted.L
    dense_t, rho_dense = [], None
    for _ in range(dense_repeat):
        t0 = time.perf_counter()
        h, x = np.empty(L), np.asarray(Gamma, dtype=float)
        for m in range(L):  # the Markov parameters by matrix powers
            h[m] = C @ x
            x = Phi @ x
        H = sl.toeplitz(h, np.zeros(L))
        Q = op.alpha * H.T if isinstance(op, Adjoint) else op.gain * np.eye(L)
        T = np.eye(L) - Q @ H
        rho_dense = float(np.linalg.norm(T, 2))
        radius = float(np.max(np.abs(np.linalg.eigvals(T))))
        dense_t.append(time.perf_counter() - t0)
    med, dmed = statistics.median(times), statistics.median(dense_t)
    return {"lifted_size": L, "learning": op.kind, "value": float(op.alpha if isinstance(op, Adjoint) else op.gain),
            "certificate_s": {"median": med, "min": min(times), "max": max(times), "rounds": repeat},
            "dense_numpy_s": {"median": dmed, "min": min(dense_t), "max": max(dense_t), "rounds": dense_repeat},
            "ratio_certificate_over_dense": med / dmed, "rho": c.rho, "rho_bounds": [c.lower, c.upper],
            "spectral_radius": c.spectral_radius, "rho_dense": rho_dense, "spectral_radius_dense": radius,
            "rho_relative_difference": abs(c.rho - rho_dense) / rho_dense}


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--repeat", type=int, default=21)
    args = parser.parse_args()
    load = os.getloadavg()[0]
    A = np.array([[-0.8, -0.22], [1.0, 0.0]])
    B = np.array([0.5, 1.0])
    C = np.array([1.0, 0.5])
    out = {"benchmark": "ilc_lifted", "machine": {"python": platform.python_version(), "cpus": os.cpu_count(),
                                                  "load_1min_before": load,
                                                  "OPENBLAS_NUM_THREADS": os.environ.get("OPENBLAS_NUM_THREADS")},
           "cases": {}}
    out["cases"]["moore_50_p_type_1.5"] = _case(A, B, C, 1.0, 51, lambda lm: PType(1.5), args.repeat,
                                                args.repeat)
    Ad, Bd, *_ = cont2discrete((np.array([[0.0, 1.0], [-2.0, -3.0]]), np.array([[0.0], [2.0]]),
                                np.array([[1.0, 0.0]]), np.zeros((1, 1))), 0.005, method="zoh")
    rounds = max(3, args.repeat // 4)
    out["cases"]["zoh_2000_adjoint"] = _case(Ad, Bd[:, 0], np.array([1.0, 0.0]), 0.005, 2001,
                                             lambda lm: Adjoint(1.0 / lm.sigma_max[0].estimate ** 2), rounds, 1)
    out["cases"]["zoh_2000_p_type_100"] = _case(Ad, Bd[:, 0], np.array([1.0, 0.0]), 0.005, 2001,
                                                lambda lm: PType(100.0), rounds, 1)
    out["machine"]["load_1min_after"] = os.getloadavg()[0]
    path = ROOT / "benchmarks" / "results" / "ilc_lifted.json"
    path.write_text(json.dumps(out, indent=2) + "\n", encoding="utf-8")
    for name, case in out["cases"].items():
        print(f"{name}: certificate {1e3 * case['certificate_s']['median']:.2f} ms, dense NumPy "
              f"{1e3 * case['dense_numpy_s']['median']:.1f} ms (x{case['ratio_certificate_over_dense']:.3f}); "
              f"rho {case['rho']:.6g} (dense {case['rho_dense']:.6g}), spectral radius {case['spectral_radius']:.6g}")


if __name__ == "__main__":
    main()
