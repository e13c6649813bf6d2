"""Mirror pre-compensated FIR plans (``plan_fir_mirror``) against ``plan_fir`` in the same run.

Usage::

    python benchmarks/fir_mirror.py [--quick] [--sweep] [--sweep-feeds] [--sweep-raise] [--sweep-chords]
                                    [--fillets-only]

1. ``--sweep``: the two constants of ``research/interpolators/_fir_mirror.py`` (``RELAX``, the
   tolerance factor the first round's timing is planned at, and ``PASSES``, the mirror passes per
   round) swept on bench_cam's quick CAM file (2,251 chords, F 200 mm/s, T 60/30 ms, eps 50 um,
   limits = the FIR's nominal envelope): cycle time, ratio to ``plan_fir``, rounds, planning time.
   ``--sweep-feeds``: the search's feed steps (``LIMIT_EXPONENT`` x ``LEAST_STEP`` x
   ``TOLERANCE_STEP``, then ``LIMIT_REACH`` alone) and the passes' smoothing (``SMOOTH``) on the
   first 100 and 300 chords of the 10^4-chord file, the quick file and bench_cam's part 4
   micro-chord program rounded to 0.1 and 2.54 um, the same setting: cycle times, rounds, sum.
   ``--sweep-raise``: the raise phase's step (``RAISE_STEP``, 0: no raise phase) on the first 100,
   300 and 1,000 chords, the quick file at eps 10-200 um and the micro-chord program at 0.1 and
   2.54 um: cycle times, rounds, sum.
   ``--sweep-chords``: the sagitta of the chords the search plans arcs as (``CHORD_SHARE``) on the
   programs with arcs of part 2 (one arc-fitted pass): cycle times, sum, planning time.
2. The defaults on bench_cam's CAM files (quick; the 10^4-chord file unless ``--quick``), on
   programs with arcs (``arc_programs``: chains of tangent arcs, the freeform curve's flat passes
   arc-fitted like a CAM post's arc filter, next to the chords they were fitted to, and
   ``random_program`` seeds 100-107; the envelope's limits), and on cam30 and the paper paths
   (``corner90``, ``diamond``, ``zigzag``) at bench_cam's setting, with the envelope's limits and
   without: cycle times, the ratio mirror / plain, the largest distance to the
   programmed path and the worst limit ratio of the mirror plan (``metrics``, on samples every
   0.5 ms), and the planning time of both (process time; the mirror's includes its plain plan).
3. Fillets (``_fir_mirror_paths.cornered``): a fillet of R 1 mm between two 50 mm lines, closed
   60 x 40 mm rectangles with R 1 and R 5 mm fillets, the offset pocket of 8 rings (``offset_pocket``)
   and slots of 40 mm with R 1 and R 3 mm half circles (``slot``, a fillet that turns the path back),
   each as G2/G3 arcs and as G1 chords of 1 um sagitta, with the envelope's limits and without:
   plain -> mirror, and the mirror with no fillet planned as a corner (``SHORT_REACH`` = 0) in the
   same run. ``--fillets-only`` runs this part alone.

Every plan printed is verified on the programmed path by ``plan_fir_mirror`` itself (vertex
distances and samples every 1 ms, as ``plan_fir``); the distance and limit columns are an
independent check on the sampled trajectory.
"""

from __future__ import annotations

import argparse
import itertools
import sys
import time

import numpy as np

sys.path.insert(0, "benchmarks")
import bench_cam  # noqa: E402
from bench_fir import Table  # noqa: E402
from research import metrics  # noqa: E402
from research.interpolators import plan_fir, plan_fir_mirror  # noqa: E402
from research.interpolators import _fir_mirror, _fir_mirror_feeds, _fir_mirror_paths  # noqa: E402
from research.limits import AxisLimits  # noqa: E402
from research.paths import Polyline, named_path  # noqa: E402
from research.paths.gcode import parse_gcode  # noqa: E402
from research.paths.library import random_program  # noqa: E402
import arc_programs  # noqa: E402
from research.paths.toolpath import ToolPath  # noqa: E402

