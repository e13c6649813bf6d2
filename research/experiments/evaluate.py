"""Evaluate one validated experiment config (the general path of runs and sweeps).

identification (synthetic log with known truth, or a logged file: relative errors of the identified
poles and friction) ; path -> each interpolator -> :func:`~research.metrics.summarize` -> drive
(structural modes: residual vibration; a drive model: tracking error) -> contour (exact error and
estimators) -> compensation (CEC). The stages are in :mod:`research.experiments.stages`.

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

import contextlib
import threading
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from research.experiments.config import METRIC_UNITS, ExperimentConfig, build_path, named_axes, read_program
from research.drives import residual_vibration_sampled
from research.experiments.stage_control import control_stage
from research.experiments.stage_feedrate import feedrate_stage
from research.experiments.stage_identified_contour import identified_contour_stage
from research.experiments.stage_execution_errors import execution_error_stage
from research.experiments.stage_identification_ch6 import identification_ch6_stage
from research.experiments.stage_mtp import mtp_stage
from research.experiments.stage_optimality import optimality_stage
from research.experiments.stages import (
    compensation_stage,
    contour_stage,
    drive_model,
    frequency_response_stage,
    identified_drive,
    interpolate,
    five_axis_contour_stage,
    spectrum_stage,
    startup_stage,
    vibration_stage,
)
from research.metrics import summarize
from research.trajectory import Trajectory

SETTLE_MARGIN_S = 0.05  # residual vibration is measured from the end of motion + this [s]


@dataclass(frozen=True)
class Evaluation:
    """What :func:`evaluate` returns: the JSON record, arrays for the store, and objects a figure needs."""

    record: dict
    arrays: dict[str, np.ndarray] = field(default_factory=dict)
    objects: dict = field(default_factory=dict)


def evaluate(cfg: ExperimentConfig, base: str | Path, log=None, *, model_file: bool = True) -> Evaluation:
    """Run everything ``cfg`` asks for. ``base``: folder that relative file names are read from.

    Args:
        cfg: a validated config.
        base: folder of the config file.
        log: optional progress callback taking one string.
        model_file: the identification stage also writes its model (``save_identified``, with its fit report:
            one more simulation of the log) as ``objects["drive_model.json"]``; sweeps, which keep only the
            record, pass ``False``.
    """
    log = log or (lambda s: None)
    base = Path(base)
    scalars, details, arrays, objects = {}, {}, {}, {}
    if cfg.identification is not None:
        log(f"identification ({cfg.identification.method})")
        ident = _identify(cfg.identification, base, objects, model_file)
        details["identification"] = ident
        scalars |= {k: v for k, v in ident.items() if k.endswith("_error")}
    if cfg.drive is not None and cfg.drive.identified_file is not None:
        log(f"drive: identified model {cfg.drive.identified_file}")
        objects["identified_drive"] = identified_drive(cfg.drive, base)
    # stages that need no tool path: (config key, progress line from its table, stage function)
    standalone = (
        ("vibration", lambda c: "vibration: resonance test -> modes -> eq 10 delays", lambda c: vibration_stage(c, base)),
        ("control", lambda c: f"control: {c.controller} controller on the Fig 5.5 path at {c.feed_mm_per_s:g} mm/s",
         control_stage),
        ("spectrum", lambda c: "spectrum: FIR chain frequency response (eq 8-10)", spectrum_stage),
        ("startup", lambda c: "startup: sigmoid start of a linear move (DiMarco eq 3-5)", startup_stage),
        ("mtp", lambda c: f"mtp: sigmoid vs linear interpolators through the drive {cfg.drive.model}",
         lambda c: mtp_stage(c, drive_model(cfg.drive, ("s",), objects.get("identified_drive")))),
        ("identification_ch6", lambda c: f"identification_ch6: {', '.join(c.methods)} on the Table 6.1 virtual drive"
                                         + (", EMPS" if c.emps_log_file else ""), lambda c: identification_ch6_stage(c, base)),
        ("optimality", lambda c: f"optimality: FIR against the time-optimal OCP on {', '.join(c.paths)}", optimality_stage),
        ("five_axis_contour", lambda c: "five_axis_contour: eq 4.36 path, exact tip contour error vs Frenet estimates "
                                        "(thesis §4.5)", five_axis_contour_stage),
        ("identified_contour", lambda c: "identified_contour: Table 6.3 machine identified by LS and PSO, eq 4.36 contour "
                                         f"error predicted at {c.feed_mm_per_s:g} mm/s (thesis §6.5.3)", identified_contour_stage),
    )
    for key, line, stage in standalone:
        table = getattr(cfg, key)
        if table is not None:
            log(line(table))
            found, details[key], more = stage(table)
            scalars |= found
            arrays |= more
    if cfg.drive is not None and cfg.drive.frequency_response is not None:
        log(f"drive {cfg.drive.model}: frequency response")
        axes = named_axes(cfg) if cfg.path is not None else ("x",)
        found, more = frequency_response_stage(cfg.drive.frequency_response,
                                               drive_model(cfg.drive, axes, objects.get("identified_drive")), axes)
        scalars |= found
        arrays |= more
    if cfg.feedrate is not None:  # thesis ch 3 along the 5-axis [path]
        log(f"feedrate: optimized vs constant feed along the 5-axis path {cfg.path.name}")
        found, details["feedrate"], more = feedrate_stage(cfg.feedrate, cfg.path.build())
        scalars |= found
        arrays |= more
    elif cfg.path is not None:
        if cfg.path.gcode is not None:  # one read: chords for the metrics, blocks for the FIR planner
            program = read_program(cfg.path, base)
            path, program_feeds = program.polyline, program.feeds
            blocks = program  # the FIR planner takes its blocks, feeds, G64 P tolerances and pauses
            pauses = _pauses_planned(cfg, program)
            # the program's own blocks (moves and arcs kept as arcs), for the summary: the chords are its polyline view
            path_counts = {"path_blocks": program.n_blocks, "path_arcs": int(np.count_nonzero(program.blocks.is_arc))}
        else:
            (path, program_feeds), blocks, pauses = build_path(cfg.path, base), None, None
            path_counts = {}
        objects["path"] = path
        cam = path if cfg.path.bspline is None else cfg.path.bspline.curve()  # errors against the curve itself
        several = len(cfg.interpolators) > 1
        for ic in cfg.interpolators:
            label = ic.label or ic.kind
            prefix = f"{label}." if several else ""
            log(f"interpolator {label}: " + (f"{path_counts['path_blocks']} blocks, {path_counts['path_arcs']} arc(s), "
                                             f"{path.n_segments} chords" if path_counts else f"{path.n_segments} segments"))
            if getattr(ic, "limits_from", None) is not None:  # the peaks of an earlier interpolator as the limits
                ic = _limits_of(ic, next(tr for lb, _, tr, _ in objects["runs"] if lb == ic.limits_from))
            with _notice_after(NOTICE_AFTER_S, log, f"interpolator {label}: still planning after {NOTICE_AFTER_S:g} s "
                               "(the first plan on a machine also compiles the planner's Numba kernels, "
                               "30-60 s once; kept in __pycache__ beside the modules or $NUMBA_CACHE_DIR)"):
                traj, info, plan = interpolate(ic, path, program_feeds, blocks, pauses)
            # a program's contour error against its own blocks (arcs exact, not their chords)
            metrics = summarize(traj, path, programmed=None if blocks is None else blocks.blocks)
            objects.setdefault("runs", []).append((label, plan, traj, metrics))
            details[label] = info | {"metrics": metrics.as_dict(), "turning_angle_deg": np.degrees(path.turning_angles).tolist()} \
                | path_counts
            scalars |= {prefix + k: float(getattr(metrics, k)) for k in ("cycle_time", "max_corner_error", "max_contour_error", "peak_feed")}
            arrays |= {f"{label}.{k}": np.asarray(getattr(traj, k)) for k in ("t", "q", "v", "a", "j")}
            if cfg.drive is None:
                continue
            log(f"drive {cfg.drive.model}: {len(cfg.drive.modes)} modes")
            drive = drive_model(cfg.drive, traj.axes, objects.get("identified_drive"))
            found, actual, deflection = _drive(cfg, traj, drive)
            scalars |= {prefix + k: v for k, v in found.items()}
            if deflection is not None:
                arrays[f"{label}.deflection"] = deflection
            if actual is not None:
                arrays[f"{label}.actual"] = actual[: traj.n_samples]
            if cfg.contour is not None:
                log(f"contour {label}: exact" + "".join(f", {e}" for e in cfg.contour.estimators))
                found, more = contour_stage(cfg.contour, cam, traj, actual)
                scalars |= {prefix + k: v for k, v in found.items()}
                arrays |= {f"{label}.{k}": v for k, v in more.items()}
            if cfg.compensation is not None:
                from research.contour import contour_error

                log(f"compensation {label}: CEC {cfg.compensation.method}")
                found, cec = compensation_stage(cfg.compensation, cam, traj, drive)
                scalars |= {prefix + k: v for k, v in found.items()}
                objects.setdefault("compensation", {})[label] = cec
                details[label]["compensation"] = {"method": cec.method, "steps": cec.steps, "converged": cec.converged,
                                                  "history": list(cec.history)}
                found, more = execution_error_stage(cam, traj, actual, cec)  # Prévost's e1, e2, eT (Fig 5)
                scalars |= {prefix + k: v for k, v in found.items()}
                arrays |= {f"{label}.{k}": v for k, v in more.items()}
                arrays |= {f"{label}.cec.q": np.asarray(cec.setpoint.q), f"{label}.cec.actual": np.asarray(cec.response.position),
                           f"{label}.cec.error_before": cec.before.distance, f"{label}.cec.error_after": cec.after.distance,
                           # e1 of Prevost 2012: the setpoint's distance to the CAM path, before and after
                           f"{label}.cec.setpoint_error_before": contour_error(cam, np.asarray(traj.q)).distance,
                           f"{label}.cec.setpoint_error_after": contour_error(cam, np.asarray(cec.setpoint.q)).distance}
    if cfg.metrics is not None:
        scalars = {k: v for k, v in scalars.items() if _metric_name(k) in cfg.metrics}
    units = {k: METRIC_UNITS[_metric_name(k)] for k in scalars}
    return Evaluation({"scalars": scalars, "units": units, "details": details}, arrays, objects)


#: seconds of a stage without output after which the run says what it is doing (a silent first run
#: that compiles for ~40 s reads as a hang)
NOTICE_AFTER_S = 10.0


@contextlib.contextmanager
def _notice_after(seconds: float, log, message: str):
    """Log ``message`` once if the block is still running after ``seconds`` (a timer thread)."""
    timer = threading.Timer(seconds, log, args=(message,))
    timer.daemon = True
    timer.start()
    try:
        yield
    finally:
        timer.cancel()


def _pauses_planned(cfg: ExperimentConfig, program):
    """The program's ``G4``/``M0``/``M1``/``M60`` pauses on its chords' vertices (``(M + 1,)`` [s], or
    None without any), refused for an interpolator that cannot plan them rather than dropped:
    ``plan_fir`` makes them exact stops held for the dwell, the S-curve and sigmoid moves stop at
    every vertex anyway and hold it; corner blending and the OCP have no pauses.

    Raises:
        ConfigError: naming the interpolator and the program lines of the pauses.
    """
    from research.errors import ConfigError

    at = np.flatnonzero(~np.isnan(program.block_pauses))
    if at.size == 0:
        return None
    lines = sorted({int(program.block_lines[max(k - 1, 0)]) for k in at})
    for ic in cfg.interpolators:
        if ic.kind not in ("fir", "scurve", "sigmoid") or (ic.kind == "fir" and ic.optimized):
            name = f"{ic.kind} (optimized)" if ic.kind == "fir" else ic.kind
            raise ConfigError(f"key 'interpolator' ({ic.label or ic.kind}): the program {cfg.path.gcode} pauses "
                              f"(G4 / M0 / M1 / M60) next to the moves of lines {lines[:10]}{' ...' if len(lines) > 10 else ''}, and "
                              f"interpolator kind {name!r} does not plan pauses; expected kind 'fir' (not optimized), "
                              "'scurve' or 'sigmoid', or a program without them")
    return program.pauses


def _limits_of(ic, traj: Trajectory):
    """``ic`` with ``limits`` set to ``traj``'s own per-axis peak |v|, |a|, |j| (``limits_from``)."""
    from research.experiments.config_stages import LimitsConfig
    from research.metrics import peak_axis_values

    peaks = [[float(x) for x in peak_axis_values(traj, nu)] for nu in (1, 2, 3)]
    limits = LimitsConfig(velocity_mm_per_s=peaks[0], acceleration_mm_per_s2=peaks[1], jerk_mm_per_s3=peaks[2])
    return ic.model_copy(update={"limits": limits, "limits_from": None})


