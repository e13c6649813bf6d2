"""FIR cornering on real CAM programs (issue "FIR cornering on real CAM programs").

Usage::

    python benchmarks/bench_cam.py [--quick] [--seed S] [--repeats R] [--no-ocp] [--ocp-budget S]

Benchmark of ``plan_fir`` (Polyline or ToolPath input, lines and arcs) on CAM-like programs. Every
ratio is against a baseline computed in the same run (absolute times on a shared machine mean
little); every target prints PASS or MISS as measured, nothing is tuned to pass.

1. CAM file. A seeded closed 3-D freeform curve (a Fourier curve, perimeter about 175 mm, radius of
   curvature mostly 5-100 mm, gentle z waviness) is machined as a waterline finishing program: the
   same curve at ``LEVELS`` z levels (each 0.2 mm lower and 0.5 % smaller, a drafted cavity), joined
   by short G1 step-downs. Each pass is tessellated into chords of sagitta <= a chord tolerance
   (chord length ``sqrt(8 R tol)`` from the local radius), the tolerance mixed per sector of each
   pass from {1, 2, 5, 10} um (as CAM does with per-surface tolerances). Points are rounded to
   4 decimals (like real posts), written with ``to_gcode`` and read back with ``parse_gcode``.
   Note: one 175 mm curve at 1-10 um sagitta and R = 5-100 mm gives only a few hundred chords,
   so the ~10^4 chords of a real file come from the number of passes, not from tiny chords.

   * FIR cycle time against ``L / F + T_d`` (the lower bound of a constant-feed move).
   * cycle time against eps (must be non-increasing to 1e-9 relative): ``plan_fir`` alone, and the
     envelope ``plan_fir_sweep`` keeps (non-increasing by construction, from the same plans);
     and the rate of seeded random programs (lines; lines and arcs) slower at 1.5 eps, for both,
     and rising anywhere along eps x 1, 1.1, 1.25, 1.5, 2, 3 for plan_fir alone.
   * cycle time against the chord tolerance (same program at 1, 2, 5, 10 um; spread <= 2 %).
   * planning cost per segment (median of ``R`` warm repeats of ``plan_fir`` and its exact profile,
     built by reading it; the first call, compilation included, printed apart) against ruckig on
     the same file: for each chord one
     ``Ruckig(3).calculate`` from the state reached at the chord start (position, velocity, zero
     acceleration) to the chord end with target velocity ``F u_chord`` (zero at the program end),
     default time synchronisation, per-axis limits = the FIR nominal envelope
     (``v = F``, ``a = F / T1``, ``j = F / (T1 T2)``). This is the standard way of following
     waypoints with ruckig (Community version, one waypoint at a time). Target: FIR <= 1x ruckig.
   * the same with ``limits=AxisLimits.fir_envelope(...)`` (limit-holding FIR).

2. FIR / time-optimal OCP on the 30-segment ``cam30`` path of ``research.experiments.optimality``
   (``cam_like_path(30)``; there is no ``named_path("cam30")``), same call as the optimality study
   (``window=10``, ``intervals_per_segment=16``), under the FIR's nominal envelope at this
   benchmark's F, delays and eps. Plain and limit-holding FIR. Target <= 1.10x with limits held.
   On the CAM file the OCP runs in windows of ``CAM_WINDOW`` chords that commit only where the
   braking distance (9 mm here) of their own path is left (``time_optimal(lookahead="braking")``;
   windows of 10 chords with 4 of look-ahead, 2-4 mm, brake in every window: +67 % on the first
   100 chords against the whole-path NLP). Its time is estimated from the file's own first
   ``OCP_PROBE_CHORDS`` chords' IPOPT time per window; it runs on the whole file if the estimate
   is within ``--ocp-budget`` (default ``OCP_BUDGET_S``; the 10^4-chord file needs about 2 h),
   else on the longest of ``OCP_EXCERPTS`` chords from its start that fits, else it is skipped
   with the estimate printed. Plain, limit-holding and mirror pre-compensated FIR
   (``plan_fir_mirror``) on the same chords, the same target. ``--ocp-intervals`` sets the jerk
   intervals per chord (default ``CAM_INTERVALS`` = 16). On the first 100 chords in one NLP N = 2,
   3, 4, 8, 16, 24 give 0.52077, 0.52001, 0.51968, 0.51952, 0.51945, 0.51945 s (N = 4 within
   0.05 %, at a fifth of N = 16's IPOPT time); windowed on the first 1,000 chords N = 4, 8, 16
   give 4.0170, 4.0816, 4.0041 s: each window's IPOPT may end at another local optimum, and the
   windows pass that on, so the windowed OCP is an upper bound that moves by 2 % with N. N = 4
   brings the whole file (500 windows) to about 20 min of IPOPT, ~10x less than N = 16.

3. The issue's part: four G1 lines and one 90 deg G2 arc (R 20 mm) at F 150 mm/s, eps 50 um,
   T 60/30 ms, parsed with ``parse_gcode``: cycle time with the arc as one block and as chords at
   1 and 10 um (``program.blocks.to_polyline(tol)``), and against eps. Target chords(1 um)/arc
   within 5 %.

4. The issue's micro-chord contouring program, rebuilt (the public file is not in the repo):
   185 mm of ``y = 3 sin(x / 15)`` (smallest radius 75 mm) in 16 um chords, rounded to 4 decimals
   of mm and of inch (the inch quantum, 2.54 um, gives the issue's 5-13 deg zigzags), written with
   ``to_gcode`` and read back: cycle time against ``L / F + T_d`` and against a constant feed at
   the crest's eq 8 feed (eps less the rounding's share), and the largest corner error.

A full run takes a few minutes on two cores; ``--quick`` (fewer passes, 3 repeats, no OCP on the
long file) about a minute.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time

import jax
import numpy as np

import research  # noqa: F401  (sets jax_enable_x64)
from research.interpolators import plan_fir, plan_fir_mirror, plan_fir_sweep
from research.interpolators._fir_candidates import envelope
from research.interpolators._fir_feed import arc_feed_caps
from research.limits import AxisLimits
from research.metrics import limit_ratios
from research.optimal._windowing import braking_distance, window_schedule
from research.paths import Polyline
from research.paths.library import random_program
from research.paths.gcode import parse_gcode, to_gcode

# the benchmarks' shared table and timer (same folder)
from bench_fir import TARGET_MEMORY_PER_SEGMENT, Table, one_check, peak_memory, plan_with_profile, timed, verdict

# The benchmark's settings (stated by the issue, not tuned)
FEED = 200.0  # commanded feed F [mm/s]
DELAYS = (0.06, 0.03)  # T1, T2 [s]
EPS = 0.05  # cornering tolerance [mm]
CHORD_TOLS = (1e-3, 2e-3, 5e-3, 1e-2)  # CAM chord tolerances [mm]
LEVELS = 40  # waterline passes of the CAM file (about 10^4 chords)
LEVELS_QUICK = 8
EPS_SWEEP = (10e-3, 20e-3, 30e-3, 50e-3, 75e-3, 100e-3, 150e-3, 200e-3)  # [mm]

# Part 3, the program
PART_FEED = 150.0  # [mm/s]
PART_DELAYS = (0.06, 0.03)
PART_EPS = 0.05
PART_EPS_SWEEP = (30e-3, 50e-3, 75e-3, 100e-3, 150e-3, 200e-3)
PART_GCODE = """G21 G90 G17
G1 X40 Y0 F9000
G1 X40 Y30
G2 X60 Y50 I20 J0
G1 X100 Y50
G1 X100 Y0
M30
"""

# Part 4, the micro-chord contouring program (rebuilt: the public file is not in the repo)
MICRO_LENGTH = 185.0  # [mm] of y = A sin(x / W)
MICRO_CHORD = 0.016  # [mm]
MICRO_A, MICRO_W = 3.0, 15.0  # [mm]; smallest radius of curvature W^2 / A = 75 mm (at the crests)
MICRO_QUANTA = (1e-4, 2.54e-3)  # 4 decimals of mm, 4 decimals of inch [mm]

# Random programs for the eps-monotone rate (the distribution of tests/interpolators/test_fir_cam.py)
RANDOM_PROGRAMS, RANDOM_PROGRAMS_QUICK = 120, 40
RANDOM_EPS_FACTOR = 1.5
RANDOM_EPS_LADDER = (1.0, 1.1, 1.25, 1.5, 2.0, 3.0)  # tests/interpolators/test_fir_monotone.py's FACTORS

# Targets (issue "FIR cornering on real CAM programs")
TARGET_MONOTONE_RTOL = 1e-9
TARGET_CHORD_SPREAD = 0.02
TARGET_VS_RUCKIG = 1.0  # FIR time per segment / ruckig's
BELOW_ENVELOPE = (0.2, 0.05)  # machines whose acceleration and jerk limits are these shares of the FIR's envelope (scenarios)
TARGET_VS_OCP = 1.10
TARGET_ARC_CHORDS = 0.05
OCP_BUDGET_S = 180.0
OCP_PROBE_CHORDS = 60  # the CAM file's first chords, whose OCP windows time the estimate (2 windows)
OCP_EXCERPTS = (1000, 300, 100)  # excerpts from the file's start, the longest within --ocp-budget
CAM_WINDOW = 40  # OCP window on the CAM file [chords]: 34 mm of 0.85 mm chords, room for the 9 mm look-ahead
CAM_INTERVALS = 16  # jerk intervals per chord of the CAM file's OCP (--ocp-intervals; module docstring)


# -- scenario --------------------------------------------------------------------------------------
def freeform_curve(seed: int, n: int = 20001):
    """Dense samples of a seeded closed 3-D Fourier curve: points ``(n, 3)`` [mm] (last = first)."""
    rng = np.random.default_rng(seed)
    th = np.linspace(0.0, 2.0 * np.pi, n)
    r = 28.0 * (1.0 + 0.12 * np.cos(2 * th + rng.uniform(0, 2 * np.pi))
                + 0.06 * np.sin(3 * th + rng.uniform(0, 2 * np.pi))
                + 0.06 * np.cos(5 * th + rng.uniform(0, 2 * np.pi))
                + 0.03 * np.cos(8 * th + rng.uniform(0, 2 * np.pi)))
    z = 1.5 * np.sin(2 * th + rng.uniform(0, 2 * np.pi)) + 0.5 * np.sin(3 * th + rng.uniform(0, 2 * np.pi))
    p = np.column_stack([r * np.cos(th), r * np.sin(th), z])
    p[-1] = p[0]
    return p


def curvature(p: np.ndarray):
    """Arc length ``(n,)`` and curvature ``(n,)`` [1/mm] of dense samples (finite differences)."""
    ds = np.linalg.norm(np.diff(p, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(ds)])
    d1 = np.gradient(p, s, axis=0)
    d2 = np.gradient(d1, s, axis=0)
    k = np.linalg.norm(np.cross(d1, d2), axis=1) / np.linalg.norm(d1, axis=1) ** 3
    return s, k


def tessellate(p: np.ndarray, tol: np.ndarray) -> np.ndarray:
    """Chord vertices of dense samples ``p`` with local sagitta <= ``tol`` (per sample) [mm].

    The chord count density is ``1 / sqrt(8 tol / kappa)`` per mm; vertices are placed where its
    integral crosses an integer (chord ends interpolated linearly on the dense samples).
    """
    s, k = curvature(p)
    dens = np.sqrt(np.maximum(k, 1e-4) / (8.0 * tol))
    cum = np.concatenate([[0.0], np.cumsum(0.5 * (dens[1:] + dens[:-1]) * np.diff(s))])
    m = max(2, int(np.ceil(cum[-1])))
    target = np.linspace(0.0, cum[-1], m + 1)
    idx = np.clip(np.searchsorted(cum, target), 1, len(s) - 1)
    w = ((target - cum[idx - 1]) / (cum[idx] - cum[idx - 1]))[:, None]
    return (1 - w) * p[idx - 1] + w * p[idx]


def cam_program(seed: int, levels: int, chord_tol=None, flat: bool = False) -> tuple[Polyline, dict]:
    """Waterline finishing program: ``levels`` passes of the freeform curve, joined by step-downs.

    ``chord_tol``: one tolerance [mm] for every pass, or ``None`` for the mixed per-sector one;
    ``flat``: each pass at one ``z`` (the curve's waviness left out, as G17 arcs need it).
    Returns the rounded polyline and facts about the curve.
    """
    rng = np.random.default_rng(seed + 1)
    base = freeform_curve(seed)
    if flat:
        base[:, 2] = 0.0
    n = base.shape[0]
    s, k = curvature(base)
    sectors = 8
    chunks = [np.zeros((1, 3))]
    for lev in range(levels):
        p = base * np.array([1 - 0.005 * lev, 1 - 0.005 * lev, 1.0]) - np.array([0.0, 0.0, 0.2 * lev])
        if chord_tol is None:
            per_sector = rng.choice(CHORD_TOLS, sectors)
            tol = per_sector[np.minimum((np.arange(n) * sectors) // n, sectors - 1)]
        else:
            tol = np.full(n, chord_tol)
        chunks.append(tessellate(p, tol))
    pts = np.round(np.vstack(chunks)[1:], 4)  # like real posts
    keep = np.concatenate([[True], np.linalg.norm(np.diff(pts, axis=0), axis=1) > 1e-4])
    pts = pts[keep]
    radius = 1.0 / np.maximum(k, 1e-9)
    info = dict(length=float(s[-1]), r_p5=float(np.percentile(radius, 5)), r_p50=float(np.median(radius)),
                r_p95=float(np.percentile(radius, 95)), r_min=float(radius.min()),
                frac_5_100=float(np.mean((radius >= 5) & (radius <= 100))))
    return Polyline(pts), info


def cam30_path() -> Polyline:
    from research.experiments.optimality import cam_like_path
    return cam_like_path(30)


# -- helpers ---------------------------------------------------------------------------------------
def median_of(repeats: int, fn, *args, **kwargs):
    """``(result, median time [s])`` of ``repeats`` calls (after the caller's warm-up)."""
    times, out = [], None
    for _ in range(repeats):
        out, dt = timed(fn, *args, **kwargs)
        times.append(dt)
    return out, float(np.median(times))


def load() -> str:
    try:
        return "load %.2f %.2f %.2f" % os.getloadavg()
    except OSError:
        return "load n/a"


def progress(msg: str, t0: float) -> None:
    print(f"[{time.perf_counter() - t0:6.1f} s] {msg}  ({load()})", flush=True)


def try_plan(table: Table, label: str, *args, **kwargs):
    """``plan_fir(*args, **kwargs)``, or ``None`` with a RAISED row (the planner is not fixed here)."""
    try:
        return plan_fir(*args, **kwargs)
    except Exception as err:  # reported, not hidden: see benchmarks/README.md
        table.row(label, "RAISED", f"{type(err).__name__}: {err}", "", "MISS")
        print(f"    plan_fir raised on {label.strip()}: {type(err).__name__}: {err}", flush=True)
        return None


def worst_ratio(plan, limits) -> float:
    r = limit_ratios(plan.trajectory(1e-3), limits)
    return max(float(np.max(v)) for v in r.values())


# -- part 1 ----------------------------------------------------------------------------------------
def ruckig_follow(path: Polyline, feed: float, delays):
    """Callable running ruckig chord by chord (see the module docstring); inputs built outside."""
    from ruckig import InputParameter, Result, Ruckig, Trajectory

    T1, T2 = sorted(delays, reverse=True)[:2]
    d = path.dim
    u = path.directions
    targets = [p.tolist() for p in path.points[1:]]
    vels = [(feed * x).tolist() for x in u[:-1]] + [[0.0] * d]
    lim = ([feed] * d, [feed / T1] * d, [feed / (T1 * T2)] * d)
    start = path.points[0].tolist()

    def run():
        otg, inp, traj = Ruckig(d), InputParameter(d), Trajectory(d)
        inp.max_velocity, inp.max_acceleration, inp.max_jerk = lim
        inp.current_position, inp.current_velocity, inp.current_acceleration = start, [0.0] * d, [0.0] * d
        failed, total = 0, 0.0
        for q, v in zip(targets, vels):
            inp.target_position, inp.target_velocity = q, v
            if otg.calculate(inp, traj) != Result.Working:
                failed += 1
            total += traj.duration
            inp.current_position, inp.current_velocity = q, v
        return failed, total

    return run


def bench_cam(args, table: Table, t0: float) -> None:
    levels = LEVELS_QUICK if args.quick else LEVELS
    path, info = cam_program(args.seed, levels)
    text = to_gcode(path, FEED * 60.0)
    prog, t_read = timed(parse_gcode, text, start=tuple(path.points[0]))
    path = prog.polyline
    M = path.n_segments
    Td = float(sum(DELAYS))
    lower = path.length / FEED + Td
    table.section(f"Part 1: CAM file, {levels} waterline passes of a {info['length']:.1f} mm freeform curve, "
                  f"{M} chords, mixed chord tol {[t * 1e3 for t in CHORD_TOLS]} um, F = {FEED:g} mm/s, "
                  f"T = {DELAYS[0] * 1e3:g}/{DELAYS[1] * 1e3:g} ms, eps = {EPS * 1e3:g} um")
    table.row("curve: radius of curvature p5 / p50 / p95 (min)",
              f"{info['r_p5']:.1f} / {info['r_p50']:.1f} / {info['r_p95']:.1f} mm", f"min {info['r_min']:.1f} mm, "
              f"{info['frac_5_100']:.0%} in 5-100 mm")
    seg = path.lengths
    table.row("chords: length min / median / max", f"{seg.min() * 1e3:.0f} / {np.median(seg) * 1e3:.0f} / "
              f"{seg.max() * 1e3:.0f} um", f"program length {path.length:.1f} mm, {len(text) / 1e3:.0f} kB G-code")
    table.row("G-code read (parse_gcode)", f"{t_read * 1e3:.1f} ms", f"{M / t_read:,.0f} lines/s")

    # plain FIR: warm-up (compile) apart, then median of repeats
    progress("part 1: plan_fir warm-up", t0)
    plan, t_cold = timed(plan_with_profile, path, FEED, DELAYS, EPS)  # each plan with its profile built, as ruckig's
    plan, t_fir = median_of(args.repeats, plan_with_profile, path, FEED, DELAYS, EPS)
    T = float(plan.cycle_time)
    table.row("FIR cycle time (refine=True)", f"{T:.4f} s", f"{T / lower:.4f}x L/F + T_d = {lower:.4f} s")
    table.row("  rounds / max corner error / path deviation", f"{plan.rounds}",
              f"{float(np.max(plan.corner_errors)) * 1e3:.1f} um / {float(plan.path_deviation) * 1e3:.1f} um",
              f"<= {EPS * 1e3:g} um (sanity)", "ok" if float(np.max(plan.corner_errors)) <= EPS * (1 + 1e-6) else "OVER")

    # eps sweep
    progress("part 1: eps sweep", t0)
    cts, raised = [], 0
    for e in EPS_SWEEP:
        p = try_plan(table, f"  eps = {e * 1e3:5.0f} um", path, FEED, DELAYS, e)
        if p is None:
            raised += 1
            continue
        cts.append(float(p.cycle_time))
        table.row(f"  eps = {e * 1e3:5.0f} um", f"{cts[-1]:.4f} s",
                  f"{cts[-1] / lower:.4f}x bound, corner max {float(np.max(p.corner_errors)) * 1e3:.1f} um, "
                  f"{p.rounds} rounds")
    worst_rise = max([0.0] + [(b - a) / a for a, b in zip(cts, cts[1:])])
    table.row("cycle time non-increasing in eps, plan_fir alone" + (f" ({raised} eps raised, judged on the rest)" if raised else ""),
              "", f"largest rise {worst_rise:.2e}", f"<= {TARGET_MONOTONE_RTOL:g} rel",
              verdict(worst_rise <= TARGET_MONOTONE_RTOL and not raised))
    env = [cts[i] for i in envelope([np.array([e]) for e in EPS_SWEEP[:len(cts)]], cts)] if not raised else []
    env_rise = max([0.0] + [(b - a) / a for a, b in zip(env, env[1:])])
    table.row("  the same sweep as plan_fir_sweep (envelope, same plans)", "", f"largest rise {env_rise:.2e}",
              f"<= {TARGET_MONOTONE_RTOL:g} rel", verdict(env_rise <= TARGET_MONOTONE_RTOL and not raised))
    random_monotone(args, table, t0)

    # chord tolerance sweep
    progress("part 1: chord tolerance sweep", t0)
    cts_tol = []
    for tol in CHORD_TOLS:
        pt, _ = cam_program(args.seed, levels, chord_tol=tol)
        pt = parse_gcode(to_gcode(pt, FEED * 60.0), start=tuple(pt.points[0])).polyline
        p = try_plan(table, f"  chord tol {tol * 1e3:4.0f} um: {pt.n_segments} chords", pt, FEED, DELAYS, EPS)
        if p is None:
            continue
        cts_tol.append(float(p.cycle_time))
        table.row(f"  chord tol {tol * 1e3:4.0f} um: {pt.n_segments} chords", f"{cts_tol[-1]:.4f} s",
                  f"{cts_tol[-1] / (pt.length / FEED + Td):.4f}x bound, {p.rounds} rounds")
    spread = max(cts_tol) / min(cts_tol) - 1 if cts_tol else float("nan")
    table.row("cycle time spread over chord tolerances (max/min - 1)", "", f"{spread:.2%}",
              f"<= {TARGET_CHORD_SPREAD:.0%}", verdict(len(cts_tol) == len(CHORD_TOLS) and spread <= TARGET_CHORD_SPREAD))

    # planning cost against ruckig
    progress("part 1: planning cost (FIR, ruckig)", t0)
    table.row(f"plan_fir first call (compile + run) / warm median of {args.repeats}", f"{t_cold:.2f} s",
              f"warm {t_fir * 1e3:.1f} ms")
    ours = t_fir / M
    table.row("plan_fir and its exact profile per segment (warm median)", f"{ours * 1e6:.2f} us", load())
    peak = peak_memory(plan_fir, path, FEED, DELAYS, EPS)
    table.row("plan_fir peak traced memory (tracemalloc), per segment", f"{peak / M / 1e3:.2f} kB",
              f"{peak / 1e6:.1f} MB in all", f"<= {TARGET_MEMORY_PER_SEGMENT / 1e3:g} kB",
              verdict(peak / M <= TARGET_MEMORY_PER_SEGMENT))
    timed(plan_with_profile, path, FEED, DELAYS, EPS, refine=False)  # warm-up
    _, t_eq = median_of(args.repeats, plan_with_profile, path, FEED, DELAYS, EPS, refine=False)
    table.row("  for information: plan_fir(refine=False) (eq 13/14 only) and its profile, per segment", f"{t_eq / M * 1e6:.2f} us",
              f"{t_eq / t_fir:.0%} of the verified plan")
    check = one_check(plan, path, EPS)
    check()  # warm-up
    (_, dev_check, _), t_check = median_of(args.repeats, check)
    table.row("  for information: one full check of the plan (profile, vertex errors, path samples), per segment",
              f"{t_check / M * 1e6:.2f} us", f"{t_check / t_fir:.0%} of the verified plan; deviation {dev_check * 1e3:.2f} um")
    try:
        import ruckig
        run = ruckig_follow(path, FEED, DELAYS)
        run()  # warm-up
        (failed, total), t_rk = median_of(args.repeats, run)
        theirs = t_rk / M
        table.row(f"ruckig {ruckig.__version__} chord following, per segment", f"{theirs * 1e6:.2f} us",
                  f"motion {total:.3f} s ({total / lower:.3f}x bound), {failed} not Working")
        table.row("  FIR / ruckig time per segment", "", f"{ours / theirs:.3f}x",
                  f"<= {TARGET_VS_RUCKIG:g}x", verdict(ours / theirs <= TARGET_VS_RUCKIG))
        table.row("  one full check / ruckig time per segment (a floor under plan_fir's ratio)", "",
                  f"{t_check / M / theirs:.3f}x")
    except ImportError as err:
        theirs = None
        table.row(f"ruckig comparison skipped (import failed: {err})")

    # limit-holding FIR
    progress("part 1: limit-holding FIR", t0)
    limits = AxisLimits.fir_envelope(path.dim, FEED, DELAYS)
    pl, t_lcold = timed(plan_with_profile, path, FEED, DELAYS, EPS, limits=limits)
    pl, t_lim = median_of(args.repeats, plan_with_profile, path, FEED, DELAYS, EPS, limits=limits)
    Tl = float(pl.cycle_time)
    table.row("FIR, limits held: cycle time", f"{Tl:.4f} s", f"{Tl / lower:.4f}x bound, {Tl / T:.4f}x plain FIR")
    table.row("  worst limit ratio (plain FIR / limits held)", f"{worst_ratio(plan, limits):.3f} / "
              f"{worst_ratio(pl, limits):.3f}")
    table.row("  first call / warm median", f"{t_lcold:.2f} s", f"warm {t_lim * 1e3:.1f} ms")
    if theirs is not None:
        table.row("  per segment, FIR limits held / ruckig", f"{t_lim / M * 1e6:.2f} us", f"{t_lim / M / theirs:.3f}x",
                  f"<= {TARGET_VS_RUCKIG:g}x", verdict(t_lim / M / theirs <= TARGET_VS_RUCKIG))
    pm, t_mirror = timed(plan_fir_mirror, path, FEED, DELAYS, EPS, limits=limits)
    table.row("FIR mirror pre-compensated (plan_fir_mirror), limits held: cycle time", f"{pm.cycle_time:.4f} s",
              f"{pm.cycle_time / Tl:.4f}x limits held, {pm.cycle_time / lower:.4f}x bound",
              f"path deviation {pm.plan.path_deviation * 1e3:.1f} um, worst limit ratio {worst_ratio(pm.plan, limits):.3f}")
    table.row("  planning (one call)", f"{t_mirror:.2f} s", f"{t_mirror / M * 1e6:.2f} us per segment, "
              f"{t_mirror / t_lim:.1f}x the limit-holding plan ({pm.rounds} rounds)")
    # below the envelope: blocks checked alone, their feeds searched, slow-downs followed along
    # chains, staircases of isolated steps (the feed of a start from rest: min(A T1, J T1 T2))
    for share in BELOW_ENVELOPE:
        below = AxisLimits(limits.velocity, share * limits.acceleration, share * limits.jerk)
        pb, t_below = median_of(min(args.repeats, 3), plan_with_profile, path, FEED, DELAYS, EPS, limits=below)
        Tb = float(pb.cycle_time)
        step = float(np.min(share * limits.acceleration * max(DELAYS)))
        table.row(f"FIR, limits held at {share:g}x the envelope's a and j: cycle time", f"{Tb:.4f} s",
                  f"{Tb / T:.4f}x plain FIR, {path.length / Tb:.1f} mm/s on average (start from rest "
                  f"{step:.1f} mm/s), worst limit ratio {worst_ratio(pb, below):.3f}")
        table.row("  planning, warm median", f"{t_below * 1e3:.1f} ms", f"{t_below / M * 1e6:.2f} us per segment, "
                  f"{t_below / t_fir:.2f}x the plain plan")
    return path


# -- part 2 ----------------------------------------------------------------------------------------
def fir_against(table: Table, path: Polyline, limits: AxisLimits, T_ocp: float, indent: str) -> None:
    """Rows of the plain, limit-holding and mirror pre-compensated FIR on ``path`` against the
    OCP's cycle ``T_ocp`` [s]."""
    plain = plan_fir(path, FEED, DELAYS, EPS)
    held = plan_fir(path, FEED, DELAYS, EPS, limits=limits)
    mirror = plan_fir_mirror(path, FEED, DELAYS, EPS, limits=limits)
    table.row(f"{indent}FIR plain / OCP", f"{float(plain.cycle_time):.4f} s", f"{float(plain.cycle_time) / T_ocp:.4f}x",
              "", f"worst limit ratio {worst_ratio(plain, limits):.3f}")
    r = float(held.cycle_time) / T_ocp
    table.row(f"{indent}FIR limits held / OCP", f"{float(held.cycle_time):.4f} s", f"{r:.4f}x", f"<= {TARGET_VS_OCP:.2f}x",
              verdict(r <= TARGET_VS_OCP) + f" (worst limit ratio {worst_ratio(held, limits):.3f})")
    r = mirror.cycle_time / T_ocp
    table.row(f"{indent}FIR mirror pre-compensated, limits held / OCP", f"{mirror.cycle_time:.4f} s", f"{r:.4f}x",
              f"<= {TARGET_VS_OCP:.2f}x", verdict(r <= TARGET_VS_OCP) + f" (worst limit ratio "
              f"{worst_ratio(mirror.plan, limits):.3f}, path deviation {mirror.plan.path_deviation * 1e3:.1f} um)")


def bench_ocp(args, table: Table, t0: float, cam: Polyline) -> None:
    from research.optimal import time_optimal

    path = cam30_path()
    limits = AxisLimits.fir_envelope(path.dim, FEED, DELAYS)
    table.section(f"Part 2: FIR / time-optimal OCP on cam30 ({path.n_segments} segments, {path.length:.1f} mm), "
                  f"limits = FIR envelope (v {FEED:g}, a {FEED / DELAYS[0]:g}, j {FEED / DELAYS[0] / DELAYS[1]:.4g})")
    progress("part 2: OCP on cam30 (window 10, N = 16)", t0)
    t1 = time.perf_counter()
    res = time_optimal(path, limits, EPS, feed=FEED, window=10, intervals_per_segment=16)
    t_ocp = time.perf_counter() - t1
    T_ocp = float(res.cycle_time)
    table.row("OCP cycle time", f"{T_ocp:.4f} s", f"{res.status}, {len(res.windows)} windows, wall {t_ocp:.1f} s, "
              f"dense check {res.verification.worst_ratio:.4f}")
    fir_against(table, path, limits, T_ocp, "")
    # the windowed OCP on the CAM file: one IPOPT solve per window (window 10, overlap 4), timed on
    # the file's own first windows (its chords take ~4x cam30's IPOPT time a window); the whole file
    # where that fits --ocp-budget, else the longest excerpt from its start that does
    if args.quick:
        table.row(f"windowed OCP on the {cam.n_segments}-chord file", "", "skipped in --quick")
        return
    lim = AxisLimits.fir_envelope(cam.dim, FEED, DELAYS)
    ahead = braking_distance(lim, FEED)
    ocp_kw = dict(feed=FEED, window=CAM_WINDOW, overlap=4, lookahead="braking", intervals_per_segment=args.ocp_intervals)
    probe = time_optimal(Polyline(cam.points[:OCP_PROBE_CHORDS + 1]), lim, EPS, **ocp_kw)
    per_window = probe.solve_time / len(probe.windows)

    def windows(n):
        return len(window_schedule(n, CAM_WINDOW, 4, cam.lengths[:n], ahead))

    for n in (cam.n_segments,) + tuple(k for k in OCP_EXCERPTS if k < cam.n_segments):
        estimate = per_window * windows(n)
        if estimate <= args.ocp_budget:
            break
    else:
        table.row(f"windowed OCP on the {cam.n_segments}-chord file skipped", "",
                  f"estimated {per_window * windows(cam.n_segments):.0f} s ({per_window:.2f} s a window on its first "
                  f"{OCP_PROBE_CHORDS} chords) > --ocp-budget {args.ocp_budget:.0f} s")
        return
    part = cam if n == cam.n_segments else Polyline(cam.points[:n + 1])
    label = f"the {n}-chord file" if n == cam.n_segments else f"its first {n} chords"
    progress(f"part 2: windowed OCP on {label} (window {CAM_WINDOW}, look-ahead {ahead:g} mm, estimated "
             f"{estimate:.0f} s)", t0)
    t1 = time.perf_counter()
    ocp = time_optimal(part, lim, EPS, **ocp_kw)
    wall = time.perf_counter() - t1
    T_part = float(ocp.cycle_time)
    table.row(f"OCP on {label} (window {CAM_WINDOW}, braking look-ahead {ahead:g} mm, N = {args.ocp_intervals})",
              f"{T_part:.4f} s",
              f"{ocp.status}, {len(ocp.windows)} windows, wall {wall:.0f} s (estimated {estimate:.0f} s), dense check "
              f"{ocp.verification.worst_ratio:.4f}")
    fir_against(table, part, lim, T_part, "  ")


# -- part 3 ----------------------------------------------------------------------------------------
def random_monotone(args, table: Table, t0: float) -> None:
    """Rate of random programs slower at a looser eps: ``RANDOM_EPS_FACTOR`` eps (plan_fir alone and
    plan_fir_sweep), and anywhere along eps x ``RANDOM_EPS_LADDER`` (plan_fir alone); the planning
    time of these plan_fir calls (mean per call, compilation of new shapes included)."""
    n = RANDOM_PROGRAMS_QUICK if args.quick else RANDOM_PROGRAMS
    progress(f"part 1: {n} random programs at eps x {RANDOM_EPS_LADDER}", t0)
    rng = np.random.default_rng(args.seed + 7)
    rows = {False: [], True: []}
    t_plan, n_plan = 0.0, 0
    for i in range(n):
        tp = random_program(rng, arcs=i % 2 == 1)
        eps, feed = float(np.exp(rng.uniform(np.log(0.005), np.log(0.5)))), float(rng.uniform(20.0, 300.0))
        sw = plan_fir_sweep(tp, feed, DELAYS, (eps, RANDOM_EPS_FACTOR * eps))
        own, kept = sw.own_cycle_times, sw.cycle_times
        a = time.perf_counter()
        ladder = np.array([float(plan_fir(tp, feed, DELAYS, f * eps).cycle_time) for f in RANDOM_EPS_LADDER])
        t_plan, n_plan = t_plan + time.perf_counter() - a, n_plan + len(RANDOM_EPS_LADDER)
        rows[i % 2 == 1].append((own[1] / own[0] - 1.0, kept[1] / kept[0] - 1.0, float(np.max(ladder[1:] / ladder[:-1] - 1.0))))
    for arcs, r in rows.items():
        r = np.asarray(r)
        slow_own, slow_env, slow_lad = (r[:, c] > TARGET_MONOTONE_RTOL for c in range(3))
        label = "lines and arcs" if arcs else "lines"
        table.row(f"  random programs ({label}), slower at {RANDOM_EPS_FACTOR:g} eps",
                  f"plan_fir {int(slow_own.sum())}/{len(r)}", f"largest {max(r[:, 0].max(), 0.0):.2%}; "
                  f"plan_fir_sweep {int(slow_env.sum())}/{len(r)}", "0", verdict(not slow_own.any()))
        table.row(f"  random programs ({label}), rising anywhere on eps x {RANDOM_EPS_LADDER}",
                  f"plan_fir {int(slow_lad.sum())}/{len(r)}", f"largest {max(r[:, 2].max(), 0.0):.2%}", "0",
                  verdict(not slow_lad.any()))
    table.row("  plan_fir on these programs, mean per call", f"{t_plan / n_plan * 1e3:.1f} ms", f"{n_plan} calls")


def micro_program(quantum: float) -> Polyline:
    """The issue's contouring program rebuilt: ``y = A sin(x / W)`` cut into chords of
    ``MICRO_CHORD`` of arc length over ``MICRO_LENGTH``, coordinates rounded to ``quantum``, written
    with ``to_gcode`` and read back with ``parse_gcode``."""
    xf = np.linspace(0.0, MICRO_LENGTH + 10.0, 400001)
    s = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(xf), np.diff(MICRO_A * np.sin(xf / MICRO_W))))])
    x = np.interp(np.arange(0.0, MICRO_LENGTH + 1e-9, MICRO_CHORD), s, xf)
    pts = np.round(np.column_stack([x, MICRO_A * np.sin(x / MICRO_W)]) / quantum) * quantum
    text = to_gcode(Polyline.from_points(pts, merge_duplicates=True), FEED * 60.0)
    return parse_gcode(text, start=(pts[0, 0], pts[0, 1], 0.0)).polyline


