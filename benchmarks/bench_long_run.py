"""A long CAM program through the whole main job (``python -m research run``): where the time and
the memory go, stage by stage.

Usage (from the repository root)::

    python benchmarks/bench_long_run.py [--passes 400] [--keep DIR]

The program is ``bench_cam.cam_program(0, passes)`` (a waterline finishing program of a freeform
curve, 1-10 um chords; 400 passes: 77,633 chords), written with ``to_gcode`` at bench_cam's F
200 mm/s and read back by the config's ``[path] gcode``; FIR 60/30 ms, eps 50 um, Ts 1 ms. It runs
``research.experiments.run_experiment`` once with ``force`` in a fresh store, its stages wrapped to
print the wall time each takes and the process's peak resident memory after it
(``ru_maxrss``: a high-water mark, so a stage's figure is the peak so far). In the same process,
the baseline: one ``plan_fir`` call on the same program (warm), and the ratio of the whole run to
it. Results and store go to a temporary folder (``--keep`` to keep them).
"""

from __future__ import annotations

import argparse
import functools
import resource
import shutil
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_cam  # noqa: E402

import research.experiments.evaluate as evaluate  # noqa: E402
import research.experiments.runner as runner  # noqa: E402
from research.interpolators import plan_fir  # noqa: E402
from research.paths.gcode import read_gcode  # noqa: E402

DELAYS_MS, EPS_UM, TS_MS = (60.0, 30.0), 50.0, 1.0


def rss_mb() -> float:
    """Peak resident memory of this process so far [MB] (Linux ``ru_maxrss`` is in kB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def staged(owner, name: str, rows: list):
    """Wrap ``owner.name`` to append ``(name, seconds, peak resident MB after)`` to ``rows``."""
    f = getattr(owner, name)

    @functools.wraps(f)
    def wrapper(*args, **kwargs):
        t = time.perf_counter()
        out = f(*args, **kwargs)
        rows.append((name, time.perf_counter() - t, rss_mb()))
        return out

    setattr(owner, name, wrapper)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--passes", type=int, default=400, help="waterline passes (400: 77,633 chords)")
    ap.add_argument("--keep", default=None, help="folder for the program, store and results (default: a temporary one)")
    args = ap.parse_args(argv)
    folder = Path(args.keep or tempfile.mkdtemp(prefix="bench_long_run."))
    folder.mkdir(parents=True, exist_ok=True)
    path, _ = bench_cam.cam_program(0, args.passes)
    program = folder / "program.ngc"
    program.write_text(bench_cam.to_gcode(path, bench_cam.FEED * 60.0))
    config = folder / "long_run.toml"
    config.write_text(f'name = "long_run"\nreproduces = "benchmark: a long CAM program end to end"\n[path]\n'
                      f'gcode = "{program.name}"\n[interpolator]\nkind = "fir"\ndelays_ms = {list(DELAYS_MS)}\n'
                      f"tolerance_um = {EPS_UM}\nsample_period_ms = {TS_MS}\n")
    print(f"program: {path.n_segments:,} chords, {path.length:.0f} mm ({program.stat().st_size / 1e6:.1f} MB G-code)")
    base_mb = rss_mb()
    print(f"resident after imports: {base_mb:.0f} MB")

    rows: list = []
    for owner, name in ((evaluate, "read_program"), (evaluate, "interpolate"), (evaluate, "summarize"),
                        (runner, "_figure")):
        staged(owner, name, rows)
    t0 = time.perf_counter()
    result = runner.run_experiment(config, cache_dir=folder / "results", figures_dir=folder / "figures",
                                   log=lambda s: None, force=True)
    total = time.perf_counter() - t0
    cycle = result.record["scalars"]["cycle_time"]
    print(f"cycle time {cycle:.3f} s at Ts = {TS_MS:g} ms: {int(cycle / (TS_MS * 1e-3)) + 1:,} samples")
    print(f"{'stage':<14} {'time [s]':>9} {'peak resident after [MB]':>26}")
    for name, seconds, peak in rows:
        print(f"{name:<14} {seconds:9.2f} {peak:26.0f}")
    print(f"{'store, files':<14} {total - sum(r[1] for r in rows):9.2f} {rss_mb():26.0f}   (the rest of the run)")
    print(f"{'whole run':<14} {total:9.2f} {rss_mb():26.0f}")

    prog = read_gcode(program)
    t = time.perf_counter()
    plan_fir(prog.polyline, prog.feeds, tuple(d * 1e-3 for d in DELAYS_MS), EPS_UM * 1e-3)
    plan_s = time.perf_counter() - t
    print(f"baseline, one warm plan_fir of the same program: {plan_s:.2f} s; the whole run is {total / plan_s:.1f}x it")
    print(f"peak resident above the imports: {(rss_mb() - base_mb) * 1e3 / path.n_segments:.1f} kB per chord")
    if args.keep:
        print(f"files under {folder}")
    else:
        shutil.rmtree(folder, ignore_errors=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
