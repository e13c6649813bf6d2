"""Cycle times of ``plan_fir`` on a fixed set of programs, to check that a planner change keeps the plans.

Usage::

    PYTHONPATH=<tree> python benchmarks/fir_plan_compare.py save OUT.npz [--seeds 20]
    python benchmarks/fir_plan_compare.py diff A.npz B.npz [--rtol 1e-9]

``save`` plans bench_cam's quick CAM file (its scenario), bench_fir's 10^3 and 10^4 paths (its
scenario) and ``--seeds`` seeded random programs of ``tests/interpolators/test_fir_monotone``
(lines, and lines with arcs) at their ``eps`` and ``1.5 eps``, and stores the cycle times and the
rounds used. ``diff`` prints the largest relative cycle-time difference between two such files
and exits 1 if it is above ``--rtol``.
"""

from __future__ import annotations

import argparse
import sys

import numpy as np


def save(out: str, seeds: int) -> None:
    sys.path.insert(0, "benchmarks")
    sys.path.insert(0, "tests/interpolators")
    import bench_cam
    import bench_fir
    from test_fir_monotone import DELAYS, _program

    import research
    from research.interpolators import plan_fir

    print("research from", research.__file__)
    names, cycles, rounds = [], [], []

    def record(name, plan):
        names.append(name)
        cycles.append(float(plan.cycle_time))
        rounds.append(int(plan.rounds))

    path, _ = bench_cam.cam_program(0, bench_cam.LEVELS_QUICK)
    path = bench_cam.parse_gcode(bench_cam.to_gcode(path, bench_cam.FEED * 60.0), start=tuple(path.points[0])).polyline
    record("quick", plan_fir(path, bench_cam.FEED, bench_cam.DELAYS, bench_cam.EPS))
    for n in (1000, 10000):
        record(f"bench_fir {n}", plan_fir(bench_fir.cam_path(n, 0), bench_fir.FEED, bench_fir.DELAYS, bench_fir.TOLERANCE))
    for seed in range(seeds):
        for arcs in (False, True):
            tp, eps, feed = _program(seed, arcs)
            for f in (1.0, 1.5):
                record(f"seed {seed} arcs {arcs} {f} eps", plan_fir(tp, feed, DELAYS, f * eps))
    np.savez(out, names=np.array(names), cycles=np.array(cycles), rounds=np.array(rounds))
    print(f"{len(names)} plans, sum of cycle times {sum(cycles):.9g} s, rounds {sum(rounds)}")


def diff(a: str, b: str, rtol: float) -> int:
    A, B = np.load(a), np.load(b)
    if not np.array_equal(A["names"], B["names"]):
        raise ValueError("the two files plan different programs")
    rel = np.abs(B["cycles"] / A["cycles"] - 1.0)
    i = int(np.argmax(rel))
    print(f"{rel.size} plans: largest relative cycle-time difference {rel[i]:.3g} ({A['names'][i]}); "
          f"{int(np.sum(rel > rtol))} above {rtol:g}; rounds {int(A['rounds'].sum())} -> {int(B['rounds'].sum())}")
    return int(rel[i] > rtol)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    s = sub.add_parser("save")
    s.add_argument("out")
    s.add_argument("--seeds", type=int, default=20)
    d = sub.add_parser("diff")
    d.add_argument("a")
    d.add_argument("b")
    d.add_argument("--rtol", type=float, default=1e-9)
    args = ap.parse_args(argv)
    if args.cmd == "save":
        save(args.out, args.seeds)
        return 0
    return diff(args.a, args.b, args.rtol)


if __name__ == "__main__":
    sys.exit(main())
