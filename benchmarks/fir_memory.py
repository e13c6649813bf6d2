"""Where ``plan_fir``'s peak traced memory is: per-stage peaks and what is held at the peak stage.

Usage::

    python benchmarks/fir_memory.py [--paths q34] [--snapshot STAGE]

Paths: ``q`` bench_cam's quick CAM file (``cam_program(0, LEVELS_QUICK)``, its scenario), ``3`` /
``4`` bench_fir's path of 10^3 / 10^4 segments (its scenario). For each: the peak of one warm call
as ``bench_fir.peak_memory`` measures it (``tracemalloc``, above what was allocated before), the
bytes of the returned plan's arrays (and of its position's, built on first use), and for the planner's stages (functions wrapped while a second
call runs) the largest peak inside each, split into what was held at its entry and what it added.
The wrappers reset ``tracemalloc``'s peak at each entry and keep the running maximum themselves, for
the whole call and for every stage still open (a stage's peak includes those of the stages it calls), so
the total is the same peak. ``--snapshot STAGE`` (a label as printed) also lists the
allocation sites (up to three frames in ``research``) of what was held at the entry of ``STAGE``,
at the call where that was largest. All figures in kB per segment.
"""

from __future__ import annotations

import argparse
import functools
import sys
import tracemalloc

import jax
import numpy as np

sys.path.insert(0, "benchmarks")
import bench_cam  # noqa: E402
import bench_fir  # noqa: E402
from research.interpolators import _fir_lookahead, _fir_profile, _fir_settle, _fir_verify, plan_fir  # noqa: E402
from research.paths import toolpath  # noqa: E402

STAGES = [  # (owner, attribute, label)
    (_fir_settle, "look_ahead", "look-ahead (candidates)"),
    (_fir_lookahead, "_candidate", "  one candidate's arrays"),
    (_fir_profile, "profile", "exact profile build"),
    (_fir_verify.RoundChecks, "__call__", "round checks"),
    (_fir_verify, "vertex_distances", "  vertex errors"),
    (_fir_verify, "_charged_samples", "  path-check chunk"),
    (toolpath.ToolPath, "distance_bound", "  ToolPath.distance_bound"),
]


def scenarios(which: str) -> dict:
    """``{name: (polyline, feeds, delays, tolerance)}`` read back through G-code, as the benchmarks do."""
    out = {}
    if "q" in which:
        path, _ = bench_cam.cam_program(0, bench_cam.LEVELS_QUICK)
        prog = bench_cam.parse_gcode(bench_cam.to_gcode(path, bench_cam.FEED * 60.0), start=tuple(path.points[0]))
        out["quick CAM file"] = (prog.polyline, np.asarray(prog.feeds), bench_cam.DELAYS, bench_cam.EPS)
    for n in "34":
        if n in which:
            path = bench_fir.cam_path(10 ** int(n), 0)
            prog = bench_fir.parse_gcode(bench_fir.to_gcode(path, bench_fir.FEED * 60.0), start=tuple(path.points[0]))
            out[f"bench_fir 10^{n}"] = (prog.polyline, np.asarray(prog.feeds), bench_fir.DELAYS, bench_fir.TOLERANCE)
    return out


class Recorder:
    """Per-stage ``[calls, peak, held at entry, added]`` (bytes) and a snapshot at one stage's entry."""

    def __init__(self, snapshot_at: str | None):
        self.stats: dict[str, list[int]] = {}
        self.outer = self.base = 0
        self.open: list[list[int]] = []  # running peaks of the stages entered and not left
        self.snapshot_at, self.snapshot, self.snapshot_held = snapshot_at, None, -1

    def wrap(self, owner, name: str, label: str):
        f = getattr(owner, name)

        @functools.wraps(f)
        def staged(*args, **kwargs):
            cur, peak = tracemalloc.get_traced_memory()
            self.outer = max(self.outer, peak)
            for frame in self.open:  # the peak so far counts in every enclosing stage
                frame[0] = max(frame[0], peak)
            if label == self.snapshot_at and cur > self.snapshot_held:
                self.snapshot_held, self.snapshot = cur, tracemalloc.take_snapshot()
            self.open.append([0])
            tracemalloc.reset_peak()
            try:
                return f(*args, **kwargs)
            finally:
                peak = tracemalloc.get_traced_memory()[1]
                self.outer = max(self.outer, peak)
                for frame in self.open:
                    frame[0] = max(frame[0], peak)
                peak = self.open.pop()[0]
                s = self.stats.setdefault(label, [0, 0, 0, 0])
                s[0] += 1
                if peak > s[1]:
                    s[1:] = [peak, cur, peak - cur]

        setattr(owner, name, staged)
        return f

    def run(self, fn, *args) -> int:
        self.stats.clear()
        tracemalloc.start(30)
        try:
            self.base = tracemalloc.get_traced_memory()[0]
            self.outer = 0
            self.start = tracemalloc.take_snapshot() if self.snapshot_at else None
            fn(*args)
            return max(self.outer, tracemalloc.get_traced_memory()[1]) - self.base
        finally:
            tracemalloc.stop()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--paths", default="q34")
    ap.add_argument("--snapshot", default=None, help="stage label (as printed) whose entry to list")
    args = ap.parse_args()
    for name, (path, feeds, delays, eps) in scenarios(args.paths).items():
        M = path.n_segments
        plan = plan_fir(path, feeds, delays, eps)  # warm: compiled kernels, path caches
        peak = bench_fir.peak_memory(plan_fir, path, feeds, delays, eps)
        plan_bytes = sum(np.asarray(x).nbytes for x in jax.tree_util.tree_leaves(plan))
        built = sum(np.asarray(x).nbytes for x in (plan.position.breaks, plan.position.coeffs))
        print(f"{name}: {M} segments, peak {peak / M / 1e3:.2f} kB/segment (bench_fir.peak_memory); returned plan's "
              f"arrays {plan_bytes / M / 1e3:.2f} kB/segment (+ {built / M / 1e3:.2f} once its position is built); "
              f"cycle time {float(plan.cycle_time):.6f} s")
        rec = Recorder(args.snapshot)
        originals = [(owner, attr, rec.wrap(owner, attr, label)) for owner, attr, label in STAGES]
        try:
            total = rec.run(plan_fir, path, feeds, delays, eps)
        finally:
            for owner, attr, f in originals:
                setattr(owner, attr, f)
        print(f"  staged run: peak {total / M / 1e3:.2f}; per stage: calls, peak = held at entry + added")
        for label, (n, pk, held, added) in sorted(rec.stats.items(), key=lambda kv: -kv[1][1]):
            print(f"  {label:30s} {n:4d} {(pk - rec.base) / M / 1e3:6.2f} = {(held - rec.base) / M / 1e3:.2f} "
                  f"+ {added / M / 1e3:.2f}")
        if rec.snapshot is not None:
            print(f"  held at the entry of {args.snapshot!r}: {(rec.snapshot_held - rec.base) / M / 1e3:.2f}, by site:")
            snap = rec.snapshot.filter_traces([tracemalloc.Filter(False, tracemalloc.__file__)])
            for st in snap.compare_to(rec.start, "traceback")[:16]:
                frames = [f for f in st.traceback if "/research/" in f.filename][-3:] or list(st.traceback)[-1:]
                where = " <- ".join(f"{f.filename.split('/research/')[-1]}:{f.lineno}" for f in reversed(frames))
                print(f"    {st.size_diff / M / 1e3:6.3f}  {where}")


if __name__ == "__main__":
    main()
