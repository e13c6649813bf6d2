"""Speed of the FIR-overlap interpolator (Sencer 2015) against baselines measured in the same run.

Usage::

    python benchmarks/bench_fir.py [--segments N] [--seed S] [--quick] [--repeats R]

What is measured (every figure is reported as a ratio against a baseline timed in the same process,
because absolute times on a shared machine mean little):

1. Trajectory generation throughput. A seeded CAM-like 3-D path of ``N`` (default 10^4) short
   ``G1`` segments (random walk of headings with small turns, lengths 0.2-2 mm, like CAM output
   for a freeform surface) is written with ``to_gcode`` and read back with ``parse_gcode`` (timed
   separately, so the reader is in the chain), then interpolated by ``fir_interpolate`` (planning
   + exact sampling) at ``Ts`` = 1 ms, feed 200 mm/s, delays ``T1`` = 148 ms, ``T2`` = 89 ms
   (Sencer 2015 §4) and cornering tolerance 0.05 mm. JIT compile time (first call) is reported
   apart from warm runs (best of ``R`` repeats).

   * "x real time" = motion duration / compute time.           Target >= 10^4.
   * Speed ratio against ``fir_by_convolution`` (the straightforward ``np.convolve`` chain with
     148 and 89 taps on the same schedule) = convolution time / our time.  Target >= 100.
   * Sanity: max |q_ours - q_convolution| over the grid, expected O(Ts^2) (printed with the scale
     ``(F / T_min) Ts^2``).

2. Per-segment planning cost against ruckig (optional dependency; skipped if not importable).
   Ours: warm ``plan_fir(path, F, delays, tol)`` time / N. Ruckig: one offline
   ``Ruckig(3).calculate(InputParameter, Trajectory)`` per segment, rest to rest from the segment's
   start to its end (exact stop), with the FIR's nominal per-axis envelope as limits:
   ``v = F |u_axis|``, ``a = F |u_axis| / T1``, ``j = F |u_axis| / (T1 T2)`` and phase
   synchronisation (a straight G01 line); the default time synchronisation is shown for
   information. Target: ours <= ruckig per segment (speed ratio t_ruckig / t_ours >= 1), judged
   for the paper's planning (``refine=False``: eq 13/14 overlaps and the exact profile, read
   once so that it is built, the like-for-like counterpart of a ruckig profile) and for the
   verified plan (which also measures every corner's error on the profile and repairs
   interacting corners). Ruckig's inputs (per-segment limits as lists, :func:`ruckig_rows`) are
   made outside its timing, and a path keeps its analysis between plans (its blocks, tangents,
   pulse table, straight runs): both sides plan from prepared inputs. The paper's planning is
   also judged on a path's first plan (its analysis in the timing) against ruckig with its
   inputs made from a path not read before (``ruckig_rows`` in the timing). One full check of the
   verified plan (:func:`one_check`: its profile, vertex errors and certified path samples, from
   scratch) is timed as well: ruckig's time over it is a ceiling on the verified plan's ratio.

Targets: issue "Core pipeline" §8. Each target line prints PASS or MISS as measured; nothing is
tuned to make them pass. When a target is missed, the "where the time goes" block splits the warm
``fir_interpolate`` time into planning (``plan_fir``; the number and cost of its exact-profile
builds) and sampling (``FIRPlan.trajectory``), and times the corner-error search
(``corner_distances``) on its own.

A full run (10^4 segments, best of 5) takes about 20 s on two cores, a few seconds of it JIT
compilation; ``--quick`` uses 2000 segments and two repeats.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time

import jax
import jax.numpy as jnp
import numpy as np

import research  # noqa: F401  (sets jax_enable_x64)
from research.interpolators import fir as fir_module
from research.interpolators import fir_by_convolution, fir_interpolate, plan_fir
from research.paths import Polyline
from research.paths.gcode import parse_gcode, to_gcode

# Scenario (Sencer 2015 §4 delays; CAM-like freeform finishing pass)
TS = 1e-3  # interpolation period [s]
FEED = 200.0  # commanded feed F [mm/s] (12 m/min)
DELAYS = (0.148, 0.089)  # T1, T2 [s], Sencer 2015 §4
TOLERANCE = 0.05  # cornering tolerance epsilon [mm]
SEGMENT_LENGTHS = (0.2, 2.0)  # [mm]

# Targets, issue "Core pipeline" §8
TARGET_REAL_TIME = 1e4  # x real time
TARGET_VS_CONVOLUTION = 100.0  # convolution time / our time
TARGET_VS_RUCKIG = 1.0  # ruckig per-segment time / ours
TARGET_MEMORY_PER_SEGMENT = 1e3  # bytes of peak planning memory per segment (issue 19 item 4)


# -- scenario --------------------------------------------------------------------------------------
def cam_path(n_segments: int, seed: int) -> Polyline:
    """Seeded 3-D freeform-like tool path of short G1 segments.

    Heading: random walk with N(0, 2 deg) turns per segment; pitch: mean-reverting random walk kept
    within about +-15 deg (a surface that rises and falls gently); lengths uniform in 0.2-2 mm.
    Turning angles are a few degrees, as in CAM output of a smooth surface.
    """
    rng = np.random.default_rng(seed)
    lengths = rng.uniform(*SEGMENT_LENGTHS, n_segments)
    heading = np.cumsum(rng.normal(0.0, np.radians(2.0), n_segments))
    pitch = np.zeros(n_segments)
    steps = rng.normal(0.0, np.radians(1.0), n_segments)
    for k in range(1, n_segments):
        pitch[k] = 0.97 * pitch[k - 1] + steps[k]
    u = np.column_stack([np.cos(pitch) * np.cos(heading), np.cos(pitch) * np.sin(heading), np.sin(pitch)])
    points = np.vstack([np.zeros((1, 3)), np.cumsum(lengths[:, None] * u, axis=0)])
    return Polyline(points)


# -- timing helpers --------------------------------------------------------------------------------
def timed(fn, *args, **kwargs):
    """``(result, seconds)`` of one call, waiting for JAX arrays in the result."""
    t0 = time.perf_counter()
    out = jax.block_until_ready(fn(*args, **kwargs))
    return out, time.perf_counter() - t0


def peak_memory(fn, *args, **kwargs) -> int:
    """Peak bytes traced by ``tracemalloc`` (Python objects and NumPy buffers, not XLA's own
    buffers) during one call, above what was allocated before it."""
    import tracemalloc

    tracemalloc.start()
    try:
        base = tracemalloc.get_traced_memory()[0]
        jax.block_until_ready(fn(*args, **kwargs))
        return tracemalloc.get_traced_memory()[1] - base
    finally:
        tracemalloc.stop()


def load() -> str:
    """The machine's load averages (1, 5, 15 min), for the record."""
    try:
        return "load %.2f %.2f %.2f" % os.getloadavg()
    except OSError:
        return "load n/a"


