"""Evaluate one validated experiment config (the general path of runs and sweeps).

path -> each interpolator -> :func:`~research.metrics.summarize` -> drive (structural modes:
residual vibration; catalog drive: tracking error) ; identification (synthetic log with known truth,
or a logged file) -> relative errors of the identified poles and friction.

:func:`evaluate` is a pure function of the config and the input files: it returns a JSON-ready
record (``scalars``: flat ``{metric: float}``; ``details``: per-interpolator corners, peaks, ...)
and arrays (sampled trajectories), which the store keeps. Scalar names are the metric names of
:data:`~research.experiments.config.METRIC_UNITS`, prefixed by ``<label>.`` when a config has
several interpolators, suffixed by ``.<axis>`` for per-mode residual vibration.

Example:
    >>> from research.experiments.config import validate
    >>> cfg = validate({"name": "t", "reproduces": "-", "path": {"name": "corner90"}}, "t.toml")
    >>> ev = evaluate(cfg, ".")
    >>> round(ev.record["scalars"]["max_corner_error"], 6)   # the default 500 um tolerance, eq 14
    0.5
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from research.experiments.config import METRIC_UNITS, ExperimentConfig, build_path, read_program
from research.experiments.fir_model import residual_vibration_sampled
from research.metrics import MotionMetrics, summarize
from research.trajectory import Trajectory

SETTLE_MARGIN_S = 0.05  # residual vibration is measured from the end of motion + this [s]


@dataclass(frozen=True)
class Evaluation:
    """What :func:`evaluate` returns: the JSON record, arrays for the store, and objects a figure needs."""

    record: dict
    arrays: dict[str, np.ndarray] = field(default_factory=dict)
    objects: dict = field(default_factory=dict)


def evaluate(cfg: ExperimentConfig, base: str | Path, log=None) -> Evaluation:
    """Run everything ``cfg`` asks for. ``base``: folder that relative file names are read from.

    Args:
        cfg: a validated config.
        base: folder of the config file.
        log: optional progress callback taking one string.
    """
    log = log or (lambda s: None)
    base = Path(base)
    scalars, details, arrays, objects = {}, {}, {}, {}
    if cfg.identification is not None:
        log(f"identification ({cfg.identification.method})")
        ident = _identify(cfg.identification, base, objects)
        details["identification"] = ident
        scalars |= {k: v for k, v in ident.items() if k.endswith("_error")}
    if cfg.path is not None:
        if cfg.path.gcode is not None:  # one read: chords for the metrics, blocks for the FIR planner
            program = read_program(cfg.path, base)
            path, program_feeds = program.polyline, program.feeds
            blocks = program.blocks, program.block_feeds, program.block_tolerance
        else:
            (path, program_feeds), blocks = build_path(cfg.path, base), None
        objects["path"] = path
        several = len(cfg.interpolators) > 1
        for ic in cfg.interpolators:
            label = ic.label or ic.kind
            prefix = f"{label}." if several else ""
            log(f"interpolator {label}: {path.n_segments} segments")
            traj, info, plan = _interpolate(ic, path, program_feeds, blocks)
            metrics = summarize(traj, path)
            objects.setdefault("runs", []).append((label, plan, traj, metrics))
            details[label] = info | {"metrics": metrics.as_dict(), "turning_angle_deg": np.degrees(path.turning_angles).tolist()}
            scalars |= {prefix + k: float(getattr(metrics, k)) for k in ("cycle_time", "max_corner_error", "max_contour_error", "peak_feed")}
            arrays |= {f"{label}.{k}": np.asarray(getattr(traj, k)) for k in ("t", "q", "v", "a", "j")}
            if cfg.drive is not None:
                log(f"drive {cfg.drive.model}: {len(cfg.drive.modes)} modes")
                scalars |= {prefix + k: v for k, v in _drive(cfg, traj, objects.get("identified_drive")).items()}
    if cfg.metrics is not None:
        scalars = {k: v for k, v in scalars.items() if _metric_name(k) in cfg.metrics}
    units = {k: METRIC_UNITS[_metric_name(k)] for k in scalars}
    return Evaluation({"scalars": scalars, "units": units, "details": details}, arrays, objects)


def _metric_name(key: str) -> str:
    return next(p for p in key.split(".") if p in METRIC_UNITS)


def _interpolate(ic, path, program_feeds, blocks=None):
    """``(trajectory, details, plan or None)`` of one interpolator config.

    The FIR planner gets a G-code program's blocks (arcs as arcs), its F words unless the config
    sets a feed, and its ``G64 P`` tolerances where the program gives them (the config's
    ``tolerance_um`` elsewhere); metrics are taken against the chords (``chord_tolerance_um``)."""
    if ic.kind == "fir":
        from research.interpolators import plan_fir

        # an explicit feed in the config wins; otherwise a G-code program's own F words are used
        explicit = "feed_mm_per_s" in ic.model_fields_set
        tolerance = ic.tolerance_um * 1e-3
        if blocks is not None:
            target, feeds, g64 = blocks
            feed = ic.feed_mm_per_s if explicit else feeds
            tolerance = np.where(np.isfinite(g64), g64, tolerance)
        else:
            target = path
            feed = program_feeds if (program_feeds is not None and not explicit) else ic.feed_mm_per_s
        plan = plan_fir(target, feed, np.asarray(ic.delays_ms) * 1e-3, tolerance, refine=ic.refine)
        traj = plan.trajectory(ic.sample_period_ms * 1e-3)
        info = {"feeds": np.asarray(plan.feeds).tolist(), "overlap_times": np.asarray(plan.overlaps).tolist(),
                "corner_errors": np.asarray(plan.corner_errors).tolist()}
        return traj, info, plan
    from research.limits import AxisLimits
    from research.optimal import time_optimal

    limits = AxisLimits.fir_envelope(path.dim, ic.feed_mm_per_s, np.asarray(ic.envelope_delays_ms) * 1e-3)
    res = time_optimal(path, limits, ic.tolerance_um * 1e-3, feed=ic.feed_mm_per_s, window=ic.window,
                       intervals_per_segment=ic.intervals_per_segment, sample_period=ic.sample_period_ms * 1e-3)
    info = {"status": res.status, "iterations": res.iterations, "solve_time": res.solve_time,
            "worst_check_ratio": float(res.verification.worst_ratio)}
    return res.trajectory, info, None


def _drive(cfg: ExperimentConfig, traj: Trajectory, identified=None) -> dict[str, float]:
    """Residual vibration per mode (and its max), and the tracking error of a catalog drive [mm]
    (``drive.model = "identified"``: the eq 6.3 model identified by the same config, ``identified``)."""
    d = cfg.drive
    out = {}
    a = np.asarray(traj.a)
    if d.model == "ideal":
        for m in d.modes:
            k = traj.axes.index(m.axis)
            out[f"residual_vibration.{m.axis}"] = residual_vibration_sampled(traj.t, a[:, k], m.frequency_hz, m.damping)
    else:
        from research.drives import FlexibleMode, simulate, virtual_drive

        drive = identified if d.model == "identified" else virtual_drive(d.model)
        held = _hold(traj, float(traj.duration) + d.settle_time_s)
        resp = simulate(drive, held)
        out["max_tracking_error"] = float(np.max(np.abs(np.asarray(resp.tracking_error))))
        after = np.asarray(held.t) > float(traj.duration) + SETTLE_MARGIN_S
        for m in d.modes:
            k = traj.axes.index(m.axis)
            one = Trajectory(held.t, held.q[:, k:k + 1], held.v[:, k:k + 1], held.a[:, k:k + 1], held.j[:, k:k + 1],
                             held.duration, None, (m.axis,), held.sample_period)
            defl = np.asarray(simulate(drive, one, modes=FlexibleMode.from_hz(m.frequency_hz, m.damping)).deflection)
            out[f"residual_vibration.{m.axis}"] = float(np.max(np.abs(defl[after, 0])))
    if d.modes:
        out["residual_vibration"] = max(out[f"residual_vibration.{m.axis}"] for m in d.modes)
    return out


def _hold(traj: Trajectory, horizon: float) -> Trajectory:
    """The same motion, held at rest at its end point until ``horizon`` [s]."""
    n = int(np.ceil(horizon / traj.sample_period)) + 1
    k = traj.n_samples
    if n <= k:
        return traj
    rest = np.zeros((n - k, traj.n_axes))
    q = np.vstack([np.asarray(traj.q), np.repeat(np.asarray(traj.q[-1:]), n - k, axis=0)])
    v, a, j = (np.vstack([np.asarray(x), rest]) for x in (traj.v, traj.a, traj.j))
    return Trajectory(np.arange(n) * traj.sample_period, q, v, a, j, traj.duration, None, traj.axes, traj.sample_period)


def _identify(ic, base: Path, objects: dict | None = None) -> dict:
    """Fit the drive; with a synthetic log, relative errors of ``wn, zeta, p, dc`` against the truth."""
    from research.drives import Encoder, virtual_drive
    from research.identification import (
        ProjectedProblem,
        bounded_fit,
        build_regression,
        identification_program,
        least_squares,
        load_drive_log,
        particle_swarm,
        synthetic_log,
    )

    truth = None
    if ic.log_file is not None:
        log = load_drive_log(base / ic.log_file)
    else:
        truth = virtual_drive(ic.truth)
        ref = identification_program(ic.seed, n_moves=ic.n_moves).trajectory()
        log = synthetic_log(truth, ref, encoder=Encoder(ic.resolution_um * 1e-3, ic.noise_um * 1e-3), seed=ic.seed)
    if ic.method == "simulation_error":
        from research.identification import simulation_error_fit

        sef = simulation_error_fit(log, ic.structure)
        if ic.structure != "eq6.3":
            return {"parameters": sef.parameters, "rms_um": sef.rms_um, "converged": sef.converged,
                    "samples": int(log.n_samples)}
        fit = sef.to_identified_drive()
        if objects is not None:
            objects["identified_drive"] = sef.closed_loop_model()
    elif ic.method == "ls":
        fit = least_squares(log)
    else:
        prob = ProjectedProblem.from_regression(build_regression(log))
        fit = particle_swarm(prob, seed=ic.seed) if ic.method == "pso" else bounded_fit(prob)
    wn, zeta, p = fit.pole_parameters()
    out = {"wn_rad_per_s": wn, "zeta": zeta, "p_rad_per_s": p, "dc": float(fit.dc), "samples": int(log.n_samples)}
    if truth is not None:
        true = dict(zip(("wn", "zeta", "p"), truth.pole_parameters())) | {"dc": float(truth.dc)}
        got = {"wn": wn, "zeta": zeta, "p": p, "dc": float(fit.dc)}
        out |= {f"{k}_error": abs(got[k] - v) / abs(v) for k, v in true.items()}
    return out
