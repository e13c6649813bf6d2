"""Dask LocalCluster (2 workers) against a serial run on an OCP sweep (issue 9, Benchmarks).

Usage::

    python benchmarks/bench_dask.py [--workers 2] [--eps 8] [--feeds 4]

Scenario: the general sweep path (:func:`research.experiments.sweep_general.run_general`, one
``evaluate`` per point, results written to an empty store) on time-optimal references
(:func:`research.optimal.time_optimal`, CasADi/IPOPT) of the Sencer 2015 diamond under the FIR
envelope of T1/T2 = 148/89 ms, N = 16 intervals per segment, over a grid of tolerance eps in
[100, 800] um x feed F in [150, 250] mm/s (default 8 x 4 = 32 points).

Measured in this run, same points, same code: serial (in this process, after one warm-up solve)
against a LocalCluster of ``--workers`` single-threaded processes (started and warmed with one solve
per worker before the timing: steady-state throughput, as for a cluster that serves many sweeps);
the cold time, cluster start included, is printed too. Target (issue 9): speed-up >= 1.7x with 2
workers. PASS/MISS as measured; the machine is shared, so times vary by tens of percent.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import numpy as np

import research  # noqa: F401
from research.experiments.config import validate
from research.experiments.runner import config_key
from research.experiments.store import ResultStore
from research.experiments.sweep_general import ONE_THREAD, point_task, run_general

TARGET = 1.7


def tasks(eps_values, feeds, tmp: Path):
    out = []
    for i, (eps, feed) in enumerate((e, f) for e in eps_values for f in feeds):
        raw = {"name": "bench_dask", "reproduces": "benchmark", "path": {"name": "diamond"},
               "interpolator": {"kind": "time_optimal", "tolerance_um": float(eps), "feed_mm_per_s": float(feed),
                                "intervals_per_segment": 16}}
        cfg = validate(raw, tmp / "bench.toml")
        out.append((i, config_key(cfg, tmp), cfg.model_dump(mode="json")))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--eps", type=int, default=8)
    ap.add_argument("--feeds", type=int, default=4)
    args = ap.parse_args()
    from dask.distributed import Client, LocalCluster

    print(f"{os.cpu_count()} cores, load {os.getloadavg()[0]:.1f}")
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        todo = tasks(np.linspace(100.0, 800.0, args.eps), np.linspace(150.0, 250.0, args.feeds), tmp)
        warm = tasks([300.0], [200.0], tmp)[0][2]
        point_task(warm, str(tmp))  # imports, CasADi and JAX warm-up, outside the timing
        t0 = time.perf_counter()
        serial = run_general(todo, tmp, ResultStore(tmp / "serial"), engine="serial")
        t_serial = time.perf_counter() - t0

        t0 = time.perf_counter()
        cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True, dashboard_address=None,
                               env=ONE_THREAD)
        client = Client(cluster)
        client.gather([client.submit(point_task, warm, str(tmp), pure=False) for _ in range(args.workers)])
        t_start = time.perf_counter() - t0
        t0 = time.perf_counter()
        parallel = run_general(todo, tmp, ResultStore(tmp / "dask"), engine="dask", scheduler=cluster.scheduler_address)
        t_dask = time.perf_counter() - t0
        client.close()
        cluster.close()
    ok = [i for i in serial if serial[i].get("status") == "ok"]
    diff = max(abs(serial[i]["scalars"]["cycle_time"] - parallel[i]["scalars"]["cycle_time"]) for i in ok)
    speedup = t_serial / t_dask
    cold = t_serial / (t_dask + t_start)
    print(f"\n{len(todo)} time-optimal diamond references (eps x F = {args.eps} x {args.feeds}), "
          f"{len(ok)} solved, serial and Dask cycle times within {diff:.1e} s\n")
    print(f"{'run':<44} {'time [s]':>9} {'per point [s]':>14}")
    print(f"{'serial (this process)':<44} {t_serial:9.2f} {t_serial / len(todo):14.3f}")
    print(f"{f'Dask LocalCluster, {args.workers} workers (warm)':<44} {t_dask:9.2f} {t_dask / len(todo):14.3f}")
    print(f"{'cluster start + warm-up (not in the speed-up)':<44} {t_start:9.2f}")
    print(f"\nspeed-up {speedup:.2f}x (cold, start included: {cold:.2f}x); target >= {TARGET}x with 2 workers: "
          f"{'PASS' if speedup >= TARGET else 'MISS'}")


if __name__ == "__main__":
    main()
