"""Cost of sampling an exact piecewise-polynomial trajectory (q, v, a, j) on the Ts grid (issue 19 item 5).

Usage (from the repository root, so that this checkout's ``research`` is measured)::

    PYTHONPATH=. python benchmarks/bench_sampling.py [--repeats R] [--quick]

Two workloads, each sampled for q, v, a, j on 3 axes:

* ``fir``: the exact position profile of ``plan_fir`` on a seeded CAM-like path of 2000 short G1
  segments (random-walk headings, 0.2-2 mm; as in bench_fir.py), feed 200 mm/s, Sencer 2015 delays
  T1 = 148 ms, T2 = 89 ms, tolerance 0.05 mm, at Ts = 20 us (delays are whole multiples of Ts, so
  the running-sum baseline is exact on the same schedule).
* ``random``: a seeded random cubic piecewise polynomial, 2x10^4 pieces, 2x10^6 samples.

Timed in the same run, best of ``R`` (compile/first-call time reported apart), per sample:

1. new: ``PiecewisePolynomial.sample`` -- one compiled pass for all orders (research/_grid_sample.py).
2. old: the per-order path it replaced (copied below from commit ef31ba8: one compiled JAX call per
   order for more than 5x10^4 samples, one NumPy search-and-Horner per order below).
3. running sum: the discrete FIR generator -- velocity pulse train as cell averages (as in
   ``fir_by_convolution``), each filter as an integrator-comb (cumulative sum minus its copy ``m``
   samples back, divided by ``m``), positions by cumulative sum, a and j by differences. Only the
   filtering and the derivatives are timed, not the pulse train's construction.
4. floor: writing the 12 doubles of a sample -- ``np.empty((4, N, 3))`` filled by one ``fill``.

Also ``Trajectory.from_piecewise`` against the old construction (old sampler + the sample checks
of ``Trajectory.__check_init__``). Target (issue 19): new sampler <= 3x the floor -> PASS/MISS.
"""

from __future__ import annotations

import argparse
import math
import os
import time
from functools import partial

import jax
import jax.numpy as jnp
import numpy as np

import research  # noqa: F401  (sets jax_enable_x64)
from research.interpolators.fir import plan_fir
from research.paths import Polyline
from research.piecewise import GRID_SNAP, PiecewisePolynomial, bucket_size
from research.trajectory import Trajectory

from bench_fir import cam_path  # noqa: E402  (the seeded CAM-like path of bench_fir.py; benchmarks/ is on sys.path)

TARGET = 3.0  # issue 19: sampling <= 3x the memory-write floor
DELAYS = (0.148, 0.089)  # Sencer 2015 section 4
FEED, TOLERANCE, TS_FIR = 200.0, 0.05, 2e-5


# -- the per-order sampler as of commit ef31ba8 (the baseline) --------------------------------------
@partial(jax.jit, static_argnums=2)
def _old_pieces(breaks, sample_period, n_samples):
    K = breaks.shape[0] - 1
    first = jnp.clip(jnp.ceil((breaks[1:K] - breaks[0]) / sample_period - GRID_SNAP), 0, n_samples).astype(jnp.int32)
    piece = jnp.cumsum(jnp.zeros(n_samples + 1, jnp.int32).at[first].add(1))[:n_samples]
    t = breaks[0] + jnp.arange(n_samples, dtype=jnp.float64) * sample_period
    tau = jnp.clip(t, breaks[0], breaks[-1]) - breaks[piece]
    return piece, tau, t <= breaks[-1]


@partial(jax.jit, static_argnums=4)
def _old_order(coeffs, piece, tau, moving, nu):
    d = coeffs.shape[1] - 1
    if nu > d:
        return jnp.zeros((piece.shape[0], coeffs.shape[2]))
    value = coeffs[piece, d, :] * math.perm(d, nu)
    for m in range(d - 1, nu - 1, -1):
        value = value * tau[:, None] + coeffs[piece, m, :] * math.perm(m, nu)
    return value if nu == 0 else jnp.where(moving[:, None], value, 0.0)


def old_sample(pp: PiecewisePolynomial, Ts: float, n: int, orders: int = 4):
    if n <= 50_000:
        t = np.asarray(pp.breaks[0]) + np.arange(n) * Ts
        return tuple(pp.evaluate_numpy(t, nu, snap=GRID_SNAP * Ts) for nu in range(orders))
    piece, tau, moving = _old_pieces(pp.breaks, jnp.asarray(Ts, jnp.float64), bucket_size(n, 256))
    return tuple(np.asarray(_old_order(pp.coeffs, piece, tau, moving, nu))[:n] for nu in range(orders))


# -- baselines --------------------------------------------------------------------------------------
def floor_write(n: int) -> np.ndarray:
    out = np.empty((4, n, 3))
    out.fill(0.5)
    return out


def running_sum(velocity: np.ndarray, taps, Ts: float, q0: np.ndarray):
    """Integrator-comb moving averages of the cell-average velocity, then q, v, a, j on the grid."""
    for m in taps:
        c = np.cumsum(np.vstack([velocity, np.zeros((m, velocity.shape[1]))]), axis=0)
        c[m:] -= c[:-m].copy()
        velocity = c / m
    q = q0 + np.cumsum(velocity, axis=0) * Ts
    a = np.diff(velocity, axis=0, prepend=0.0) / Ts
    j = np.diff(a, axis=0, prepend=0.0) / Ts
    return q, velocity, a, j