def bench_micro(args, table: Table, t0: float) -> None:
    table.section(f"Part 4: the issue's micro-chord program: {MICRO_LENGTH:g} mm of y = {MICRO_A:g} sin(x / {MICRO_W:g}) "
                  f"in {MICRO_CHORD * 1e3:g} um chords, rounded, F = {FEED:g} mm/s, eps = {EPS * 1e3:g} um")
    Td = float(sum(DELAYS))
    r_min = MICRO_W ** 2 / MICRO_A
    for q in MICRO_QUANTA:
        progress(f"part 4: quantum {q * 1e3:g} um", t0)
        path = micro_program(q)
        u = path.directions
        turn = np.degrees(np.arccos(np.clip(np.sum(u[1:] * u[:-1], axis=1), -1.0, 1.0)))
        plan, t_plan = timed(plan_fir, path, FEED, DELAYS, EPS)
        T, L = float(plan.cycle_time), path.length
        # constant feed at the crest's eq 8 feed, eps less what the rounding can move a vertex and
        # the average of the input (|delta| <= q / sqrt(2) each): a plan of about that time is feasible
        f8 = float(arc_feed_caps(np.array([r_min]), np.asarray(DELAYS), np.array([EPS - np.sqrt(2.0) * q]), np.array([FEED]))[0])
        table.row(f"  rounded to {q * 1e3:g} um: {path.n_segments} chords, turns p50 / p95 / max",
                  f"{np.percentile(turn, 50):.2f} / {np.percentile(turn, 95):.2f} / {turn.max():.2f} deg",
                  f"plan {t_plan:.1f} s (cold), {plan.rounds} rounds")
        table.row(f"  rounded to {q * 1e3:g} um: cycle time", f"{T:.4f} s",
                  f"{T / (L / FEED + Td):.3f}x L/F + T_d; {T / (L / f8 + Td):.3f}x L/F8(R {r_min:g}) + T_d "
                  f"(F8 {f8:.1f} mm/s); corner max {float(np.max(plan.corner_errors)) * 1e3:.2f} um")