def best_of(repeats: int, fn, *args, **kwargs):
    """``(result of the last call, best time [s])`` over ``repeats`` calls."""
    best, out = np.inf, None
    for _ in range(repeats):
        out, dt = timed(fn, *args, **kwargs)
        best = min(best, dt)
    return out, best


# -- table -----------------------------------------------------------------------------------------
class Table:
    """Fixed-width text table: measurement | value | ratio / rate | target | verdict."""

    def __init__(self, title: str):
        self.title = title
        self.rows: list[tuple[str, str, str, str, str]] = []

    def row(self, name: str, value: str = "", ratio: str = "", target: str = "", verdict: str = ""):
        self.rows.append((name, value, ratio, target, verdict))

    def section(self, name: str):
        self.rows.append((name, None, None, None, None))

    def print(self):
        head = ("measurement", "value", "ratio / rate", "target", "")
        body = [r for r in self.rows if r[1] is not None]
        w = [max(len(str(r[i])) for r in [head, *body]) for i in range(5)]
        line = "-" * (sum(w) + 3 * 4)
        print(f"\n{self.title}\n{line}")
        print(" | ".join(h.ljust(w[i]) for i, h in enumerate(head)).rstrip())
        print(line)
        for r in self.rows:
            if r[1] is None:
                print(r[0])
            else:
                print(" | ".join(str(c).ljust(w[i]) for i, c in enumerate(r)).rstrip())
        print(line)


def verdict(ok: bool) -> str:
    return "PASS" if ok else "MISS"