def pulse_train(plan, path: Polyline, Ts: float) -> np.ndarray:
    """Unfiltered velocity as exact cell averages over [i Ts, (i+1) Ts) (as fir_by_convolution)."""
    starts = np.asarray(plan.start_times)
    ends = starts + np.asarray(plan.pulse_times)
    knots = np.stack([starts, ends], axis=1).reshape(-1)
    knot_pos = np.repeat(path.points, 2, axis=0)[1:-1]
    grid = np.arange(int(np.ceil(ends[-1] / Ts)) + 2) * Ts
    unfiltered = np.column_stack([np.interp(grid, knots, knot_pos[:, k]) for k in range(path.dim)])
    return np.diff(unfiltered, axis=0) / Ts


def best_of(repeats: int, fn, *args):
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn(*args)
        times.append(time.perf_counter() - t0)
    return min(times)


def first_call(fn, *args):
    t0 = time.perf_counter()
    out = fn(*args)
    return out, time.perf_counter() - t0


def bench(name: str, pp: PiecewisePolynomial, Ts: float, repeats: int, filtering=None) -> bool:
    breaks = np.asarray(pp.breaks)
    n = int(np.ceil((breaks[-1] - breaks[0]) / Ts - 1e-9)) + 1
    K = pp.coeffs.shape[0]
    print(f"\n[{name}] K = {K:,} pieces, degree {pp.degree}, {pp.n_channels} axes, N = {n:,} samples, Ts = {Ts:g} s")
    new, c_new = first_call(pp.sample, Ts, n, 4)
    old, c_old = first_call(old_sample, pp, Ts, n, 4)
    err = max(float(np.max(np.abs(a - b)) / max(1.0, np.max(np.abs(b)))) for a, b in zip(new, old))
    t_new = best_of(repeats, pp.sample, Ts, n, 4)
    t_old = best_of(repeats, old_sample, pp, Ts, n, 4)
    t_floor = best_of(repeats, floor_write, n)
    ns = lambda t: t / n * 1e9  # noqa: E731
    rows = [("new: one pass, all orders", t_new), ("old: per-order path (ef31ba8)", t_old)]
    if filtering is not None:
        rows.append(("running-sum (integrator-comb) filtering", best_of(repeats, filtering)))
    rows.append(("memory-write floor (12 doubles/sample)", t_floor))
    for label, t in rows:
        print(f"  {label:<44s} {ns(t):8.1f} ns/sample   {t / t_floor:6.2f}x floor   {t / t_new:6.2f}x new")
    print(f"  first call (compile or cache load): new {c_new * 1e3:.0f} ms, old {c_old * 1e3:.0f} ms")
    print(f"  max |new - old| / max(1, |old|) over q v a j: {err:.1e} (test: <= 1e-12)")

    # whole Trajectory construction: old sampler + per-sample checks vs from_piecewise
    axes = ("x", "y", "z")[: pp.n_channels]

    def old_trajectory():
        q, v, a, j = old_sample(pp, Ts, n, 4)
        shifted = PiecewisePolynomial(pp.breaks - pp.start, pp.coeffs)
        return Trajectory(np.arange(n) * Ts, q, v, a, j, pp.end - pp.start, shifted, axes, Ts)

    t_tr_new = best_of(repeats, Trajectory.from_piecewise, pp, Ts, axes)
    t_tr_old = best_of(repeats, old_trajectory)
    print(f"  Trajectory: from_piecewise {ns(t_tr_new):.1f} ns/sample ({t_tr_new / t_floor:.2f}x floor), "
          f"old sampler + sample checks {ns(t_tr_old):.1f} ns/sample ({t_tr_old / t_tr_new:.2f}x slower)")
    ok = t_new <= TARGET * t_floor
    print(f"  target new <= {TARGET:g}x floor: {t_new / t_floor:.2f}x -> {'PASS' if ok else 'MISS'}")
    return ok


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--quick", action="store_true", help="500 segments, 5x10^5 random samples, 3 repeats")
    args = ap.parse_args(argv)
    repeats = 3 if args.quick else args.repeats
    print(f"bench_sampling: load average {open('/proc/loadavg').read().split()[:3]} on {os.cpu_count()} cores")

    path = cam_path(500 if args.quick else 2000, seed=0)
    t0 = time.perf_counter()
    plan = plan_fir(path, FEED, DELAYS, TOLERANCE)
    print(f"plan_fir ({path.n_segments} segments, incl. compile): {time.perf_counter() - t0:.1f} s")
    taps = [int(round(T / TS_FIR)) for T in DELAYS]
    assert np.allclose(np.array(taps) * TS_FIR, DELAYS, rtol=0, atol=1e-12)
    velocity = pulse_train(plan, path, TS_FIR)
    ok = bench("fir", plan.position, TS_FIR, repeats, lambda: running_sum(velocity, taps, TS_FIR, path.points[0]))

    rng = np.random.default_rng(1)
    n_rand, K = (500_000, 5_000) if args.quick else (2_000_000, 20_000)
    Ts = 1e-3
    breaks = np.concatenate([[0.0], np.cumsum(rng.uniform(0.0, 2.0 * (n_rand - 1) * Ts / K, K))])
    breaks *= (n_rand - 1) * Ts / breaks[-1]
    pp = PiecewisePolynomial(jnp.asarray(breaks), jnp.asarray(rng.normal(size=(K, 4, 3))))
    ok &= bench("random", pp, Ts, repeats)
    print(f"\nload average after: {open('/proc/loadavg').read().split()[:3]}")
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
