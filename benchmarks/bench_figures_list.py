"""``python -m research figures --list`` against importing every figure module (issue 16, target < 2 s).

The baseline is what ``--list`` did before: ``research.figures.registry()`` (imports every registered
figure module, and with them jax, matplotlib and the package). Both run in fresh interpreters in this
run, best of ``REPEATS``; the ratio is baseline / list.

    python benchmarks/bench_figures_list.py
"""

from __future__ import annotations

import subprocess
import sys
import time

REPEATS = 3
TARGET_S = 2.0  # issue 16: "--list answers in under 2 s"


def _best(cmd: list[str]) -> float:
    times = []
    for _ in range(REPEATS):
        t = time.perf_counter()
        subprocess.run(cmd, check=True, capture_output=True)
        times.append(time.perf_counter() - t)
    return min(times)


def main() -> None:
    listing = _best([sys.executable, "-m", "research", "figures", "--list"])
    baseline = _best([sys.executable, "-c", "from research.figures import registry; registry()"])
    print(f"figures --list: {listing:.3f} s (best of {REPEATS}, fresh interpreter, start-up included)")
    print(f"baseline, import every figure module: {baseline:.3f} s")
    print(f"ratio baseline / list = {baseline / listing:.1f}")
    print(f"target < {TARGET_S:g} s: {'PASS' if listing < TARGET_S else 'MISS'}")


if __name__ == "__main__":
    main()