# -- part 1 ----------------------------------------------------------------------------------------
def bench_throughput(path: Polyline, repeats: int, table: Table) -> dict:
    """G-code round trip, fir_interpolate (cold / warm), convolution baseline, accuracy."""
    M = path.n_segments
    table.section(f"Part 1: trajectory generation, {M} segments, Ts = {TS * 1e3:g} ms, F = {FEED:g} mm/s, "
                  f"T1/T2 = {DELAYS[0] * 1e3:g}/{DELAYS[1] * 1e3:g} ms, eps = {TOLERANCE:g} mm")

    # G-code writer and reader in the chain (the program is read back to the identical vertices)
    text, t_write = best_of(repeats, to_gcode, path, FEED * 60.0)
    prog, t_read = best_of(repeats, parse_gcode, text, start=tuple(path.points[0]))
    if not np.array_equal(prog.polyline.points, path.points):
        raise RuntimeError("to_gcode -> parse_gcode round trip changed the vertices")
    path, feeds = prog.polyline, np.asarray(prog.feeds)  # feeds [mm/s], one per segment

    # ours: first call compiles, then best of warm repeats
    traj, t_cold = timed(fir_interpolate, path, feeds, DELAYS, TOLERANCE, TS)
    traj, t_ours = best_of(repeats, fir_interpolate, path, feeds, DELAYS, TOLERANCE, TS)
    duration = float(traj.duration)
    n = traj.n_samples
    real_time = duration / t_ours

    # baseline: np.convolve with 148 + 89 taps on the same schedule
    plan = plan_fir(path, feeds, DELAYS, TOLERANCE)
    (t_conv, q_conv), t_baseline = best_of(repeats, fir_by_convolution, plan, path, TS)
    speedup = t_baseline / t_ours
    q = np.asarray(traj.q)
    k = min(n, q_conv.shape[0])
    diff = float(np.max(np.abs(q[:k] - q_conv[:k])))
    tail = float(np.max(np.abs(q_conv[k - 1:] - path.points[-1])))  # convolution's samples past ours
    scale = FEED / min(DELAYS) * TS**2  # peak acceleration * Ts^2

    table.row("G-code write (to_gcode)", f"{t_write * 1e3:.1f} ms", f"{M / t_write:,.0f} lines/s")
    table.row("G-code read (parse_gcode)", f"{t_read * 1e3:.1f} ms",
              f"{M / t_read:,.0f} lines/s, {duration / t_read:,.0f}x real time")
    table.row("motion: duration / samples", f"{duration:.2f} s", f"{n:,} samples "
              f"(mean speed {path.length / duration:.1f} mm/s)")
    table.row("fir_interpolate cold (JIT compile + run)", f"{t_cold:.3f} s",
              f"compile ~{t_cold - t_ours:.2f} s")
    table.row(f"fir_interpolate warm (best of {repeats})", f"{t_ours * 1e3:.1f} ms", f"{n / t_ours:,.0f} samples/s")
    table.row("  x real time (duration / warm time)", "", f"{real_time:,.0f}x",
              f">= {TARGET_REAL_TIME:,.0f}x", verdict(real_time >= TARGET_REAL_TIME))
    table.row(f"fir_by_convolution (np.convolve {round(DELAYS[0] / TS)}+{round(DELAYS[1] / TS)} taps)",
              f"{t_baseline * 1e3:.1f} ms", f"{q_conv.shape[0] / t_baseline:,.0f} samples/s")
    table.row("  speed ratio ours / convolution (t_conv / t_ours)", "", f"{speedup:.2f}x",
              f">= {TARGET_VS_CONVOLUTION:g}x", verdict(speedup >= TARGET_VS_CONVOLUTION))
    table.row("  max |q_ours - q_conv| (sanity, O(Ts^2))", f"{diff:.2e} mm",
              f"scale (F/T_min) Ts^2 = {scale:.1e} mm", "", "ok" if diff <= scale else "LARGE")
    table.row("  convolution end point error", f"{tail:.1e} mm")
    return dict(path=path, feeds=feeds, t_ours=t_ours, plan=plan, duration=duration,
                misses=real_time < TARGET_REAL_TIME or speedup < TARGET_VS_CONVOLUTION)


