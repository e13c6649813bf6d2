"""Benchmark: simulate 10^6 samples x 3 axes of the thesis Table 6.1 drive (eq 6.3 with Coulomb friction)
and compare with ``scipy.signal.lsim`` measured in the same run.

Run: ``python benchmarks/bench_drives.py [n_samples]``. Prints compile time, samples/s per axis after
compilation and the speed ratio against lsim (linear model, one axis at a time, as lsim allows).
Targets (issue 3): >= 1e7 samples/s per axis after compilation, >= 10x lsim.
"""

from __future__ import annotations

import sys
import time

import numpy as np
from scipy import signal

import research  # noqa: F401  (x64)
from research.drives import ClosedLoopModel, simulate, table_6_1_closed_loop
from research.trajectory import Trajectory


def make_reference(n: int, Ts: float = 1e-3, axes=("x", "y", "z")) -> Trajectory:
    """Three sinusoidal axes (1, 1.3, 1.7 Hz, 20 mm) with exact derivatives."""
    t = np.arange(n) * Ts
    w = 2 * np.pi * np.array([1.0, 1.3, 1.7])[None, :]
    s, c = np.sin(w * t[:, None]), np.cos(w * t[:, None])
    A = 20.0
    return Trajectory(t, A * s, A * w * c, -A * w**2 * s, -A * w**3 * c, np.float64(t[-1]), None, tuple(axes), Ts)


def main(n: int = 1_000_000) -> None:
    tr = make_reference(n)
    model = table_6_1_closed_loop()
    t0 = time.perf_counter()
    simulate(model, tr).position.block_until_ready()
    first = time.perf_counter() - t0
    runs = []
    for _ in range(3):
        t0 = time.perf_counter()
        simulate(model, tr).position.block_until_ready()
        runs.append(time.perf_counter() - t0)
    run = min(runs)
    compile_time = first - run
    per_axis = n / run

    linear = ClosedLoopModel(model.a1, model.a2, model.a3, model.b0, model.b1, model.b2, 0.0)
    r = linear.realization()
    sys_ = (np.asarray(r.A), np.asarray(r.B), np.asarray(r.C[:1]), np.zeros((1, 3)))
    u = np.stack([np.asarray(tr.q[:, 0]), np.asarray(tr.v[:, 0]), np.asarray(tr.a[:, 0])], axis=1)
    t_l = time.perf_counter()
    signal.lsim(sys_, u, np.asarray(tr.t), X0=[0.0, float(tr.q[0, 0]), float(tr.v[0, 0])], interp=False)
    lsim_axis = time.perf_counter() - t_l
    lsim_rate = n / lsim_axis
    print(f"samples per axis           : {n:,} x 3 axes, Ts = {tr.sample_period} s")
    print(f"first call (compile + run) : {first:.3f} s  -> compile ~ {compile_time:.3f} s")
    print(f"simulate (compiled, best/3): {run:.4f} s  -> {per_axis:.3e} samples/s per axis ({3 * per_axis:.3e} total)")
    print(f"scipy.signal.lsim, 1 axis  : {lsim_axis:.3f} s  -> {lsim_rate:.3e} samples/s (linear, no friction)")
    print(f"speed-up vs lsim (per axis): {per_axis / lsim_rate:.1f}x")
    print(f"targets: >= 1e7 samples/s per axis [{'met' if per_axis >= 1e7 else 'NOT met'}], "
          f">= 10x lsim [{'met' if per_axis / lsim_rate >= 10 else 'NOT met'}]")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 1_000_000)
