"""Benchmark: simulate 10^6 samples x 3 axes of the thesis Table 6.1 drive (eq 6.3 with Coulomb friction)
and compare with ``scipy.signal.lsim`` measured in the same run.

Run: ``python benchmarks/bench_drives.py [n_samples] [--repeats R]``. Prints compile time, samples/s per
axis after compilation (best of R warm calls of ``simulate``, which include moving the trajectory to JAX
and building the ``DriveResponse``), and the speed ratio against lsim: lsim simulates the same model
without friction (it is linear only) on the same input, one axis, which is its per-axis cost.
Targets (issue 3): >= 1e7 samples/s per axis after compilation, >= 10x lsim. Timings on a shared
machine vary with its load, which is printed alongside.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np
from scipy import signal

import research  # noqa: F401  (x64)
from research.drives import ClosedLoopModel, simulate, table_6_1_closed_loop
from research.trajectory import Trajectory

TARGET_RATE = 1e7  # samples/s per axis
TARGET_RATIO = 10.0  # x lsim


def make_reference(n: int, Ts: float = 1e-3, axes=("x", "y", "z")) -> Trajectory:
    """Three sinusoidal axes (1, 1.3, 1.7 Hz, 20 mm) with exact derivatives."""
    t = np.arange(n) * Ts
    w = 2 * np.pi * np.array([1.0, 1.3, 1.7])[None, :]
    s, c = np.sin(w * t[:, None]), np.cos(w * t[:, None])
    A = 20.0
    return Trajectory(t, A * s, A * w * c, -A * w**2 * s, -A * w**3 * c, np.float64(t[-1]), None, tuple(axes), Ts)


def time_simulate(model, tr: Trajectory, repeats: int) -> tuple[float, list[float]]:
    """(first call [s], warm calls [s]); each call waits for the position to be computed."""
    t0 = time.perf_counter()
    simulate(model, tr).position.block_until_ready()
    first = time.perf_counter() - t0
    runs = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        simulate(model, tr).position.block_until_ready()
        runs.append(time.perf_counter() - t0)
    return first, runs


def time_lsim(model: ClosedLoopModel, tr: Trajectory) -> float:
    """Seconds for ``scipy.signal.lsim`` (ZOH, the model without friction) on axis 0 of ``tr``."""
    linear = ClosedLoopModel(model.a1, model.a2, model.a3, model.b0, model.b1, model.b2, 0.0)
    r = linear.realization()
    sys_ = (np.asarray(r.A), np.asarray(r.B), np.asarray(r.C[:1]), np.zeros((1, 3)))
    u = np.stack([np.asarray(tr.q[:, 0]), np.asarray(tr.v[:, 0]), np.asarray(tr.a[:, 0])], axis=1)
    t0 = time.perf_counter()
    signal.lsim(sys_, u, np.asarray(tr.t), X0=[0.0, float(tr.q[0, 0]), float(tr.v[0, 0])], interp=False)
    return time.perf_counter() - t0


def main(n: int = 1_000_000, repeats: int = 5) -> bool:
    tr = make_reference(n)
    model = table_6_1_closed_loop()
    load_before = os.getloadavg()[0]
    first, runs = time_simulate(model, tr, repeats)
    lsim_axis = time_lsim(model, tr)
    load_after = os.getloadavg()[0]

    run = min(runs)
    rate = n / run
    lsim_rate = n / lsim_axis
    ratio = rate / lsim_rate
    ok_rate, ok_ratio = rate >= TARGET_RATE, ratio >= TARGET_RATIO
    print(f"drive simulation: {n:,} samples x {tr.n_axes} axes, Ts = {tr.sample_period} s, thesis Table 6.1 "
          f"(eq 6.3, Coulomb friction), cubic hold; 1-min load average {load_before:.1f} -> {load_after:.1f} "
          f"on {os.cpu_count()} CPUs")
    print(f"compile (first call - best warm call): {first - run:.3f} s   (first call {first:.3f} s)")
    print(f"warm calls [s]: {', '.join(f'{r:.4f}' for r in runs)}   (best {run:.4f}, median {np.median(runs):.4f})")
    print()
    print("| measurement                          | value               | target       | result |")
    print("|--------------------------------------|---------------------|--------------|--------|")
    print(f"| simulate, samples/s per axis         | {rate:10.3e}          | >= {TARGET_RATE:.0e}    | "
          f"{'PASS' if ok_rate else 'MISS'}   |")
    print(f"| scipy.signal.lsim, samples/s (1 axis)| {lsim_rate:10.3e}          |              |        |")
    print(f"| speed-up vs lsim (per axis)          | {ratio:10.1f}x         | >= {TARGET_RATIO:.0f}x       | "
          f"{'PASS' if ok_ratio else 'MISS'}   |")
    return ok_rate and ok_ratio


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("n", nargs="?", type=int, default=1_000_000, help="samples per axis")
    parser.add_argument("--repeats", type=int, default=5, help="warm calls to time (best is reported)")
    args = parser.parse_args()
    main(args.n, args.repeats)