def bench_breakdown(path: Polyline, feeds, plan, t_ours: float, repeats: int, table: Table) -> None:
    """Where the warm fir_interpolate time goes: planning (profile builds) vs sampling."""
    table.section("Where the time goes (warm, best of repeats; shares of the warm fir_interpolate time)")
    _, t_plan = best_of(repeats, plan_fir, path, feeds, DELAYS, TOLERANCE)
    _, t_sample = best_of(repeats, plan.trajectory, TS)
    table.row("plan_fir (overlaps + exact profile + verification)", f"{t_plan * 1e3:.1f} ms",
              f"{t_plan / t_ours:.0%}")

    # count and time the exact-profile builds inside plan_fir's rounds (private helper, NumPy/Numba;
    # skipped if renamed)
    builder = getattr(fir_module, "_fir_profile", None)
    build = getattr(builder, "profile", None)
    if build is not None:
        calls: list[float] = []

        def counted(*args):
            out, dt = timed(build, *args)
            calls.append(dt)
            return out

        per_run: list[list[float]] = []
        builder.profile = counted
        try:
            for _ in range(repeats):
                calls.clear()
                plan_fir(path, feeds, DELAYS, TOLERANCE)
                per_run.append(list(calls))
        finally:
            builder.profile = build
        calls = min(per_run, key=sum)  # the fastest run, like best_of
        table.row(f"  exact-profile builds (_fir_profile.profile): {len(calls)} calls", f"{sum(calls) * 1e3:.1f} ms",
                  f"{sum(calls) / t_ours:.0%} ({np.mean(calls) * 1e3:.1f} ms each)")

    # the corner-error search on its own, on the plan's real corners
    Td = float(np.sum(DELAYS))
    centre = plan.corner_times
    vertices = jnp.asarray(path.points[1:-1])
    search = jax.jit(fir_module.corner_distances)
    timed(search, plan.position, vertices, centre, 0.5 * Td)  # compile
    _, t_search = best_of(repeats, search, plan.position, vertices, centre, 0.5 * Td)
    # plan_fir pads the path to a bucket size: 2 breaks per padded segment, doubled by each filter
    padded = plan.position.breaks.shape[0] // (2 * 2 ** len(DELAYS))
    table.row(f"  corner_distances alone ({path.n_segments - 1} real corners)", f"{t_search * 1e3:.1f} ms",
              f"{t_search / t_ours:.0%} (once per verification round)")
    table.row("  profile pieces K / segments after padding", f"{plan.position.coeffs.shape[0]:,}",
              f"{padded:,} padded segments (real: {path.n_segments:,})")
    table.row("sampling (FIRPlan.trajectory, q v a j)", f"{t_sample * 1e3:.1f} ms", f"{t_sample / t_ours:.0%}")
    rest = t_ours - t_plan - t_sample  # difference of best-of times: can come out below noise
    table.row("rest (Trajectory checks, host copies, dispatch)",
              f"{rest * 1e3:.1f} ms" if rest > 0 else "below noise", f"{rest / t_ours:.0%}" if rest > 0 else "")


# -- part 2 ----------------------------------------------------------------------------------------
def ruckig_rows(path: Polyline, feeds) -> list:
    """Ruckig's inputs for every segment of ``path``, rest to rest from its start to its end:
    ``(start, end, v, a, j)`` lists [mm, mm/s, mm/s^2, mm/s^3] with the FIR's nominal per-axis
    envelope ``v = F |u_axis|``, ``a = v / T1``, ``j = v / (T1 T2)`` as limits (NumPy on the whole
    path, one ``tolist`` per array)."""
    T1, T2 = DELAYS
    v = np.asarray(feeds, dtype=np.float64)[:, None] * np.abs(path.directions)
    points = path.points
    return list(zip(points[:-1].tolist(), points[1:].tolist(), v.tolist(), (v / T1).tolist(),
                    (v / (T1 * T2)).tolist()))


def unread_copies(path: Polyline, n: int):
    """An iterator over ``n`` new polylines of ``path``'s points, made here (outside any timing):
    paths that no plan has read, so none holds an analysis kept from an earlier plan."""
    return iter([Polyline(path.points.copy(), path.axes) for _ in range(n)])


def plan_with_profile(*args, **kwargs):
    """``plan_fir(*args, **kwargs)`` with its exact profile built: a plan builds its profile's
    coefficients on first read (``FIRPlan.position``), and ruckig's ``calculate`` makes its
    profile, so what the ruckig comparisons time holds one on both sides."""
    plan = plan_fir(*args, **kwargs)
    plan.position
    return plan


