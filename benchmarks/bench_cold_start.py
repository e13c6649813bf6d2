"""First ``plan_fir`` after a fresh install: compilation on empty caches, against the same call warm
(issue "FIR cornering on real CAM programs", item 5: a new path must not cost a fresh compile).

Usage::

    python benchmarks/bench_cold_start.py [--loops 25]

Each case runs in a new Python process twice with the same two empty cache folders
(``NUMBA_CACHE_DIR`` for the Numba kernels, ``RESEARCH_JAX_CACHE`` for JAX): the first process
compiles and fills them (a fresh install's first plan), the second one loads them (every later
process). Cases: the lines of the Sencer 2015 diamond (two filters) and a seeded adaptive-clearing
program of ``bench_adaptive`` (lines and arcs), then the same adaptive program through three
filters in the same cache (one more row count per filter: what a user's first 3-filter plan adds).
Prints the wall time of the ``plan_fir`` call in each process; the compile time is the cold minus
the warm one. Absolute times depend on the machine and its load: compare within one run.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile

_CASE = r"""
import sys, time
sys.path.insert(0, "benchmarks")
from research.interpolators import plan_fir
case, loops = sys.argv[1], int(sys.argv[2])
if case == "diamond":
    from research.paths.library import diamond
    path, feed, delays, eps = diamond(), 250.0, (0.148, 0.089), 0.5
else:
    from bench_adaptive import HOME, adaptive_program
    from research.paths.gcode import parse_gcode
    prog = parse_gcode(adaptive_program(0, loops), source="adaptive", home=HOME)
    path, feed, eps = prog.blocks, prog.block_feeds, 0.05
    delays = (0.06, 0.03) if case == "adaptive" else (0.05, 0.03, 0.01)
t0 = time.perf_counter()
plan = plan_fir(path, feed, delays, eps)
print(f"{time.perf_counter() - t0:.3f} {float(plan.cycle_time):.6f}")
"""


def _run(case: str, loops: int, env: dict) -> tuple[float, float]:
    out = subprocess.run([sys.executable, "-c", _CASE, case, str(loops)], env=env, capture_output=True, text=True,
                         check=True, cwd=os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    seconds, cycle = out.stdout.split()[-2:]
    return float(seconds), float(cycle)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--loops", type=int, default=25, help="trochoidal loops of the adaptive program")
    args = ap.parse_args(argv)
    print(f"load {os.getloadavg()[0]:.1f}")
    print(f"{'case':>22} {'cold [s]':>9} {'warm [s]':>9} {'compile [s]':>12} {'cold / warm':>12}")
    for cases in (("diamond",), ("adaptive", "adaptive-3-filters")):
        with tempfile.TemporaryDirectory() as numba_dir, tempfile.TemporaryDirectory() as jax_dir:
            env = dict(os.environ, NUMBA_CACHE_DIR=numba_dir, RESEARCH_JAX_CACHE=jax_dir)
            for case in cases:
                cold, c1 = _run(case, args.loops, env)
                warm, c2 = _run(case, args.loops, env)
                assert c1 == c2, (case, c1, c2)  # the same plan from compiled and cached kernels
                print(f"{case:>22} {cold:>9.2f} {warm:>9.2f} {cold - warm:>12.2f} {cold / warm:>11.0f}x", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
