"""A 10^4-point (T1, T2, eps) sweep of the diamond on the jax.vmap fast path (issue 9, Benchmarks).

Usage::

    python benchmarks/bench_sweep.py [--t1 25] [--t2 20] [--eps 20] [--baseline 40]

Scenario: Sencer 2015 §4 diamond, F = 250 mm/s, beams at 11.4 Hz (X) and 6.8 Hz (Y) with 2 %
damping; a grid of T1 in [120, 170] ms x T2 in [60, 110] ms x eps in [50, 1000] um (default
25 x 20 x 20 = 10^4 points; every block stays longer than the filter, so all points are on the
fast path). Measured, in this run:

* the whole ``python -m research sweep`` pipeline (expansion and validation of every point, the
  compiled vmap calls with autodiff sensitivities, store entries, table and npz) on an empty store;
* the same sweep again (everything from the store: the re-run cost);
* the compiled vmap call alone (compile, then a warm call of all points);
* baseline: the exact planner ``plan_fir`` (eq 13/14 + verified corners) plus the sampled
  residual vibration, per point, on ``--baseline`` random grid points, extrapolated to the grid.

Target (issue 9): the 10^4-point sweep in < 60 s on 2 cores. PASS/MISS as measured; the machine is
shared, so absolute times vary by tens of percent.
"""

from __future__ import annotations

import argparse
import os
import platform
import tempfile
import time
from pathlib import Path

import jax.numpy as jnp
import numpy as np

import research  # noqa: F401  (x64)
from research.drives import residual_vibration_sampled
from research.experiments.sweep import run_sweep
from research.experiments.sweep_vmap import _batch
from research.interpolators import plan_fir
from research.paths import named_path

TARGET_S = 60.0
CONFIG = """
name = "bench_sweep"
reproduces = "benchmark: 10^4-point (T1, T2, eps) sweep of the Sencer 2015 diamond"
[path]
name = "diamond"
[interpolator]
feed_mm_per_s = 250.0
delays_ms = [148.0, 89.0]
tolerance_um = 500.0
[drive]
modes = [{{axis = "x", frequency_hz = 11.4, damping = 0.02}}, {{axis = "y", frequency_hz = 6.8, damping = 0.02}}]
[output]
figure = false
[sweep]
engine = "vmap"
chunk = {chunk}
[sweep.parameters]
"interpolator.delays_ms[0]" = {{start = 120.0, stop = 170.0, num = {t1}}}
"interpolator.delays_ms[1]" = {{start = 60.0, stop = 110.0, num = {t2}}}
"interpolator.tolerance_um" = {{start = 50.0, stop = 1000.0, num = {eps}}}
"""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--t1", type=int, default=25)
    ap.add_argument("--t2", type=int, default=20)
    ap.add_argument("--eps", type=int, default=20)
    ap.add_argument("--chunk", type=int, default=10_000, help="points per compiled call")
    ap.add_argument("--baseline", type=int, default=40, help="points timed with plan_fir")
    args = ap.parse_args()
    n = args.t1 * args.t2 * args.eps
    print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, load {os.getloadavg()[0]:.1f}")
    with tempfile.TemporaryDirectory() as tmp:
        cfg = Path(tmp) / "bench_sweep.toml"
        cfg.write_text(CONFIG.format(t1=args.t1, t2=args.t2, eps=args.eps, chunk=min(args.chunk, n)))
        kw = dict(cache_dir=Path(tmp) / "cache", log=lambda s: None, show_progress=False)
        t0 = time.perf_counter()
        res = run_sweep(cfg, **kw)
        t_sweep = time.perf_counter() - t0
        t0 = time.perf_counter()
        again = run_sweep(cfg, **kw)
        t_again = time.perf_counter() - t0
    assert res.stats["ok"] == n and res.stats["fast"] == n, res.stats
    assert again.stats["computed"] == 0

    # the compiled call alone
    T1, T2, E = (np.array([r[k] for r in res.rows]) for k in
                 ("interpolator.delays_ms[0]", "interpolator.delays_ms[1]", "interpolator.tolerance_um"))
    x = dict(feed=jnp.full(n, 250.0), delays=jnp.stack([T1, T2], 1) * 1e-3, tolerance=jnp.asarray(E) * 1e-3,
             mode_hz=jnp.tile(jnp.array([11.4, 6.8]), (n, 1)), mode_damping=jnp.full((n, 2), 0.02))
    pts = jnp.asarray(named_path("diamond").points)
    t0 = time.perf_counter()
    out = _batch(pts, **x, axes=(0, 1), with_sensitivities=True)
    out["cycle_time"].block_until_ready()
    t_first = time.perf_counter() - t0
    t0 = time.perf_counter()
    out = _batch(pts, **x, axes=(0, 1), with_sensitivities=True)
    out["cycle_time"].block_until_ready()
    t_warm = time.perf_counter() - t0

    # baseline: the exact planner point by point (+ sampled residual vibration)
    rng = np.random.default_rng(0)
    pick = rng.choice(n, args.baseline, replace=False)
    path = named_path("diamond")
    plan_fir(path, 250.0, [0.148, 0.089], 0.5)  # compile once, outside the timing
    t0 = time.perf_counter()
    worst = worst_r = 0.0
    for i in pick:
        plan = plan_fir(path, 250.0, [T1[i] * 1e-3, T2[i] * 1e-3], E[i] * 1e-3)
        tr = plan.trajectory(1e-3)
        a = np.asarray(tr.a)
        r = max(residual_vibration_sampled(tr.t, a[:, 0], 11.4, 0.02), residual_vibration_sampled(tr.t, a[:, 1], 6.8, 0.02))
        worst = max(worst, abs(float(plan.cycle_time) - res.rows[i]["cycle_time"]),
                    abs(float(jnp.max(plan.corner_errors)) - res.rows[i]["max_corner_error"]))
        worst_r = max(worst_r, abs(r - res.rows[i]["residual_vibration"]) / res.rows[i]["residual_vibration"])
    t_base = (time.perf_counter() - t0) / args.baseline * n

    rows = [
        ("sweep pipeline, empty store", t_sweep, f"{n / t_sweep:,.0f} points/s"),
        ("same sweep again (store)", t_again, f"{t_sweep / t_again:,.0f}x faster than computing"),
        ("vmap call: compile + run", t_first, "one compiled call, values + 12 derivatives per point"),
        ("vmap call: warm", t_warm, f"{n / t_warm:,.0f} points/s"),
        (f"baseline plan_fir per point (x{n} from {args.baseline})", t_base, f"{t_base / t_sweep:,.1f}x slower than the sweep"),
    ]
    print(f"\n{n} points (T1 x T2 x eps = {args.t1} x {args.t2} x {args.eps}), diamond, F = 250 mm/s\n")
    print(f"{'measurement':<48} {'time [s]':>10}  note")
    for name, t, note in rows:
        print(f"{name:<48} {t:10.3f}  {note}")
    print(f"\nagreement with plan_fir on the baseline points: cycle time / corner error within {worst:.1e} (s / mm), "
          f"residual vibration (Ts = 1 ms trapezoid) within {worst_r:.1e} relative")
    print(f"\ntarget: 10^4-point sweep < {TARGET_S:.0f} s on 2 cores: {t_sweep:.1f} s -> "
          f"{'PASS' if t_sweep < TARGET_S else 'MISS'} (ratio to the per-point baseline {t_base / t_sweep:.1f}x)")


if __name__ == "__main__":
    main()
