"""Solve time of the time-optimal reference OCP against the number of corners (issue 6, Benchmark).

Usage::

    python benchmarks/bench_optimal.py [--corners 10 30 100] [--seed S] [--window W] [--overlap O]
                                       [--intervals N] [--whole-max C]

Scenario: a seeded random 2-D polyline with C corners (C + 1 segments of 8-20 mm, each turning by
20-120 deg to a random side, like a pocketing path), the nominal FIR envelope of Sencer 2015 §4 as
per-axis limits (F = 250 mm/s, T1 = 148 ms, T2 = 89 ms: v = F, a = F/T1, j = F/(T1 T2)), feed limit
|v| <= F and tolerance eps = 0.5 mm. ``time_optimal`` solves it in receding windows (default 8
segments with an overlap of 3, thesis §3.5) with N = 16 jerk intervals per segment, warm-started
from the exact-stop S-curve.

Reported per path: wall time of the whole call (warm start, NLP construction, IPOPT, sampling),
IPOPT time alone, windows and iterations, time per corner and its ratio to the 10-corner case, and
the log-log slope of wall time against corners (1 = linear). The whole-path NLP (one window) is also
timed up to ``--whole-max`` corners (default 30) to show what windowing buys; both must give about
the same cycle time. Each solution's cycle time is printed against FIR overlap and the S-curve
exact stop on the same path, with the dense between-grid check (worst tube / limit ratio).

Targets (issue 6): < 30 s for 100 corners with windowing; cost about linear in path length, judged
here as a log-log slope <= 1.2 between the smallest and the largest path. PASS/MISS as measured on
this run, nothing tuned to pass. The machine is shared: absolute times vary by tens of percent.
"""

from __future__ import annotations

import argparse
import platform
import time

import numpy as np

import research  # noqa: F401  (sets jax_enable_x64)
from research.interpolators import fir_interpolate, scurve_interpolate
from research.limits import AxisLimits
from research.optimal import time_optimal
from research.paths import Polyline

F, DELAYS, EPS = 250.0, (0.148, 0.089), 0.5  # Sencer 2015 §4 / Fig 6
TARGET_100 = 30.0  # s, issue 6
TARGET_SLOPE = 1.2


def random_path(corners: int, seed: int) -> Polyline:
    """Seeded 2-D polyline with ``corners`` interior vertices: segments of 8-20 mm, turns of
    20-120 deg to a random side [mm]."""
    rng = np.random.default_rng(seed)
    lengths = rng.uniform(8.0, 20.0, corners + 1)
    turns = rng.uniform(np.radians(20.0), np.radians(120.0), corners) * rng.choice([-1.0, 1.0], corners)
    heading = np.concatenate([[0.0], np.cumsum(turns)])
    steps = lengths[:, None] * np.column_stack([np.cos(heading), np.sin(heading)])
    return Polyline(np.vstack([[0.0, 0.0], np.cumsum(steps, axis=0)]))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--corners", type=int, nargs="+", default=[10, 30, 100])
    ap.add_argument("--seed", type=int, default=6)
    ap.add_argument("--window", type=int, default=8)
    ap.add_argument("--overlap", type=int, default=3)
    ap.add_argument("--intervals", type=int, default=16)
    ap.add_argument("--whole-max", type=int, default=30, help="largest path also solved as one NLP")
    args = ap.parse_args()
    limits = AxisLimits.fir_envelope(2, F, DELAYS)
    print(f"bench_optimal: {platform.processor() or platform.machine()}, python {platform.python_version()}; "
          f"window {args.window}, overlap {args.overlap}, N = {args.intervals}, eps = {EPS} mm, F = {F} mm/s")

    # warm-up: import / first-call costs stay out of the table
    time_optimal(random_path(2, args.seed), limits, EPS, feed=F, intervals_per_segment=args.intervals)

    rows = []
    header = (f"{'corners':>7} {'mode':>8} {'wall s':>8} {'ipopt s':>8} {'windows':>7} {'iter':>6} "
              f"{'s/corner':>9} {'x 10-c':>7} {'T_ocp s':>9} {'T_fir s':>8} {'T_scurve':>8} {'worst':>7}")
    print(header)
    print("-" * len(header))
    for corners in args.corners:
        path = random_path(corners, args.seed)
        fir = float(fir_interpolate(path, F, DELAYS, EPS).duration)
        scurve = float(scurve_interpolate(path, F, limits).duration)
        modes = [("window", args.window)] + ([("whole", None)] if corners <= args.whole_max else [])
        for mode, window in modes:
            t0 = time.perf_counter()
            res = time_optimal(path, limits, EPS, feed=F, intervals_per_segment=args.intervals,
                               window=window, overlap=args.overlap)
            wall = time.perf_counter() - t0
            rows.append((corners, mode, wall, res))
            base = next((w / c for c, m, w, _ in rows if m == mode and c == args.corners[0]), wall / corners)
            print(f"{corners:>7} {mode:>8} {wall:>8.2f} {res.solve_time:>8.2f} {len(res.windows):>7} {res.iterations:>6} "
                  f"{wall / corners:>9.3f} {wall / corners / base:>7.2f} {res.cycle_time:>9.4f} {fir:>8.4f} "
                  f"{scurve:>8.4f} {res.verification.worst_ratio:>7.4f}")

    win = [(c, w, r) for c, m, w, r in rows if m == "window"]
    print()
    for c, m, w, r in rows:
        if m == "whole":
            other = next(x for x in win if x[0] == c)
            print(f"{c} corners: windowed / whole-path cycle time = {other[2].cycle_time / r.cycle_time:.6f}, "
                  f"wall time ratio whole / windowed = {w / other[1]:.2f}")
    ok_quality = all(r.verification.worst_ratio <= 1.01 for *_, r in rows)
    print(f"between-grid check (tube and limits within 1 %): {'PASS' if ok_quality else 'MISS'}")
    largest = max(win, key=lambda x: x[0])
    if largest[0] >= 100:
        t100 = largest[1]
        print(f"target {largest[0]} corners < {TARGET_100:.0f} s (windowed): {t100:.2f} s  "
              f"{'PASS' if t100 < TARGET_100 else 'MISS'}")
    if len(win) >= 2:
        (c0, w0, _), (c1, w1, _) = min(win, key=lambda x: x[0]), largest
        slope = np.log(w1 / w0) / np.log(c1 / c0)
        print(f"cost vs corners: log-log slope {slope:.2f} between {c0} and {c1} corners "
              f"(time per corner x{(w1 / c1) / (w0 / c0):.2f}); target <= {TARGET_SLOPE}: "
              f"{'PASS' if slope <= TARGET_SLOPE else 'MISS'}")


if __name__ == "__main__":
    main()