SWEEP_RELAX = (2.0, 4.0, 8.0, 16.0, 32.0, 64.0)
SWEEP_PASSES = (1, 3, 5, 8)
SWEEP_EXPONENT = (0.25, 1.0 / 3.0, 0.5)
SWEEP_LEAST = (0.01, 0.03)
SWEEP_TOLERANCE = (0.03, 0.05, 0.1)
SWEEP_REACH = (0.0, 0.05, 0.1, 0.25, 0.5)
SWEEP_SMOOTH = (0.0, 0.1, 0.15, 0.25, 0.35, 0.5, 1.0)
SWEEP_RAISE = (0.0, 0.01, 0.03, 0.05, 0.1, 0.2)
SWEEP_RAISE_EPS = (0.01, 0.02, 0.03, 0.05, 0.075, 0.1, 0.15, 0.2)  # the quick file's eps ladder [mm]
SWEEP_CHORDS = (0.01, 0.02, 0.05, 0.1, 0.2, 0.35, 0.5)  # CHORD_SHARE
ARC_SEEDS = range(100, 108)  # random_program seeds of the arc programs (test_fir_mirror's are 100-103)
FIT_CHORD_TOL, FIT_TOL = 2e-3, 5e-3  # the arc-fitted passes: source chords' sagitta, arc filter tolerance [mm]


def timed(fn, *args, **kwargs):
    t0 = time.process_time()
    out = fn(*args, **kwargs)
    return out, time.process_time() - t0


def checked(m, path, limits) -> tuple[float, float]:
    """Largest distance [mm] of the mirror plan's samples (every 0.5 ms) to the programmed path
    (``ToolPath.distance``) and its worst limit ratio (``metrics.limit_ratios``; NaN without limits)."""
    tr = m.plan.trajectory(5e-4)
    tp = path if isinstance(path, ToolPath) else ToolPath.from_polyline(path)
    dist = float(np.max(tp.distance(np.asarray(tr.q))))
    ratio = float("nan") if limits is None else max(float(np.max(r)) for r in metrics.limit_ratios(tr, limits).values())
    return dist, ratio


def cam_file(levels: int):
    path, _ = bench_cam.cam_program(0, levels)
    prog = bench_cam.parse_gcode(bench_cam.to_gcode(path, bench_cam.FEED * 60.0), start=tuple(path.points[0]))
    return prog.polyline


def sweep(table: Table) -> None:
    path = cam_file(bench_cam.LEVELS_QUICK)
    limits = AxisLimits.fir_envelope(path.dim, bench_cam.FEED, bench_cam.DELAYS)
    args = (path, bench_cam.FEED, bench_cam.DELAYS, bench_cam.EPS)
    plain, t_plain = timed(plan_fir, *args, limits=limits)
    T = float(plain.cycle_time)
    table.section(f"Sweep on the quick CAM file ({path.n_segments} chords), limits = envelope: plan_fir {T:.4f} s, "
                  f"planned in {t_plain:.2f} s")
    for relax in SWEEP_RELAX:
        for passes in SWEEP_PASSES:
            m, t = timed(plan_fir_mirror, *args, limits=limits, relax=relax, passes=passes)
            table.row(f"  relax {relax:g}, passes {passes}", f"{m.cycle_time:.4f} s", f"{m.cycle_time / T:.4f}x plain",
                      f"{m.rounds} rounds", f"{t:.2f} s planning")


