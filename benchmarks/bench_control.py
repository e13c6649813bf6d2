"""Benchmark: closed-loop 5-axis simulation with the thesis ch 5 contour controller (Table 5.3) against
the SISO sliding-mode loop (Table 5.2), both measured in the same run on the Fig 5.5 path (eq 4.36,
50 mm/s, control period 0.1 ms: 55 277 periods), and a ``jax.vmap`` over 1000 gain sets of the contour
controller (a Table 5.5 sensitivity sweep of the tangent / normal / binormal bandwidths) in one
compiled call.

Run: ``python benchmarks/bench_control.py [--repeats R] [--sets S] [--vmap-samples N]``. Prints compile
time (first call minus the best warm call) apart from the warm time (SISO and contour calls interleaved,
best of R each, so both see the same load), samples/s after compilation, the
per-sample cost ratio contour / SISO in process CPU time and in wall time (target: <= 3x, issue 17;
the verdict uses CPU time, which the waits for a core on a loaded machine do not inflate) and the vmap call's time per gain set.
The vmap sweep runs the first ``N`` periods (default 5000 = 0.5 s, through the acceleration phase) so
that 1000 sets fit in a short run; its rate is in (set x period)/s. Timings on a shared machine vary
with its load, which is printed alongside.
"""

from __future__ import annotations

import argparse
import os
import time

import jax
import jax.numpy as jnp
import numpy as np

import research  # noqa: F401  (x64)
from research.control import (
    ContourGains,
    TipGains,
    eq436_reference,
    identify_coulomb,
    simulate_closed_loop,
    table_5_2,
    table_5_3,
    thesis_plant,
)
from research.paths.kinematics5 import TableTiltingAC

TARGET_RATIO = 3.0  # contour controller cost per sample / SISO loop's


def timed(fn, repeats: int) -> tuple[float, float]:
    """(first call [s], best warm call [s]); each call waits for its result."""
    t0 = time.perf_counter()
    jax.block_until_ready(fn())
    first = time.perf_counter() - t0
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        jax.block_until_ready(fn())
        best = min(best, time.perf_counter() - t0)
    return first, best


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--sets", type=int, default=1000)
    ap.add_argument("--vmap-samples", type=int, default=5000)
    args = ap.parse_args()
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores; jax {jax.__version__} {jax.default_backend()}")
    ref, _ = eq436_reference(sample_period=1e-4)
    # friction identified on the 0.25 ms grid: same values to ~1 %, and it does not compile the 0.1 ms
    # SISO loop before it is timed (compile time is reported apart)
    plant = thesis_plant(identify_coulomb(T=2.5e-4))
    N = ref.n_samples
    rows = []
    # jitted wrapper: inside the trace the reference's per-call finiteness check (a host-side numpy pass,
    # the same for both loops) is skipped, so the timing is the closed loop itself
    loop = jax.jit(lambda p, r, g: simulate_closed_loop(p, r, g).q)
    calls = [(name, lambda g=gains: loop(plant, ref, g))
             for name, gains in (("SISO SMC (Table 5.2)", table_5_2()), ("contour controller (Table 5.3)", table_5_3()))]
    firsts = []
    for _, fn in calls:
        t0 = time.perf_counter()
        jax.block_until_ready(fn())
        firsts.append(time.perf_counter() - t0)
    best = [np.inf, np.inf]
    cpu = [np.inf, np.inf]
    for _ in range(args.repeats):  # interleaved, so both see the same machine load
        for i, (_, fn) in enumerate(calls):
            t0, c0 = time.perf_counter(), time.process_time()
            jax.block_until_ready(fn())
            best[i] = min(best[i], time.perf_counter() - t0)
            cpu[i] = min(cpu[i], time.process_time() - c0)
    for (name, _), first, warm, c in zip(calls, firsts, best, cpu):
        rows.append((name, first - warm, warm, N / warm))
        print(f"{name:32s} compile {first - warm:6.2f} s  warm {warm * 1e3:8.1f} ms  {N / warm:10.3g} samples/s  "
              f"({warm / N * 1e6:.2f} us/sample wall, {c / N * 1e6:.2f} us/sample CPU)")
    ratio_wall = rows[1][2] / rows[0][2]
    ratio = cpu[1] / cpu[0]
    # verdict on process CPU time: on a shared, loaded machine the wall time also counts the waits for a core
    print(f"cost per sample contour / SISO: {ratio:.2f}x CPU time, {ratio_wall:.2f}x wall time "
          f"(target <= {TARGET_RATIO:g}x, judged on CPU time): {'PASS' if ratio <= TARGET_RATIO else 'MISS'}")

    n = min(args.vmap_samples, N)
    short = jax.tree_util.tree_map(lambda x: x[:n] if hasattr(x, "shape") and x.ndim >= 1 else x, ref)
    rng = np.random.default_rng(17)
    base = table_5_3()
    wn = jnp.asarray(np.column_stack([rng.uniform(70, 100, args.sets), *(2 * [rng.uniform(200, 230, args.sets)])]))

    @jax.jit
    def sweep(wn):
        def one(w):
            g = ContourGains(TipGains(w, base.tip.Ks, base.tip.Gamma, base.tip.zeta), base.rotary, base.W)
            res = simulate_closed_loop(plant, short, g)
            tip = jax.vmap(lambda q: TableTiltingAC().forward(q)[0])(res.q)
            return jnp.max(jnp.linalg.norm(tip - short.P, axis=1)), res.diverged
        return jax.vmap(one)(wn)

    first, warm = timed(lambda: sweep(wn), max(1, args.repeats // 2))
    err, div = (np.asarray(x) for x in sweep(wn))
    print(f"vmap over {args.sets} gain sets x {n} periods: compile {first - warm:.2f} s, warm {warm:.2f} s "
          f"({warm / args.sets * 1e3:.2f} ms per set, {args.sets * n / warm:.3g} set-periods/s); "
          f"peak tip tracking error |P_ref - P| over the sets {err.min() * 1e3:.3f} .. {err.max() * 1e3:.3f} um, diverged {int(div.sum())}")
    single_rate = rows[1][3]
    print(f"vmap throughput / single contour run: {args.sets * n / warm / single_rate:.2f}x")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