def bench_part(args, table: Table, t0: float) -> None:
    progress("part 3: lines + arc part", t0)
    prog, t_read = timed(parse_gcode, PART_GCODE)
    blocks, feeds = prog.blocks, np.asarray(prog.block_feeds)
    table.section(f"Part 3: the issue's part, 4 G1 + one 90 deg G2 (R 20 mm), F = {PART_FEED:g} mm/s, "
                  f"eps = {PART_EPS * 1e3:g} um, T = {PART_DELAYS[0] * 1e3:g}/{PART_DELAYS[1] * 1e3:g} ms")
    table.row("blocks / arcs / length", f"{blocks.n_blocks} / {int(blocks.is_arc.sum())}",
              f"{blocks.length:.3f} mm, feeds {sorted(set(feeds.tolist()))} mm/s, read {t_read * 1e3:.1f} ms")
    arc = plan_fir(blocks, feeds, PART_DELAYS, PART_EPS)
    T_arc = float(arc.cycle_time)
    lower = blocks.length / PART_FEED + sum(PART_DELAYS)
    table.row("arc as one block: cycle time", f"{T_arc:.4f} s",
              f"{T_arc / lower:.4f}x L/F + T_d, corner max {float(np.max(arc.corner_errors)) * 1e3:.1f} um, "
              f"path deviation {float(arc.path_deviation) * 1e3:.1f} um")
    for tol in (1e-3, 1e-2):
        pl, idx = blocks.to_polyline(tol)
        ch = plan_fir(pl, feeds[idx], PART_DELAYS, PART_EPS)
        r = float(ch.cycle_time) / T_arc
        is_target = tol == 1e-3
        table.row(f"arc as chords at {tol * 1e3:g} um ({pl.n_segments - 4} chords): cycle time",
                  f"{float(ch.cycle_time):.4f} s", f"chords / arc {r:.4f}",
                  f"within {TARGET_ARC_CHORDS:.0%}" if is_target else "",
                  verdict(abs(r - 1) <= TARGET_ARC_CHORDS) if is_target else "")
    cts = []
    for e in PART_EPS_SWEEP:
        p = plan_fir(blocks, feeds, PART_DELAYS, e)
        cts.append(float(p.cycle_time))
        table.row(f"  arc block, eps = {e * 1e3:5.0f} um", f"{cts[-1]:.4f} s",
                  f"corner max {float(np.max(p.corner_errors)) * 1e3:.1f} um")
    rise = max(0.0, *[(b - a) / a for a, b in zip(cts, cts[1:])])
    table.row("  non-increasing in eps", "", f"largest rise {rise:.2e}", f"<= {TARGET_MONOTONE_RTOL:g} rel",
              verdict(rise <= TARGET_MONOTONE_RTOL))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help=f"{LEVELS_QUICK} passes, 3 repeats (about a minute)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--repeats", type=int, default=None, help="warm repeats (median), default 7 (3 with --quick)")
    ap.add_argument("--no-ocp", action="store_true", help="skip part 2")
    ap.add_argument("--ocp-budget", type=float, default=OCP_BUDGET_S,
                    help=f"seconds the windowed OCP on the CAM file may take (estimated; default {OCP_BUDGET_S:g}: "
                         "the whole 10^4-chord file needs about 2 h)")
    ap.add_argument("--ocp-intervals", type=int, default=CAM_INTERVALS,
                    help=f"jerk intervals per chord of the CAM file's OCP (default {CAM_INTERVALS}; 4 solves ~10x "
                         "faster, +0.32 %% on the first 1,000 chords, see the module docstring)")
    args = ap.parse_args(argv)
    args.repeats = args.repeats or (3 if args.quick else 7)
    cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    print(f"python {platform.python_version()}, numpy {np.__version__}, jax {jax.__version__} "
          f"({jax.default_backend()}), {cpus} CPUs, {load()} at start")
    t0 = time.perf_counter()
    table = Table("bench_cam: FIR cornering on CAM programs (issue 'FIR cornering on real CAM programs')")
    cam = bench_cam(args, table, t0)
    if not args.no_ocp:
        bench_ocp(args, table, t0, cam)
    bench_part(args, table, t0)
    bench_micro(args, table, t0)
    table.print()
    print(f"{load()} at end; total benchmark time {time.perf_counter() - t0:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