def sweep_feeds(table: Table) -> None:
    whole = cam_file(bench_cam.LEVELS)
    paths = {"first 100": Polyline(whole.points[:101]), "first 300": Polyline(whole.points[:301]),
             "quick file": cam_file(bench_cam.LEVELS_QUICK), "micro 0.1 um": bench_cam.micro_program(1e-4),
             "micro 2.54 um": bench_cam.micro_program(2.54e-3)}
    F, D, eps = bench_cam.FEED, bench_cam.DELAYS, bench_cam.EPS
    table.section("Sweep of the mirror's feed steps and smoothing, limits = envelope: cycle times [s] (rounds) of "
                  + ", ".join(paths) + " (part 4's program rounded to 0.1 / 2.54 um)")
    names = [(_fir_mirror_feeds, "LIMIT_EXPONENT"), (_fir_mirror_feeds, "LEAST_STEP"), (_fir_mirror, "TOLERANCE_STEP"),
             (_fir_mirror_feeds, "LIMIT_REACH"), (_fir_mirror, "SMOOTH")]
    kept = [getattr(module, name) for module, name in names]
    settings = [dict(zip(("LIMIT_EXPONENT", "LEAST_STEP", "TOLERANCE_STEP"), c))
                for c in itertools.product(SWEEP_EXPONENT, SWEEP_LEAST, SWEEP_TOLERANCE)]
    settings += [{"LIMIT_REACH": r} for r in SWEEP_REACH] + [{"SMOOTH": w} for w in SWEEP_SMOOTH]
    try:
        for setting in settings:
            for (module, name), value in zip(names, kept):
                setattr(module, name, setting.get(name, value))
            times, rounds = [], []
            for path in paths.values():
                m = plan_fir_mirror(path, F, D, eps, limits=AxisLimits.fir_envelope(path.dim, F, D))
                times.append(m.cycle_time)
                rounds.append(m.rounds)
            table.row("  " + ", ".join(f"{k} {v:.3g}" for k, v in setting.items()),
                      " / ".join(f"{t:.4f} ({r})" for t, r in zip(times, rounds)), f"sum {sum(times):.4f} s")
    finally:
        for (module, name), value in zip(names, kept):
            setattr(module, name, value)


def sweep_raise(table: Table) -> None:
    whole = cam_file(bench_cam.LEVELS)
    quick = cam_file(bench_cam.LEVELS_QUICK)
    F, D = bench_cam.FEED, bench_cam.DELAYS
    cases = [(f"first {n}", Polyline(whole.points[:n + 1]), bench_cam.EPS) for n in (100, 300, 1000)]
    cases += [(f"quick {e * 1e3:g} um", quick, e) for e in SWEEP_RAISE_EPS]
    cases += [("micro 0.1 um", bench_cam.micro_program(1e-4), bench_cam.EPS),
              ("micro 2.54 um", bench_cam.micro_program(2.54e-3), bench_cam.EPS)]
    table.section("Sweep of the raise phase's step (RAISE_STEP; 0: none), limits = envelope: cycle times [s] "
                  "(rounds) of " + ", ".join(name for name, _, _ in cases))
    kept = _fir_mirror.RAISE_STEP
    try:
        for step in SWEEP_RAISE:
            _fir_mirror.RAISE_STEP = step  # the name _fir_mirror's search starts each block's step from
            out = [plan_fir_mirror(p, F, D, e, limits=AxisLimits.fir_envelope(p.dim, F, D)) for _, p, e in cases]
            table.row(f"  RAISE_STEP {step:g}", " / ".join(f"{m.cycle_time:.4f} ({m.rounds})" for m in out),
                      f"sum {sum(m.cycle_time for m in out):.4f} s")
    finally:
        _fir_mirror.RAISE_STEP = kept


def arc_cases(levels: int) -> dict:
    """``{name: (path, its chord source or None)}``: the programs with arcs (arc_programs): a chain
    of 40 tangent arcs (a line before every third), 30 arcs between lines, the freeform curve's
    flat passes arc-fitted (with the chords they were fitted to), ``random_program`` seeds
    ``ARC_SEEDS`` (lines and arcs), and offset pockets of 1 and 8 rings with small corner fillets
    (``arc_programs.offset_pocket``)."""
    pts = arc_programs.freeform_passes(levels, FIT_CHORD_TOL)
    text, counts = arc_programs.arc_fitted(pts, FIT_TOL, bench_cam.FEED * 60.0)
    fitted = parse_gcode(text, start=tuple(pts[0])).blocks
    cases = {"40 tangent arcs, a line every 3rd": (arc_programs.arc_chain(40, 3, 3), None),
             "30 tangent arcs between lines": (arc_programs.arc_chain(30, 3, 1), None),
             f"freeform x {levels} flat passes arc-fitted at {FIT_TOL * 1e3:g} um ({counts['arcs']} arcs, "
             f"{counts['lines']} lines)": (fitted, Polyline(pts))}
    cases.update({f"random_program seed {s}": (random_program(np.random.default_rng(s)), None) for s in ARC_SEEDS})
    for rings in (1, 8):  # fillets far shorter than the filters' reach (plan_fir_mirror's short arcs)
        text = arc_programs.offset_pocket(rings)
        cases[f"offset pocket, {rings} ring{'s' if rings > 1 else ''}, G3 fillets R 0.3-1 mm"] = (
            parse_gcode(text, start=(30.0, 0.0, 0.0)).blocks, None)
    return cases