def one_check(plan, path: Polyline, tolerance: float, check_period: float = fir_module.CHECK_PERIOD):
    """A callable that runs one full verification pass of the verified ``plan`` of ``path`` as
    ``plan_fir``'s rounds do (``_fir_settle``), from scratch (no earlier check to reuse): its exact
    profile built from its inputs, every vertex error and every path sample every ``check_period``
    [s], bounded between samples (``_fir_certify``), against ``tolerance`` [mm] up to the profile's
    rounding. ``plan_fir`` runs at least one such pass for the plan it returns, so its time is a
    floor under the verified planner's own (its look-ahead, other candidates and repair rounds come
    on top), and ruckig's time over it a ceiling on any ratio a plan checked this way can reach.
    The callable returns ``(largest vertex error [mm], largest sampled deviation [mm], path
    samples)``.

    Raises:
        ValueError: the plan was made on another pulse table than the path's own (its straight
            runs planned as one block each), whose blocks are not the path's.
    """
    from research.interpolators import _fir_profile
    from research.interpolators._fir_verify import RoundChecks, profile_rounding
    from research.piecewise import NumpyPiecewise

    inputs = plan.profile
    tab = inputs.pieces.table
    tp = fir_module._as_toolpath(path)
    M = tp.n_blocks
    if tab.first_motion.size != M:
        raise ValueError(f"one_check: the plan's pulse table has {tab.first_motion.size} blocks, the path {M}")
    durations = inputs.durations()
    tol = np.full(M, float(tolerance))
    Td = float(np.sum(inputs.delays))

    def run():
        starts, _, breaks, coeffs, centre = _fir_profile.profile(inputs.start, tab.geo, tab.block, tab.gap,
                                                                 inputs.fraction, inputs.piece_tv, inputs.gaps,
                                                                 inputs.delays, tab.joins)
        position = NumpyPiecewise(breaks, coeffs)
        checks = RoundChecks(tp, tol, tab.block, Td, check_period, tab.fraction, tab.joins)
        checks.slack = profile_rounding(position, tp.ends[-1])
        errors = checks.vertices(position, starts[:M], centre[: M - 1], durations, True)
        deviation, _, _ = checks.samples_check(certify=True)
        return float(np.max(errors, initial=0.0)), deviation, checks.samples

    return run