def _metric_name(key: str) -> str:
    return next(p for p in key.split(".") if p in METRIC_UNITS)


def _drive(cfg: ExperimentConfig, traj: Trajectory, drive) -> tuple[dict[str, float], np.ndarray | None,
                                                                   np.ndarray | None]:
    """Residual vibration per mode (and its max), and the tracking error of a drive model [mm]
    (``drive``: from :func:`~research.experiments.stages.drive_model`, ``None`` for the ideal drive).

    Returns:
        ``(scalars, actual positions on the held grid or None, deflection of each mode (columns in the order of
        ``[[drive.modes]]``) on the held grid ``k Ts`` (motion + settle_time_s) [mm], or None (no modes, or the ideal
        drive))``.
    """
    d = cfg.drive
    out = {}
    a = np.asarray(traj.a)
    actual, deflections = None, []
    if drive is None:
        for m in d.modes:
            k = traj.axes.index(m.axis)
            out[f"residual_vibration.{m.axis}"] = residual_vibration_sampled(traj.t, a[:, k], m.frequency_hz, m.damping)
    else:
        from research.drives import FlexibleMode, simulate

        held = _hold(traj, float(traj.duration) + d.settle_time_s)
        resp = simulate(drive, held)
        actual = np.asarray(resp.position)
        out["max_tracking_error"] = float(np.max(np.abs(np.asarray(resp.tracking_error))))
        after = np.asarray(held.t) > float(traj.duration) + SETTLE_MARGIN_S
        for m in d.modes:
            k = traj.axes.index(m.axis)
            one = Trajectory(held.t, held.q[:, k:k + 1], held.v[:, k:k + 1], held.a[:, k:k + 1], held.j[:, k:k + 1],
                             held.duration, None, (m.axis,), held.sample_period)
            axis_drive = drive[k] if isinstance(drive, tuple) else drive
            defl = np.asarray(simulate(axis_drive, one, modes=FlexibleMode.from_hz(m.frequency_hz, m.damping)).deflection)
            out[f"residual_vibration.{m.axis}"] = float(np.max(np.abs(defl[after, 0])))
            deflections.append(defl[:, 0])
    if d.modes:
        out["residual_vibration"] = max(out[f"residual_vibration.{m.axis}"] for m in d.modes)
    return out, actual, (np.stack(deflections, axis=1) if deflections else None)


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