def sweep_chords(table: Table) -> None:
    F, D, eps = bench_cam.FEED, bench_cam.DELAYS, bench_cam.EPS
    cases = arc_cases(1)
    table.section("Sweep of the arcs' chord sagitta (CHORD_SHARE of eps), limits = envelope: cycle times [s] of "
                  + ", ".join(cases))
    kept = _fir_mirror_paths.CHORD_SHARE
    try:
        for share in SWEEP_CHORDS:
            _fir_mirror_paths.CHORD_SHARE = share
            out, t = [], 0.0
            for path, _ in cases.values():
                m, dt = timed(plan_fir_mirror, path, F, D, eps, limits=AxisLimits.fir_envelope(path.dim, F, D))
                out.append(m.cycle_time)
                t += dt
            table.row(f"  CHORD_SHARE {share:g}", " / ".join(f"{x:.4f}" for x in out),
                      f"sum {sum(out):.4f} s", f"planning {t:.1f} s")
    finally:
        _fir_mirror_paths.CHORD_SHARE = kept


def fillet_cases() -> dict:
    """``{name: path}`` of part 3 (module docstring): each program as arcs and as 1 um G1 chords."""
    corner = parse_gcode("G21 G90 G17\nG1 X-1 Y0 F12000\nG3 X0 Y1 I0 J1\nG1 X0 Y50\nM2", start=(-50.0, 0.0, 0.0)).blocks
    programs = {"fillet R 1 mm between 50 mm lines": corner,
                "rectangle 60 x 40 mm, R 1 mm fillets": parse_gcode(arc_programs.offset_pocket(1),
                                                                  start=(30.0, 0.0, 0.0)).blocks,
                "rectangle 60 x 40 mm, R 5 mm fillets": parse_gcode(arc_programs.offset_pocket(1, radius=5.0),
                                                                  start=(30.0, 0.0, 0.0)).blocks,
                "offset pocket, 8 rings, R 1-0.3 mm fillets": parse_gcode(arc_programs.offset_pocket(8),
                                                                        start=(30.0, 0.0, 0.0)).blocks,
                "slot 40 mm, R 1 mm half circles": parse_gcode(arc_programs.slot(1.0), start=(20.0, -1.0, 0.0)).blocks,
                "slot 40 mm, R 3 mm half circles": parse_gcode(arc_programs.slot(3.0), start=(20.0, -3.0, 0.0)).blocks}
    cases = {}
    for name, tp in programs.items():
        cases[f"{name}, arcs"] = tp
        cases[f"{name}, 1 um chords"] = tp.to_polyline(1e-3)[0]
    return cases


def fillets(table: Table) -> None:
    """Part 3 (module docstring)."""
    F, D, eps = bench_cam.FEED, bench_cam.DELAYS, bench_cam.EPS
    table.section("Fillets planned as corners (_fir_mirror_paths.cornered): plain -> mirror; the mirror "
                  "without (SHORT_REACH = 0) in the same run")
    kept = _fir_mirror_paths.SHORT_REACH
    for name, path in fillet_cases().items():
        for lim in (None, AxisLimits.fir_envelope(path.dim, F, D)):
            try:
                _fir_mirror_paths.SHORT_REACH = 0.0
                without = plan_fir_mirror(path, F, D, eps, limits=lim).cycle_time
            finally:
                _fir_mirror_paths.SHORT_REACH = kept
            T, Tm = compare(table, name, path, F, D, eps, lim)
            table.row("  without fillets as corners", f"{without:.4f} s", f"{Tm / without:.4f}x of it")


