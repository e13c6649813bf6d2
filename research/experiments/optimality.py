"""Optimality study: every cornering method against the CasADi time-optimal reference.

Methods, all held to the same per-axis limits and cornering tolerance: FIR overlap (Sencer 2015,
plain), FIR overlap holding the limits (beyond the paper), the S-curve with exact stops, geometric
corner smoothing (the Fig 6 baseline) and the time-optimal OCP. Two limit conventions:

* ``"a"``: the FIR's own per-axis peak velocity, acceleration and jerk on that path (the FIR is
  within them by construction; the others get exactly what the FIR used);
* ``"b"``: the FIR's nominal envelope ``v = F``, ``a = F / T1``, ``j = F / (T1 T2)`` (plain FIR
  overlap breaks it at corners, which the table shows).

Run ``python -m research.experiments.optimality [--quick] [--out FILE]``: it prints the table and
writes the rows (JSON) after every path, so an interrupted study keeps what it finished.
"""

from __future__ import annotations

import argparse
import json
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from research.experiments.store import atomic_write
from research.interpolators import blend_interpolate, fir_interpolate, plan_fir, scurve_interpolate
from research.limits import AxisLimits
from research.metrics import corner_errors, limit_ratios, max_contour_error, peak_axis_values
from research.paths import Polyline, named_path
from research.trajectory import Trajectory

PAPER = dict(feed=250.0, delays=(0.148, 0.089), tolerance=0.5)  # Sencer 2015 §4 [mm/s, s, mm]


@dataclass(frozen=True)
class StudyRow:
    """One method on one path under one limit convention (units: s, mm, mm/s^2, mm/s^3)."""

    path: str
    convention: str
    method: str
    cycle_time: float
    ratio_to_ocp: float
    max_contour_error: float
    max_corner_error: float
    peak_acceleration: list
    peak_jerk: list
    worst_limit_ratio: float
    within_limits: bool


def cam_like_path(n_segments: int = 30, seed: int = 0) -> Polyline:
    """Seeded 2-D path of short G01 segments (2-6 mm, turns of up to +-40 deg), like CAM output."""
    rng = np.random.default_rng(seed)
    heading = np.cumsum(rng.uniform(-np.radians(40), np.radians(40), n_segments))
    steps = rng.uniform(2.0, 6.0, n_segments)[:, None] * np.column_stack([np.cos(heading), np.sin(heading)])
    return Polyline(np.vstack([[0.0, 0.0], np.cumsum(steps, axis=0)]))


def study_limits(convention: str, path: Polyline, fir: Trajectory, feed: float, delays) -> AxisLimits:
    """The per-axis limits every method is held to under ``convention`` (``"a"`` or ``"b"``)."""
    if convention == "a":
        return AxisLimits(*(peak_axis_values(fir, nu) for nu in (1, 2, 3)))
    if convention == "b":
        return AxisLimits.fir_envelope(path.dim, feed, delays)
    raise ValueError(f"limit convention must be 'a' or 'b', got {convention!r}")


def run_path(name: str, path: Polyline, *, feed: float, delays, tolerance: float, conventions=("a", "b"),
             window: int | None = None, intervals_per_segment: int = 16, log=print) -> list[StudyRow]:
    """All methods on one path, under each limit convention."""
    from research.optimal import time_optimal

    fir = fir_interpolate(path, feed, delays, tolerance)
    rows = []
    for conv in conventions:
        limits = study_limits(conv, path, fir, feed, delays)
        t0 = time.perf_counter()
        ocp = time_optimal(path, limits, tolerance, feed=feed, window=window,
                           intervals_per_segment=intervals_per_segment, warm_start=fir if conv == "a" else None)
        log(f"  {name} ({conv}): OCP {ocp.cycle_time:.4f} s in {time.perf_counter() - t0:.1f} s")
        methods = {
            "FIR overlap (paper)": fir,
            "FIR overlap, limits held": plan_fir(path, feed, delays, tolerance, limits=limits).trajectory(1e-3),
            "S-curve exact stop": scurve_interpolate(path, feed, limits),
            "geometric blend": blend_interpolate(path, feed, tolerance, limits),
            "time-optimal OCP": ocp.trajectory,
        }
        for method, traj in methods.items():
            ratios = limit_ratios(traj, limits)
            worst = max(float(np.max(r)) for r in ratios.values())
            corners = corner_errors(traj, path)
            rows.append(StudyRow(
                path=name, convention=conv, method=method, cycle_time=float(traj.duration),
                ratio_to_ocp=float(traj.duration) / ocp.cycle_time,
                max_contour_error=max_contour_error(traj, path),
                max_corner_error=float(corners.max()) if corners.size else 0.0,
                peak_acceleration=peak_axis_values(traj, 2).tolist(), peak_jerk=peak_axis_values(traj, 3).tolist(),
                worst_limit_ratio=worst, within_limits=worst <= 1 + 1e-3,  # the OCP's 1 % grid check
            ))
    return rows


def format_table(rows: list[StudyRow]) -> str:
    """Plain-text table of the study."""
    head = f"{'path':<10} {'lim':<3} {'method':<26} {'T [s]':>8} {'T/T_ocp':>8} {'contour':>9} {'corner':>9} {'worst':>6} ok"
    lines = [head, "-" * len(head)]
    for r in rows:
        lines.append(
            f"{r.path:<10} {r.convention:<3} {r.method:<26} {r.cycle_time:8.4f} {r.ratio_to_ocp:8.3f} "
            f"{r.max_contour_error * 1e3:7.1f}um {r.max_corner_error * 1e3:7.1f}um {r.worst_limit_ratio:6.3f} "
            f"{'yes' if r.within_limits else 'NO'}"
        )
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="FIR, S-curve, geometric blend and OCP under equal limits")
    ap.add_argument("--quick", action="store_true", help="corner90 and diamond only")
    ap.add_argument("--out", type=Path, default=Path(".cache/results/optimality.json"))
    args = ap.parse_args(argv)
    paths = {"corner90": named_path("corner90"), "diamond": named_path("diamond")}
    if not args.quick:
        paths |= {"zigzag": named_path("zigzag"), "cam30": cam_like_path(30)}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    rows: list[StudyRow] = []
    for name, path in paths.items():
        window = 10 if path.n_segments > 12 else None
        rows += run_path(name, path, feed=PAPER["feed"], delays=PAPER["delays"], tolerance=PAPER["tolerance"], window=window)
        record = json.dumps({"setting": PAPER, "rows": [asdict(r) for r in rows]}, indent=1).encode()
        atomic_write(args.out, record)  # completed paths survive interruption
    print(format_table(rows))
    print(f"\nrows written to {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
