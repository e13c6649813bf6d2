"""Limit-holding planning on chains of blocks under limits below the FIR envelope: linear in N?

    python benchmarks/bench_fir_limit_chain.py [--sizes 250 1000 4000] [--repeats 2]

A straight 1,000 mm line cut into N equal blocks and a circle of radius 2 m in N chords, at
F = 12.2 mm/s with T1/T2 = 20/10 ms, tolerance 0.1 um, under uniform limits v = 12.2 mm/s,
a = 500 mm/s^2, j = 1e4 mm/s^3: below the envelope (F / T1 = 610 mm/s^2, F / (T1 T2) = 61,000
mm/s^3), so every block alone runs at most at j T1 T2 = 2 mm/s (Sencer 2015 §2.1: a pulse peaks at
F / (T1 T2)) and each slowed block's feed step breaks its neighbour's corner. Before the slow-down
was followed along the chain (``_fir_limit_spread``) this took N / 2 rounds (~N^2 planning).

Prints per size: best-of-R process time of ``plan_fir(..., limits=...)`` (``timeit.repeat``; the
first call, with compilations, apart), rounds, cycle time (the line's against ``L / v + T_d``, the velocity limit all
the way, and against every block at the feed of a start from rest, ``L / (J T1 T2) + T_d``), and
time per block relative to the smallest size's in the same run; then the scaling exponent
``log(t_max / t_min) / log(N_max / N_min)``. Target: exponent <= 1.2 (linear up to the
log-factors of sorting and the doubling runs): PASS / MISS as measured.
"""

from __future__ import annotations

import argparse
import time
import timeit

import numpy as np

import research  # noqa: F401  (sets jax_enable_x64)
from research.interpolators import plan_fir
from research.limits import AxisLimits
from research.paths import Polyline

FEED, DELAYS, TOL = 12.2, (0.02, 0.01), 1e-4  # [mm/s], [s], [mm]
LIMITS = (12.2, 500.0, 1e4)  # v [mm/s], a [mm/s^2], j [mm/s^3]
TARGET_EXPONENT = 1.2


def line(n: int) -> Polyline:
    x = np.linspace(0.0, 1000.0, n + 1)
    return Polyline(np.column_stack([x, 0.0 * x]))


def circle(n: int) -> Polyline:
    a = np.linspace(0.0, 2.0 * np.pi, n + 1)
    return Polyline(2000.0 * np.column_stack([np.cos(a), np.sin(a)]))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[250, 1000, 4000])
    ap.add_argument("--repeats", type=int, default=2)
    args = ap.parse_args()
    with open("/proc/loadavg") as f:
        print("load:", f.read().strip())
    lim = AxisLimits.uniform(2, *LIMITS)
    feed_cap = min(LIMITS[0], LIMITS[1] * DELAYS[0], LIMITS[2] * DELAYS[0] * DELAYS[1])
    t = time.process_time()
    plan_fir(line(20), FEED, DELAYS, TOL, limits=lim)
    print(f"first call (compilations): {time.process_time() - t:.2f} s")
    for name, make in (("line", line), ("circle", circle)):
        per_block = []
        for n in args.sizes:
            path = make(n)
            plan = plan_fir(path, FEED, DELAYS, TOL, limits=lim)
            t = min(timeit.repeat(lambda: plan_fir(path, FEED, DELAYS, TOL, limits=lim), timer=time.process_time,
                                  number=1, repeat=args.repeats))
            per_block.append(t / n)
            cycle = float(plan.cycle_time)
            ref = (f" = {cycle / (1000.0 / LIMITS[0] + sum(DELAYS)):.4f}x L / v + T_d (every block at the {feed_cap:g} mm/s "
                   f"of a start from rest: {1000.0 / feed_cap + sum(DELAYS):.2f} s)") if name == "line" else ""
            print(f"{name:6s} N = {n:5d}: {t:6.3f} s, {t / n * 1e6:7.1f} us/block "
                  f"({per_block[-1] / per_block[0]:.2f}x the N = {args.sizes[0]} rate), rounds {plan.rounds}, "
                  f"cycle {cycle:.3f} s{ref}")
        exponent = np.log(per_block[-1] * args.sizes[-1] / (per_block[0] * args.sizes[0])) / np.log(args.sizes[-1] / args.sizes[0])
        print(f"{name:6s} scaling exponent {exponent:.2f} (target <= {TARGET_EXPONENT}): "
              f"{'PASS' if exponent <= TARGET_EXPONENT else 'MISS'}")


if __name__ == "__main__":
    main()