def compare(table: Table, name: str, path, feed, delays, eps, limits) -> tuple[float, float]:
    """One row: ``plan_fir`` and ``plan_fir_mirror`` on ``path``; returns their cycle times [s]."""
    args = (path, feed, delays, eps)
    plan_fir(*args, limits=limits)  # compiled kernels warm for both timings
    plain, t_plain = timed(plan_fir, *args, limits=limits)
    m, t = timed(plan_fir_mirror, *args, limits=limits)
    dist, ratio = checked(m, path, limits)
    T = float(plain.cycle_time)
    table.row(f"{name}{'' if limits is None else ', limits = envelope'}", f"{T:.4f} -> {m.cycle_time:.4f} s",
              f"{m.cycle_time / T:.4f}x plain", f"dist {dist * 1e3:.2f} um / eps {eps * 1e3:g}, limits {ratio:.3f}",
              f"planning {t_plain:.2f} -> {t:.2f} s ({m.rounds} rounds)")
    return T, m.cycle_time


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="the quick CAM file only (no 10^4-chord file)")
    ap.add_argument("--sweep", action="store_true", help="sweep RELAX x PASSES on the quick CAM file first")
    ap.add_argument("--sweep-feeds", action="store_true", help="sweep the feed steps of _fir_mirror_feeds first")
    ap.add_argument("--sweep-raise", action="store_true", help="sweep the raise phase's step first")
    ap.add_argument("--sweep-chords", action="store_true", help="sweep the arcs' chord sagitta (CHORD_SHARE) first")
    ap.add_argument("--fillets-only", action="store_true", help="part 3 (fillets) alone")
    args = ap.parse_args(argv)
    table = Table(f"plan_fir_mirror (RELAX {_fir_mirror.RELAX:g}, PASSES {_fir_mirror.PASSES}) against plan_fir")
    if args.sweep:
        sweep(table)
    if args.sweep_feeds:
        sweep_feeds(table)
    if args.sweep_raise:
        sweep_raise(table)
    if args.sweep_chords:
        sweep_chords(table)
    F, D, eps = bench_cam.FEED, bench_cam.DELAYS, bench_cam.EPS
    if args.fillets_only:
        fillets(table)
        table.print()
        return 0
    table.section(f"Defaults, F {F:g} mm/s, T {D[0] * 1e3:g}/{D[1] * 1e3:g} ms, eps {eps * 1e3:g} um: "
                  "plain -> mirror cycle time")
    files = [bench_cam.LEVELS_QUICK] + ([] if args.quick else [bench_cam.LEVELS])
    for levels in files:
        path = cam_file(levels)
        lim = AxisLimits.fir_envelope(path.dim, F, D)
        compare(table, f"CAM file, {path.n_segments} chords", path, F, D, eps, lim)
    table.section(f"Programs with arcs (CHORD_SHARE {_fir_mirror_paths.CHORD_SHARE:g}), limits = envelope")
    plain_sum = mirror_sum = 0.0
    for name, (path, source) in arc_cases(1 if args.quick else bench_cam.LEVELS_QUICK).items():
        lim = AxisLimits.fir_envelope(path.dim, F, D)
        T, Tm = compare(table, name, path, F, D, eps, lim)
        plain_sum, mirror_sum = plain_sum + T, mirror_sum + Tm
        if source is not None:
            compare(table, "  the chords it was fitted to", source, F, D, eps, lim)
    table.row("  programs with arcs, summed", f"{plain_sum:.4f} -> {mirror_sum:.4f} s", f"{mirror_sum / plain_sum:.4f}x plain")
    for name, path in (("cam30", bench_cam.cam30_path()), ("corner90", named_path("corner90")),
                       ("diamond", named_path("diamond")), ("zigzag", named_path("zigzag"))):
        for lim in (None, AxisLimits.fir_envelope(path.dim, F, D)):
            compare(table, name, path, F, D, eps, lim)
    fillets(table)
    table.print()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
