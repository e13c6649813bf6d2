"""Limit-holding ``plan_fir`` on random programs under limits below the FIR envelope: validity,
and cycle times to compare two trees.

Usage::

    PYTHONPATH=<tree> python benchmarks/fir_limits_stress.py save OUT.npz [--programs 150]
    python benchmarks/fir_limits_stress.py diff A.npz B.npz

``save`` plans ``--programs`` seeded programs, by turns the lines and the lines with arcs of
``tests/interpolators/test_fir_monotone`` (its seeds, eps and feeds) and circles of 30-200 chords
of 0.5-4 deg (R 5-60 mm, eps 5-100 um, F 50-300 mm/s), each under ``AxisLimits.fir_envelope``
with its acceleration and jerk scaled by ``exp(U(log 0.05, 0))`` (seeded), and stores each plan's
cycle time, worst ``metrics.limit_ratios`` on its 1 ms trajectory, largest corner error over eps
and planning process time. It prints the worst ratios (limits are held where the first is <= 1 +
1e-6, the tolerance where the second is <= 1 + 1e-6). ``diff`` prints how many plans are faster
or slower in B than in A (1e-9 relative) and the planning time of each (in all, the median per-plan
ratio and the plan slowest in A); the planner's kernels are compiled by one untimed plan first.
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np


def _circle(rng):
    n, radius, step = int(rng.integers(30, 200)), rng.uniform(5.0, 60.0), rng.uniform(0.5, 4.0)
    from research.paths import Polyline
    th = np.radians(np.arange(n) * step) + rng.uniform(0.0, 2.0 * np.pi)
    return Polyline(np.column_stack([radius * np.cos(th), radius * np.sin(th)])), float(rng.uniform(0.005, 0.1)), \
        float(rng.uniform(50.0, 300.0))


def save(out: str, programs: int) -> None:
    sys.path.insert(0, "tests/interpolators")
    from test_fir_monotone import DELAYS, _program

    import research
    from research.interpolators import plan_fir
    from research.limits import AxisLimits
    from research.metrics import limit_ratios

    print("research from", research.__file__, flush=True)
    # the first plan compiles the planner's kernels: planned once untimed, so every time is warm
    path, eps, feed = _program(0, False)
    env = AxisLimits.fir_envelope(path.dim, feed, DELAYS)
    plan_fir(path, feed, DELAYS, eps, limits=AxisLimits(env.velocity, 0.5 * env.acceleration, 0.5 * env.jerk))
    rows = []
    for seed in range(programs):
        rng = np.random.default_rng(1000 + seed)
        if seed % 3 < 2:
            path, eps, feed = _program(seed, bool(seed % 3))
        else:
            path, eps, feed = _circle(rng)
        dim = path.dim
        env = AxisLimits.fir_envelope(dim, feed, DELAYS)
        s = float(np.exp(rng.uniform(np.log(0.05), 0.0)))
        limits = AxisLimits(env.velocity, s * env.acceleration, s * env.jerk)
        t = time.process_time()
        plan = plan_fir(path, feed, DELAYS, eps, limits=limits)
        dt = time.process_time() - t
        worst = max(float(np.max(v)) for v in limit_ratios(plan.trajectory(1e-3), limits).values())
        rows.append((float(plan.cycle_time), worst, float(np.max(np.asarray(plan.corner_errors), initial=0.0)) / eps, dt))
        print(f"\r{seed + 1}/{programs}", end="", flush=True)
    a = np.array(rows)
    np.savez(out, cycle=a[:, 0], limit=a[:, 1], corner=a[:, 2], plan_time=a[:, 3])
    print(f"\nworst limit ratio {a[:, 1].max():.6f}, worst corner error / eps {a[:, 2].max():.6f}, "
          f"planning {a[:, 3].sum():.2f} s in all")


def diff(a: str, b: str) -> None:
    A, B = np.load(a), np.load(b)
    r = B["cycle"] / A["cycle"]
    print(f"{r.size} plans: {int(np.sum(r < 1 - 1e-9))} faster in B (down to {r.min():.4f}x), "
          f"{int(np.sum(r > 1 + 1e-9))} slower (up to {r.max():.4f}x); planning {A['plan_time'].sum():.2f} s (A) "
          f"-> {B['plan_time'].sum():.2f} s (B), per plan B / A median {np.median(B['plan_time'] / A['plan_time']):.3f} "
          f"(slowest in A {A['plan_time'].max():.2f} -> {B['plan_time'][np.argmax(A['plan_time'])]:.2f} s); "
          f"worst limit ratio {A['limit'].max():.6f} -> {B['limit'].max():.6f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    s = sub.add_parser("save")
    s.add_argument("out")
    s.add_argument("--programs", type=int, default=150)
    d = sub.add_parser("diff")
    d.add_argument("a")
    d.add_argument("b")
    args = ap.parse_args()
    save(args.out, args.programs) if args.cmd == "save" else diff(args.a, args.b)


if __name__ == "__main__":
    main()
