"""Solve time of the B-spline feed-rate optimization (Sencer 2009 thesis ch 3, issue 8).

Usage::

    python benchmarks/bench_feedrate.py [--turns 1 2 4 8] [--window W] [--no-ocp] [--quick]

1. Thesis size. The public 300 mm blade-flank path (``research.paths.five_axis_library``; the
   thesis' impeller data are not public), Table 3.1 limits (A / C jerk read as rad/s^3), programmed
   feed 150 mm/s, n = 276 feed control points as in the thesis (§3.6), per-axis constraints, minimum
   time, check points refined until the dense check is within 0.2 %. Timed: the whole-path NLP and
   the windowed solution (windows of ``--window`` control points, look-ahead from the braking
   distance). Target (issue 8): at least 10x faster than the thesis' 126 s (MATLAB SQP, P4 2.3 GHz),
   i.e. < 12.6 s wall time, whole path. Baselines measured in the same run: the whole-path solve (for
   the windowed ratio) and the direct path-parametrized OCP (``reference_ocp``, 300 intervals) for
   solve time and cycle time; the constant 15 mm/s feed for cycle time.
2. Scaling. Helices of 1, 2, 4, 8 turns (126 mm per turn, one control point per mm): wall time whole
   and windowed against path length, with the log-log slope (1 = linear).

PASS/MISS as measured on this run, nothing tuned to pass. The machine is shared: absolute times
vary by tens of percent.
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import numpy as np

import research  # noqa: F401  (sets jax_enable_x64)
from research.optimal import (
    constant_feed,
    optimize_feedrate,
    reference_ocp,
    table31_limits,
)
from research.paths.five_axis_library import blade_flank_path, helix_path

THESIS_SECONDS, THESIS_N = 126.0, 276  # thesis §3.6
THESIS_T_CONST, THESIS_T_OPT = 20.18, 4.664  # s, on the (unavailable) impeller path
TARGET = THESIS_SECONDS / 10
FEED = 150.0


def timed(fn, *args, **kw):
    t0 = time.perf_counter()
    out = fn(*args, **kw)
    return out, time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--turns", type=float, nargs="+", default=[1, 2, 4, 8])
    ap.add_argument("--window", type=int, default=120)
    ap.add_argument("--no-ocp", action="store_true")
    ap.add_argument("--quick", action="store_true", help="turns 1 2 only, no OCP")
    args = ap.parse_args()
    if args.quick:
        args.turns, args.no_ocp = [1, 2], True
    lim = table31_limits()
    print(f"bench_feedrate: {platform.processor() or platform.machine()}, python {platform.python_version()}, "
          f"load {os.getloadavg()[0]:.1f}; F = {FEED} mm/s, Table 3.1 limits")
    optimize_feedrate(helix_path(0.25), lim, FEED, control_points=12)  # warm-up: JAX compile, CasADi load

    blade = blade_flank_path()
    whole, t_whole = timed(optimize_feedrate, blade, lim, FEED, control_points=THESIS_N)
    win, t_win = timed(optimize_feedrate, blade, lim, FEED, control_points=THESIS_N, window=args.window)
    const, _ = timed(constant_feed, blade, lim, 15.0)
    print(f"\n1. thesis size: blade-flank path {blade.length:.1f} mm, n = {THESIS_N} control points")
    head = f"{'method':>18} {'wall s':>8} {'ipopt s':>8} {'build s':>8} {'NLPs':>5} {'iter':>6} {'T cycle s':>10} {'worst':>7}"
    print(head)
    print("-" * len(head))
    rows = [("B-spline whole", whole, t_whole), (f"B-spline win {args.window}", win, t_win)]
    if not args.no_ocp:
        ocp, t_ocp = timed(reference_ocp, blade, lim, FEED, intervals=300, warm_start=whole)
        rows.append(("OCP N=300", ocp, t_ocp))
    for name, r, t in rows:
        print(f"{name:>18} {t:>8.2f} {r.solve_time:>8.2f} {r.build_time:>8.2f} {max(len(r.windows), 1):>5} "
              f"{r.iterations:>6} {r.cycle_time:>10.4f} {r.check.worst_ratio:>7.4f}")
    print(f"{'constant 15 mm/s':>18} {'':>8} {'':>8} {'':>8} {'':>5} {'':>6} {const.cycle_time:>10.4f} "
          f"{const.check.worst_ratio:>7.4f}")
    print(f"\ncycle time: optimized {whole.cycle_time:.3f} s vs constant 15 mm/s {const.cycle_time:.2f} s "
          f"(x{const.cycle_time / whole.cycle_time:.2f}); thesis on its impeller path: {THESIS_T_OPT} s vs "
          f"{THESIS_T_CONST} s (x{THESIS_T_CONST / THESIS_T_OPT:.2f})")
    if not args.no_ocp:
        print(f"B-spline / OCP cycle time = {whole.cycle_time / ocp.cycle_time:.4f}; "
              f"wall time OCP / B-spline = {t_ocp / t_whole:.2f}")
    print(f"windowed / whole: wall time {t_win / t_whole:.2f}, cycle time {win.cycle_time / whole.cycle_time:.5f}")
    print(f"target whole path < {TARGET:.1f} s (10x faster than the thesis' {THESIS_SECONDS:.0f} s): {t_whole:.2f} s, "
          f"x{THESIS_SECONDS / t_whole:.1f}  {'PASS' if t_whole < TARGET else 'MISS'}")
    print(f"target windowed   < {TARGET:.1f} s: {t_win:.2f} s, x{THESIS_SECONDS / t_win:.1f}  "
          f"{'PASS' if t_win < TARGET else 'MISS'}")
    ok = all(r.check.worst_ratio <= 1.002 for _, r, _ in rows)
    print(f"dense check of every solution within 0.2 %: {'PASS' if ok else 'MISS'}")

    print("\n2. scaling: helix, one control point per mm")
    head = f"{'turns':>6} {'L mm':>7} {'n':>5} {'whole s':>8} {'window s':>9} {'win/whole':>9} {'T whole':>8} {'T win':>8}"
    print(head)
    print("-" * len(head))
    walls = []
    for turns in args.turns:
        p = helix_path(turns)
        n = int(np.ceil(p.length)) + 3
        rw, tw = timed(optimize_feedrate, p, lim, FEED, control_points=n)
        rv, tv = timed(optimize_feedrate, p, lim, FEED, control_points=n, window=args.window)
        walls.append((p.length, tw, tv))
        print(f"{turns:>6g} {p.length:>7.1f} {n:>5} {tw:>8.2f} {tv:>9.2f} {tv / tw:>9.2f} {rw.cycle_time:>8.4f} {rv.cycle_time:>8.4f}")
    if len(walls) >= 2:
        (l0, w0, v0), (l1, w1, v1) = walls[0], walls[-1]
        print(f"log-log slope of wall time against length: whole {np.log(w1 / w0) / np.log(l1 / l0):.2f}, "
              f"windowed {np.log(v1 / v0) / np.log(l1 / l0):.2f}")


if __name__ == "__main__":
    main()
