"""Evaluation throughput of the sigmoid interpolator (DiMarco 2015) against the S-curve baseline.

Both interpolators are planned once for the same MTP move (10 mm at 20 mm/s, 0.2 mm x 20 Hz
oscillation, a_max = 5000 mm/s^2, j_max = 2e6 mm/s^3; research/figures/dimarco2015_mtp.py), then
evaluated (position, velocity, acceleration, jerk) on a uniform grid of N samples:

* sigmoid: ``SigmoidMotion.derivatives`` (closed-form exponentials and sines, NumPy);
* baseline: the linear interpolator's exact piecewise-cubic profile, ``PiecewisePolynomial.sample``
  (one search-free pass per derivative, JAX).

Printed: samples/s of each and the ratio sigmoid / baseline measured in the same run (issue
"Sigmoid and exponential interpolators", benchmark section; no target is set there). Planning time
(alpha search) is printed apart. Usage: ``python benchmarks/bench_sigmoid.py [--samples N]``.
"""

from __future__ import annotations

import argparse
import time

import jax
import numpy as np

import research  # noqa: F401  (x64)
from research.figures.dimarco2015_mtp import LIMITS, MOVE
from research.interpolators import mtp_linear_baseline, mtp_motion


def best_of(repeats, fn):
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        jax.block_until_ready(fn())
        times.append(time.perf_counter() - t0)
    return min(times)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--samples", type=int, default=1_000_000)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args(argv)

    t0 = time.perf_counter()
    motion = mtp_motion(**MOVE, **LIMITS)
    t_plan_sig = time.perf_counter() - t0
    t0 = time.perf_counter()
    baseline, _ = mtp_linear_baseline(**MOVE, **LIMITS)
    t_plan_lin = time.perf_counter() - t0
    profile = baseline.exact

    n = args.samples
    t_sig_grid = np.linspace(0.0, motion.duration, n)
    period_lin = float(profile.end - profile.start) / (n - 1)
    profile.sample(period_lin, n)  # compile
    t_sig = best_of(args.repeats, lambda: motion.derivatives(t_sig_grid))
    t_lin = best_of(args.repeats, lambda: profile.sample(period_lin, n))

    print(f"planning: sigmoid (alpha search) {t_plan_sig:.2f} s, linear interpolator {t_plan_lin:.2f} s "
          f"({len(profile.breaks) - 1} polynomial pieces)")
    print(f"{'evaluation of q, v, a, j':<40} {'time [ms]':>10} {'samples/s':>14}")
    print(f"{'sigmoid (closed form, NumPy)':<40} {t_sig * 1e3:10.1f} {n / t_sig:14,.0f}")
    print(f"{'S-curve baseline (piecewise cubic)':<40} {t_lin * 1e3:10.1f} {n / t_lin:14,.0f}")
    print(f"ratio sigmoid / baseline throughput: {t_lin / t_sig:.2f}x (measured in this run)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