def _identify(ic, base: Path, objects: dict | None = None, model_file: bool = True) -> dict:
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
        c, u = ic.columns, ic.units
        log = load_drive_log(base / ic.log_file, time=c.t, reference=c.x_ref, actual=c.x_act, time_unit=u.t,
                             units={"x_ref": u.x_ref, "x_act": u.x_act}, counts_per_mm=ic.counts_per_mm,
                             counts_per_rev=ic.counts_per_rev)
    else:
        truth = virtual_drive(ic.truth)
        ref = identification_program(ic.seed, n_moves=ic.n_moves).trajectory()
        log = synthetic_log(truth, ref, encoder=Encoder(ic.resolution_um * 1e-3, ic.noise_um * 1e-3), seed=ic.seed)
    if ic.method == "simulation_error":
        from research.identification import simulation_error_fit

        sef = simulation_error_fit(log, ic.structure)
        if ic.structure != "eq6.3":
            if objects is not None and model_file:
                objects["drive_model.json"] = _model_file(sef, log, None if ic.log_file is None else base / ic.log_file)
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
    if objects is not None and model_file:  # the model as a file (save_identified): results/<name>/drive_model.json
        objects["drive_model.json"] = _model_file(sef if ic.method == "simulation_error" else fit, log,
                                                  None if ic.log_file is None else base / ic.log_file)
    wn, zeta, p = fit.pole_parameters()
    out = {"wn_rad_per_s": wn, "zeta": zeta, "p_rad_per_s": p, "dc": float(fit.dc), "samples": int(log.n_samples)}
    if truth is not None:
        true = dict(zip(("wn", "zeta", "p"), truth.pole_parameters())) | {"dc": float(truth.dc)}
        got = {"wn": wn, "zeta": zeta, "p": p, "dc": float(fit.dc)}
        out |= {f"{k}_error": abs(got[k] - v) / abs(v) for k, v in true.items()}
    return out


def _model_file(fit, log, log_file) -> bytes:
    """The bytes :func:`research.identification.save_identified` writes for ``fit`` (identified on ``log``)."""
    import tempfile

    from research.identification import save_identified

    with tempfile.TemporaryDirectory() as tmp:
        return save_identified(fit, Path(tmp) / "drive_model.json", log=log, log_file=log_file).read_bytes()