def bench_planning(path: Polyline, feeds, repeats: int, table: Table) -> None:
    """Per-segment planning cost: plan_fir against ruckig exact-stop segments."""
    M = path.n_segments
    table.section(f"Part 2: per-segment planning cost, {M} segments")
    plan, t_plan = best_of(repeats, plan_with_profile, path, feeds, DELAYS, TOLERANCE)
    _, t_plan_eq = best_of(repeats, plan_with_profile, path, feeds, DELAYS, TOLERANCE, refine=False)
    # the same on a path not planned before: its analysis (blocks, tangents, pulse table,
    # straight runs), made once per path and kept for every later plan of it, is in the timing
    fresh = unread_copies(path, repeats)
    _, t_plan_fresh = best_of(repeats, lambda: plan_with_profile(next(fresh), feeds, DELAYS, TOLERANCE, refine=False))
    ours = t_plan / M
    table.row("plan_fir (warm) and its exact profile, per segment", f"{ours * 1e6:.2f} us", load())
    peak = peak_memory(plan_fir, path, feeds, DELAYS, TOLERANCE)
    table.row("plan_fir peak traced memory (tracemalloc), per segment", f"{peak / M / 1e3:.2f} kB",
              f"{peak / 1e6:.1f} MB in all", f"<= {TARGET_MEMORY_PER_SEGMENT / 1e3:g} kB",
              verdict(peak / M <= TARGET_MEMORY_PER_SEGMENT))
    table.row("plan_fir(refine=False) (eq 13/14 only) and its exact profile, per segment", f"{t_plan_eq / M * 1e6:.2f} us",
              f"{t_plan_eq / t_plan:.0%} of full plan")
    table.row("  the same, first plan of the path (its analysis included), per segment",
              f"{t_plan_fresh / M * 1e6:.2f} us", f"{t_plan_fresh / t_plan_eq:.2f}x the later plans'")
    try:
        import ruckig
    except ImportError as err:  # optional dependency
        table.row(f"ruckig comparison skipped (import failed: {err})")
        return

    from ruckig import InputParameter, Result, Ruckig, Synchronization, Trajectory

    rows = ruckig_rows(path, feeds)  # built outside the timing
    # ruckig's counterpart of a path's first plan: its inputs made from a path not read before
    fresh = unread_copies(path, repeats)
    _, t_rows = best_of(repeats, lambda: len(ruckig_rows(next(fresh), feeds)))  # (timed blocks on a result's leaves)
    table.row("ruckig's inputs made from the path (ruckig_rows), per segment", f"{t_rows / M * 1e6:.2f} us", "")

    # the verified plan's floor: one full check of the plan it returns, from scratch
    (_, deviation, samples), t_check = best_of(repeats, one_check(plan, path, TOLERANCE))
    table.row("one full check of the verified plan (profile, vertex errors, certified path samples), per segment",
              f"{t_check / M * 1e6:.2f} us",
              f"{samples} samples, deviation {deviation * 1e3:.2f} um (the plan's {plan.path_deviation * 1e3:.2f})")

    def ruckig_loop(sync):
        otg, inp, traj = Ruckig(path.dim), InputParameter(path.dim), Trajectory(path.dim)
        inp.synchronization = sync
        failed, total = 0, 0.0
        for p, q, v, a, j in rows:  # from rest at the segment start to rest at its end
            inp.current_position, inp.target_position = p, q
            inp.max_velocity, inp.max_acceleration, inp.max_jerk = v, a, j
            if otg.calculate(inp, traj) != Result.Working:
                failed += 1
            total += traj.duration
        return failed, total

    for label, sync, is_target in (("phase sync, straight G01", Synchronization.Phase, True),
                                   ("default time sync", Synchronization.Time, False)):
        (failed, total), t_rk = best_of(repeats, ruckig_loop, sync)
        theirs = t_rk / M
        note = f" ({failed} failed)" if failed else ""
        table.row(f"ruckig {ruckig.__version__} exact stop, {label}, per segment", f"{theirs * 1e6:.2f} us",
                  f"exact-stop motion {total:.1f} s{note}")
        # Like for like: ruckig plans each block and its profile, as plan_fir(refine=False) does
        # (eq 13/14 overlaps + the exact profile); the verified plan also measures every corner's
        # error on the profile and repairs interacting corners, which ruckig has no counterpart for.
        # The path's first plan against ruckig with its inputs made from the same path: each side
        # then reads the path once.
        for ours_label, ours_t, rk_t, rk_label in (
                ("eq 13/14 plan", t_plan_eq / M, theirs, "ruckig"),
                ("eq 13/14 plan, path's first", t_plan_fresh / M, theirs + t_rows / M, "ruckig and its inputs"),
                ("verified plan", ours, theirs, "ruckig")):
            table.row(f"  speed ratio ours ({ours_label}) / {rk_label} (t_ruckig / t_ours)", "", f"{rk_t / ours_t:.3f}x",
                      f">= {TARGET_VS_RUCKIG:g}x" if is_target else "",
                      verdict(rk_t / ours_t >= TARGET_VS_RUCKIG) if is_target else "")
        # no plan checked on its exact profile every check period gets past this ratio: one check
        # costs that much before any candidate, round or look-ahead
        table.row("  ceiling on the verified plan's ratio: ruckig / one full check", "", f"{theirs / (t_check / M):.3f}x")


# -- main ------------------------------------------------------------------------------------------
def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--segments", type=int, default=10_000, help="number of G1 segments (default 10^4)")
    ap.add_argument("--seed", type=int, default=0, help="seed of the random path")
    ap.add_argument("--repeats", type=int, default=None, help="warm repeats per measurement (default 5)")
    ap.add_argument("--quick", action="store_true", help="2000 segments, 2 repeats (a smoke run)")
    args = ap.parse_args(argv)
    segments = args.segments if not args.quick or args.segments != 10_000 else 2000
    repeats = args.repeats or (2 if args.quick else 5)
    if segments < 2:
        ap.error("--segments must be >= 2")

    cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    print(f"python {platform.python_version()}, numpy {np.__version__}, jax {jax.__version__} "
          f"({jax.default_backend()}), {cpus} CPUs available ({os.cpu_count()} total), {platform.machine()}, "
          f"{load()} at start")
    print(f"path: {segments} segments, seed {args.seed}; best of {repeats} warm repeats; "
          f"ratios are against baselines timed in this run")

    t_start = time.perf_counter()
    path = cam_path(segments, args.seed)
    table = Table("bench_fir: FIR-overlap interpolator (Sencer 2015) vs baselines (targets: issue 'Core pipeline' §8)")
    res = bench_throughput(path, repeats, table)
    if res["misses"]:
        bench_breakdown(res["path"], res["feeds"], res["plan"], res["t_ours"], repeats, table)
    bench_planning(res["path"], res["feeds"], repeats, table)
    table.print()
    print(f"total benchmark time {time.perf_counter() - t_start:.1f} s ({load()} at the end)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
