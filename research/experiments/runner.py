"""Run one experiment config end to end: path -> interpolator -> metrics -> results + figure.

Results go to a git-ignored cache (``.cache/results/<name>/``: ``results.json`` and
``trajectory.npz``, written atomically); the figure goes to ``paper_figures/<name>.png``.
"""

from __future__ import annotations

import json
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

import research
from research.experiments.config import ExperimentConfig, build_path, load_config
from research.interpolators import FIRPlan, plan_fir
from research.metrics import MotionMetrics, summarize
from research.paths import Polyline
from research.trajectory import Trajectory

DEFAULT_CACHE = Path(".cache") / "results"
DEFAULT_FIGURES = Path("paper_figures")


@dataclass(frozen=True)
class RunResult:
    """What one run produced, and where it was written."""

    config: ExperimentConfig
    path: Polyline
    plan: FIRPlan
    trajectory: Trajectory
    metrics: MotionMetrics
    results_file: Path
    figure_file: Path | None


def run_experiment(
    config_file: str | Path,
    *,
    cache_dir: str | Path = DEFAULT_CACHE,
    figures_dir: str | Path = DEFAULT_FIGURES,
    log=print,
) -> RunResult:
    """Run the experiment in ``config_file`` and save its results and figure.

    Args:
        config_file: TOML experiment config (see :mod:`research.experiments.config`).
        cache_dir: results root; the run writes ``<cache_dir>/<name>/``.
        figures_dir: where the figure goes.
        log: progress callback taking one string (``print`` by default).
    """
    cfg, base = load_config(config_file)
    log(f"[1/4] path: {_describe_path(cfg)}")
    path, program_feeds = build_path(cfg.path, base)
    ic = cfg.interpolator
    # An explicit feed in the config wins; otherwise a G-code program's own F words are used.
    feed = program_feeds if (program_feeds is not None and "feed_mm_per_s" not in ic.model_fields_set) else ic.feed_mm_per_s
    delays = np.asarray(ic.delays_ms) * 1e-3
    log(f"[2/4] FIR interpolation: {path.n_segments} segments, T_i = {ic.delays_ms} ms, eps = {ic.tolerance_um} um")
    plan = plan_fir(path, feed, delays, ic.tolerance_um * 1e-3, refine=ic.refine)
    traj = plan.trajectory(ic.sample_period_ms * 1e-3)
    log(f"[3/4] metrics on {traj.n_samples} samples at Ts = {ic.sample_period_ms} ms")
    metrics = summarize(traj, path)

    out = Path(cache_dir) / cfg.name
    out.mkdir(parents=True, exist_ok=True)
    record = {
        "experiment": cfg.name,
        "reproduces": cfg.reproduces,
        "config": cfg.model_dump(),
        "research_version": research.__version__,
        "units": {"time": "s", "length": "mm", "overlap_times": "s", "corner_errors": "mm"},
        "metrics": metrics.as_dict(),
        "corners": {
            "turning_angle_deg": np.degrees(path.turning_angles).tolist(),
            "overlap_times": np.asarray(plan.overlaps).tolist(),
            "corner_errors": np.asarray(plan.corner_errors).tolist(),
        },
    }
    results_file = out / "results.json"
    _atomic_write(results_file, lambda f: f.write(json.dumps(record, indent=2).encode()))
    _atomic_write(out / "trajectory.npz", lambda f: traj.save(f))
    figure_file = None
    if cfg.output.figure:
        from research.figures.fir_run import plot_fir_run

        figures_dir = Path(figures_dir)
        figures_dir.mkdir(parents=True, exist_ok=True)
        figure_file = figures_dir / f"{cfg.name}.png"
        fig = plot_fir_run(path, plan, traj, metrics, title=f"{cfg.name}\n{cfg.reproduces}")
        _atomic_write(figure_file, lambda f: fig.savefig(f, format="png", dpi=150))
    log(f"[4/4] results: {results_file}" + (f"; figure: {figure_file}" if figure_file else ""))
    return RunResult(cfg, path, plan, traj, metrics, results_file, figure_file)


def format_summary(result: RunResult) -> str:
    """A plain-text table of the run's metrics, with units."""
    m, ic = result.metrics, result.config.interpolator
    rows = [
        ("experiment", result.config.name),
        ("reproduces", result.config.reproduces),
        ("segments / corners", f"{result.path.n_segments} / {max(result.path.n_segments - 1, 0)}"),
        ("feed F [mm/s]", _range(np.asarray(result.plan.feeds))),
        ("FIR delays T_i [ms]", ", ".join(f"{d:g}" for d in ic.delays_ms)),
        ("tolerance eps [um]", f"{ic.tolerance_um:g}"),
        ("cycle time [s]", f"{m.cycle_time:.6f}"),
        ("max corner error [um]", f"{m.max_corner_error * 1e3:.3f}"),
        ("max contour error [um]", f"{m.max_contour_error * 1e3:.3f}"),
        ("overlap T_k [ms]", _range(np.asarray(result.plan.overlaps) * 1e3)),
        ("peak feed [mm/s]", f"{m.peak_feed:.3f}"),
    ]
    for k, axis in enumerate(m.axes):
        rows.append((f"peak |v|, |a|, |j| {axis} [mm/s^n]", f"{m.peak_velocity[k]:.1f}, {m.peak_acceleration[k]:.1f}, {m.peak_jerk[k]:.1f}"))
    width = max(len(r[0]) for r in rows)
    return "\n".join(f"{k:<{width}}  {v}" for k, v in rows)


def _range(x: np.ndarray) -> str:
    if x.size == 0:
        return "-"
    return f"{x.min():.3f}" if np.ptp(x) < 1e-9 else f"{x.min():.3f} .. {x.max():.3f}"


def _describe_path(cfg: ExperimentConfig) -> str:
    p = cfg.path
    return p.name if p.name else (f"G-code {p.gcode}" if p.gcode else f"{len(p.points_mm)} points")


def _atomic_write(target: Path, write) -> None:
    """Write through a temporary file in the same folder, then rename: never a half-written file."""
    fd, tmp = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            write(f)
        os.chmod(tmp, 0o644)
        os.replace(tmp, target)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
