"""Contour-error and CEC benchmarks (issue 5).

Usage::

    python benchmarks/bench_contour.py [--quick] [--seed S]

1. CEC: optimistix ``Newton`` (model inversion, JAX Jacobian) against the plain mirror iteration
   (optimistix ``FixedPointIteration`` of Prévost eq 4) on Prévost Application 1 (B-spline at
   10 m/min, FIR 24/12 ms at Ts = 6 ms, Table 6.1 P-PI drive): iterations, primal simulations,
   Jacobians (each = N x A tangent simulations, batched by ``jax.vmap``) and wall time (compilation
   included, then warm) to reach max |e_T| <= 2 um, and to reach 0.1 um. Target: Newton needs
   >= 5x fewer simulations (primal simulations counted; Jacobians reported separately).
2. Exact contour error of 10^5 points against a 10^4-segment path (seeded random walk) with
   ``contour_error`` (KD-tree + local projection) against ``brute_force_contour_error`` (every point
   against every segment, chunked numpy); ratio = brute time / ours, and the max difference.
   ``--quick`` brute-forces a 10^4-point subset and scales the time linearly (stated in the output).

Each target line prints PASS or MISS as measured; nothing is tuned to pass.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from research.contour import (
    brute_force_contour_error,
    contour_error,
    mirror_compensation,
    prevost2012_application1,
)
from research.errors import ConvergenceError
from research.paths import Polyline


def bench_cec() -> None:
    case = prevost2012_application1()
    N, A = case.setpoint.n_samples, case.setpoint.n_axes
    print(f"CEC on Prévost Application 1: N = {N} samples x {A} axes, Ts = 6 ms, before max |e_T| = ", end="")
    rows = {}
    for tol in (2e-3, 0.1e-3):
        for method in ("fixed_point", "newton"):
            times = []
            for _ in range(2):  # first call includes compilation
                t0 = time.perf_counter()
                try:
                    r = mirror_compensation(case.problem, method=method, tolerance=tol, max_steps=30)
                except ConvergenceError as e:
                    r = e.result
                times.append(time.perf_counter() - t0)
            rows[tol, method] = (r, times)
        if tol == 2e-3:
            print(f"{rows[tol, 'newton'][0].before.max * 1e3:.2f} um")
    for (tol, method), (r, times) in rows.items():
        print(f"  to {tol * 1e3:4.1f} um  {method:11s}: {'converged' if r.converged else 'NOT converged'} "
              f"max|e_T| = {r.after.max * 1e3:.4f} um, iterations {r.steps}, primal simulations {r.simulations}, "
              f"Jacobians {r.jacobians} ({r.tangent_simulations} tangent sims), wall {times[0]:.2f} s first / {times[1]:.2f} s warm")
    for tol in (2e-3, 0.1e-3):
        fp, nt = rows[tol, "fixed_point"][0], rows[tol, "newton"][0]
        if not fp.converged:
            print(f"  target (>= 5x fewer simulations to {tol * 1e3:.1f} um): fixed point does not converge "
                  f"(stalls at {fp.after.max * 1e3:.3f} um); Newton: {nt.simulations} simulations")
            continue
        ratio = fp.simulations / nt.simulations
        wall = rows[tol, "fixed_point"][1][1] / rows[tol, "newton"][1][1]
        print(f"  target (>= 5x fewer simulations to {tol * 1e3:.1f} um): ratio {ratio:.2f} -> {'PASS' if ratio >= 5 else 'MISS'} "
              f"(wall-time ratio fixed point / Newton, warm: {wall:.2f})")


def bench_projection(quick: bool, seed: int) -> None:
    rng = np.random.default_rng(seed)
    steps = rng.uniform(0.2, 2.0, 10_000)[:, None] * np.column_stack([np.cos(h := np.cumsum(rng.normal(0, 0.3, 10_000))), np.sin(h)])
    path = Polyline(np.vstack([[0.0, 0.0], np.cumsum(steps, axis=0)]))
    idx = rng.integers(0, path.n_segments, 100_000)
    pts = path.points[idx] + rng.normal(0, 1.0, (100_000, 2))
    contour_error(path, pts[:10])  # build the index once (counted below separately)
    path2 = Polyline(path.points)
    t0 = time.perf_counter()
    ours = contour_error(path2, pts).distance
    t_ours = time.perf_counter() - t0
    n_brute = 10_000 if quick else pts.shape[0]
    t0 = time.perf_counter()
    brute = brute_force_contour_error(path, pts[:n_brute])
    t_brute = (time.perf_counter() - t0) * pts.shape[0] / n_brute
    diff = float(np.max(np.abs(brute - ours[:n_brute])))
    note = f" (brute force timed on {n_brute} points and scaled)" if n_brute < pts.shape[0] else ""
    print(f"Exact contour error, 1e5 points vs {path.n_segments} segments: ours {t_ours:.3f} s (index build included), "
          f"brute force {t_brute:.2f} s{note}; ratio {t_brute / t_ours:.0f}x; max |difference| = {diff:.2e} mm")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="brute-force only 1e4 of the 1e5 points")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    bench_projection(args.quick, args.seed)
    bench_cec()


if __name__ == "__main__":
    main()
