"""Planning cost of the limit-holding FIR plan (``plan_fir(..., limits=...)``) on seeded CAM-like paths.

    PYTHONPATH=. python benchmarks/bench_fir_limits_cost.py [--segments N] [--seeds 3 ...] [--repeats R]

Per seed: ``cam_like_path(N, seed)`` at F = 200 mm/s, T1/T2 = 60/30 ms, eps = 50 um, under the
nominal FIR envelope (``AxisLimits.fir_envelope``) and under the plain plan's own peaks (which the
plain FIR keeps by construction). Prints best-of-R wall time of plain and limit-holding planning
(first call, JAX compile, apart), their ratio, cycle times, the worst limit ratio measured on the
sampled trajectory (``metrics.limit_ratios``), the corner error and the path deviation. Targets
(recorded in benchmarks/README.md, bench_fir_optimal section): envelope case within ~2x of the
0.3 s the 15 %-step repair took; under the plain plan's own peaks no slower than before. For a
before -> after comparison run the script twice, with ``PYTHONPATH`` on each package version.
"""
from __future__ import annotations

import argparse
import time

import numpy as np

from research.experiments.optimality import cam_like_path
from research.interpolators.fir import plan_fir
from research.limits import AxisLimits
from research.metrics import limit_ratios, peak_axis_values

F, D, EPS = 200.0, (0.06, 0.03), 50e-3


def best_of(fn, repeats):
    out, best = None, np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return out, best


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--segments", type=int, default=400)
    ap.add_argument("--seeds", type=int, nargs="+", default=[3])
    ap.add_argument("--repeats", type=int, default=2)
    args = ap.parse_args()
    with open("/proc/loadavg") as f:
        print("load:", f.read().strip())
    for seed in args.seeds:
        path = cam_like_path(args.segments, seed=seed)
        plan_fir(path, F, D, EPS)  # compile
        plain, t_plain = best_of(lambda: plan_fir(path, F, D, EPS), args.repeats)
        tr = plain.trajectory()
        for conv, limits in (("envelope", AxisLimits.fir_envelope(path.dim, F, D)),
                             ("plain peaks", AxisLimits(*(peak_axis_values(tr, nu) for nu in (1, 2, 3))))):
            held, t_held = best_of(lambda: plan_fir(path, F, D, EPS, limits=limits), args.repeats)
            htr = held.trajectory()
            w = max(float(np.max(r)) for r in limit_ratios(htr, limits).values())
            print(f"seed {seed} {conv:11s}: plain {t_plain:.3f} s, held {t_held:.3f} s ({t_held / t_plain:.2f}x plain); "
                  f"T plain {float(plain.cycle_time):.4f} s, held {float(held.cycle_time):.4f} s, worst {w:.6f}, "
                  f"corner {float(np.max(held.corner_errors)) / EPS:.4f} eps, deviation {held.path_deviation / EPS:.4f} eps, rounds {held.rounds}")


if __name__ == "__main__":
    main()
