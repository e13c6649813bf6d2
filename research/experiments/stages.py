"""The stages of an experiment, each a call into the package on the package's own types:

- :func:`interpolate`: an interpolator config -> :class:`~research.trajectory.Trajectory` (FIR, with
  limits or not; time-optimal; S-curve; geometric blend; sigmoid);
- :func:`drive_model`: a ``[drive]`` table -> a drive model (:class:`~research.drives.ClosedLoopModel`,
  a physical cascade, or one per axis), ``None`` for the ideal drive;
- :func:`contour_stage`: exact contour error of the actual motion and the thesis' estimators;
- :func:`compensation_stage`: CEC (:mod:`research.contour`) of the setpoint through the drive.

Each returns its scalars (keys of :data:`~research.experiments.config.METRIC_UNITS`, mm and s) and
the objects later stages or figures use.
"""

from __future__ import annotations

import logging

import numpy as np

from research.errors import GCodeError
from research.experiments.config_drive import PER_AXIS_DRIVES
from research.trajectory import Trajectory

_log = logging.getLogger(__name__)


def envelope(ic, n_axes: int):
    """The axis limits of an S-curve / blend config: its ``limits`` or the FIR envelope (Sencer 2015 §2.1)."""
    from research.limits import AxisLimits

    if ic.limits is not None:
        return ic.limits.axis_limits(n_axes)
    return AxisLimits.fir_envelope(n_axes, ic.feed_mm_per_s, np.asarray(ic.envelope_delays_ms) * 1e-3)


def _optimized_fir(ic, target, feed, tolerance, limits):
    """``optimize_fir`` on a config's path: G01 blocks with one feed and one tolerance (it takes no arcs,
    per-block F words or G64 P tolerances: refused by name rather than replaced)."""
    from research.errors import ConfigError
    from research.interpolators import optimize_fir
    from research.paths import Polyline
    from research.paths.toolpath import ToolPath

    if isinstance(target, ToolPath):
        if np.any(target.is_arc):
            raise ConfigError("key 'interpolator.optimized': optimize_fir takes G01 blocks; this program has arcs")
        target = Polyline(np.vstack([target.start, target.ends]))
    feeds, tolerances = np.unique(np.atleast_1d(feed)), np.unique(np.atleast_1d(tolerance))
    if feeds.size > 1 or tolerances.size > 1:
        raise ConfigError("key 'interpolator.optimized': optimize_fir takes one feed and one tolerance; this program "
                          f"has {feeds.size} feeds and {tolerances.size} tolerances (set interpolator.feed_mm_per_s, "
                          "give no or one G64 P)")
    return optimize_fir(target, float(feeds[0]), np.asarray(ic.delays_ms) * 1e-3, float(tolerances[0]), limits)


def interpolate(ic, path, program_feeds, blocks=None, pauses=None):
    """``(trajectory, details, plan or None)`` of one interpolator config.

    The FIR planner gets the blocks of the G-code program ``blocks`` (a ``GCodeProgram``; arcs as
    arcs), its F words unless the config sets a feed, its ``G64 P`` tolerances where the program
    gives them (the config's ``tolerance_um`` elsewhere) and its pauses (``G4``/``M0``/``M1``); an
    arc under ``G61``/``G61.1`` (tolerance 0) is refused with its file and line, as an FIR chain
    cannot run any arc exactly (Sencer 2015 eq 8). The S-curve and sigmoid moves, which stop at
    every vertex, hold ``pauses`` ``(M + 1,)`` [s] on the chords' vertices; corner errors are taken
    at the chords' vertices (``chord_tolerance_um``), the contour error against the program's
    blocks, its arcs exact (``evaluate``)."""
    Ts = ic.sample_period_ms * 1e-3
    explicit = "feed_mm_per_s" in ic.model_fields_set
    feed = program_feeds if (program_feeds is not None and not explicit) else ic.feed_mm_per_s
    if ic.kind == "fir":
        from research.interpolators import plan_fir

        tolerance = ic.tolerance_um * 1e-3
        target = path
        block_pauses = None  # the FIR plans blocks: the pauses on their vertices
        if blocks is not None:
            target, g64, block_pauses = blocks.blocks, blocks.block_tolerance, blocks.block_pauses
            feed = ic.feed_mm_per_s if explicit else blocks.block_feeds
            tolerance = np.where(np.isfinite(g64), g64, tolerance)
            exact_arcs = np.flatnonzero(target.is_arc & (tolerance <= 0.0))
            if exact_arcs.size:
                raise GCodeError(f"arc under G61/G61.1 (exact path, tolerance 0) planned by the FIR interpolator "
                                 f"'{ic.label or ic.kind}': an FIR chain shrinks every arc it averages (Sencer 2015 "
                                 f"eq 8), so it cannot run an arc exactly ({exact_arcs.size} such arc(s)); expected "
                                 "a G64 P<tolerance> in force at the arc", source=blocks.source,
                                 line=int(blocks.block_lines[exact_arcs[0]]), column=1)
        limits = None if ic.limits is None else ic.limits.axis_limits(path.dim)
        if ic.optimized:
            plan = _optimized_fir(ic, target, feed, tolerance, limits)
        elif ic.mirror:
            from tqdm.auto import tqdm

            from research.interpolators import plan_fir_mirror

            # disable None: shown on a terminal only (no carriage returns in logs)
            bar = tqdm(desc="mirror re-plans", unit="plan", disable=True if len(target.lengths) < _MIRROR_BAR else None,
                       leave=False)

            def progress(best):
                bar.update()
                bar.set_postfix_str(f"best {best:.4f} s", refresh=False)

            try:
                plan = plan_fir_mirror(target, feed, np.asarray(ic.delays_ms) * 1e-3, tolerance, limits=limits,
                                       pauses=block_pauses, progress=progress).plan
            finally:
                bar.close()
        else:
            plan = plan_fir(target, feed, np.asarray(ic.delays_ms) * 1e-3, tolerance, refine=ic.refine, limits=limits,
                            pauses=block_pauses, corner_speed=ic.corner_speed)
        planned_tol = np.asarray(tolerance, dtype=np.float64)
        info = {"planner": "optimize_fir" if ic.optimized else "plan_fir_mirror" if ic.mirror else "plan_fir",
                "feeds": np.asarray(plan.feeds).tolist(), "overlap_times": np.asarray(plan.overlaps).tolist(),
                "corner_errors": np.asarray(plan.corner_errors).tolist(),
                # the tolerances planned [um]: the program's G64 P where it gives one, tolerance_um elsewhere
                "tolerance_um_range": [float(planned_tol.min()) * 1e3, float(planned_tol.max()) * 1e3]}
        return plan.trajectory(Ts), info, plan
    if ic.kind == "scurve":
        from research.interpolators import scurve_interpolate

        limits = envelope(ic, path.dim)
        return scurve_interpolate(path, feed, limits, Ts, pauses=pauses), {"limits": _limits_dict(limits)}, None
    if ic.kind == "blend":
        from research.interpolators import blend_interpolate

        limits = envelope(ic, path.dim)
        return blend_interpolate(path, feed, ic.tolerance_um * 1e-3, limits, Ts), {"limits": _limits_dict(limits)}, None
    if ic.kind == "sigmoid":
        return _sigmoid_moves(ic, path, pauses)
    from research.limits import AxisLimits
    from research.optimal import time_optimal

    # a G-code program's own feed unless the config writes one, as the FIR stage: its largest F word
    # (one bound on the whole path; the OCP takes no per-block speed bounds)
    bound = float(np.max(feed)) if np.ndim(feed) else float(feed)
    if np.ndim(feed) and np.min(feed) < bound:
        _log.warning(
            "interpolator '%s': the program's feeds run from %.6g to %.6g mm/s; the time-optimal reference "
            "takes one speed bound on the whole path, the largest (set [interpolator] feed_mm_per_s to "
            "choose another)", ic.label or ic.kind, float(np.min(feed)), bound)
    limits = AxisLimits.fir_envelope(path.dim, bound, np.asarray(ic.envelope_delays_ms) * 1e-3)
    if ic.window is None and path.n_segments >= _WHOLE_NLP_WARN:
        _log.warning(
            "interpolator '%s': the time-optimal reference over all %d segments is one NLP of %d intervals "
            "(measured: 250 segments x 16 took 212 s and 2.6 GB); set [interpolator] window (e.g. 10) for a "
            "receding-horizon reference", ic.label or ic.kind, path.n_segments, path.n_segments * ic.intervals_per_segment)
    res = time_optimal(path, limits, ic.tolerance_um * 1e-3, feed=bound, window=ic.window,
                       lookahead="braking" if ic.lookahead == "braking" else None,
                       intervals_per_segment=ic.intervals_per_segment, sample_period=Ts)
    info = {"status": res.status, "iterations": res.iterations, "solve_time": res.solve_time,
            "worst_check_ratio": float(res.verification.worst_ratio), "feed_mm_per_s": bound}
    return res.trajectory, info, None


def _limits_dict(limits) -> dict:
    return {k: getattr(limits, k).tolist() for k in ("velocity", "acceleration", "jerk")}


#: segments from which the sigmoid stage shows a progress bar over its moves
_SIGMOID_BAR = 50
#: blocks from which the mirror planner shows a progress bar over its re-plans: 80 blocks plan in
#: about 1 s, a real 394-block program at eps 2.54 um in 7 s and its 1,897 blocks in 30 s
#: (README, "The mirror at tight tolerances")
_MIRROR_BAR = 200
#: segments from which a whole-path time-optimal NLP (no ``window``) is warned of: ~1 min and ~1 GB
#: by the one measured (250 segments x 16 intervals: 212 s, 2.6 GB; README, eighth CAM section)
_WHOLE_NLP_WARN = 100


def _sigmoid_moves(ic, path, pauses=None):
    """Each segment a rest-to-rest DiMarco move (:func:`~research.interpolators.mtp_motion`), one after
    the other, sampled on one grid ``k Ts``: ``q = P_k + u_k s_k(t - t_k)``. A move ends once inside
    its settle band (``settle_tol`` = 0.1 um of mtp_motion), so consecutive moves join within 0.1 um.
    ``pauses`` ``(M + 1,)`` [s] (NaN: none) delay the moves after each vertex (the samples hold it)."""
    from tqdm.auto import tqdm

    from research.interpolators import mtp_motion

    # each move is its own alpha search (~0.3 s): a bar on programs of many segments
    lengths = tqdm(path.lengths, desc="sigmoid moves", unit="move", disable=path.n_segments < _SIGMOID_BAR, leave=False)
    moves = [mtp_motion(float(L), ic.feed_mm_per_s, ic.amplitude_mm, ic.frequency_hz,
                        acceleration=ic.acceleration_mm_per_s2, jerk=ic.jerk_mm_per_s3, order=ic.order)
             for L in lengths]
    durations = np.array([m.duration for m in moves])
    dwell = np.zeros(path.n_segments + 1) if pauses is None else np.nan_to_num(np.asarray(pauses, dtype=np.float64), nan=0.0)
    # move i starts after the moves and dwells before it; starts[M] is the end of the motion (and last dwell)
    starts = np.concatenate([[dwell[0]], dwell[0] + np.cumsum(durations + dwell[1:])])
    Ts = ic.sample_period_ms * 1e-3
    t = np.arange(int(np.ceil(starts[-1] / Ts - 1e-9)) + 1) * Ts
    k = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(moves) - 1)
    out = np.zeros((4, t.size, path.dim))
    first = np.searchsorted(k, np.arange(len(moves) + 1))  # k is non-decreasing: move i's samples are a run
    for i, m in enumerate(moves):
        on = slice(first[i], first[i + 1])
        d = m.derivatives(np.clip(t[on] - starts[i], 0.0, durations[i]))  # held at rest before and after
        for nu in range(4):
            out[nu, on] = (path.points[i] if nu == 0 else 0.0) + d[nu][:, None] * path.directions[i]
    traj = Trajectory(t, out[0], out[1], out[2], out[3], np.float64(starts[-1]), None, path.axes, float(Ts))
    return traj, {"move_durations": durations.tolist()}, None


def drive_model(d, axes: tuple[str, ...], identified=None):
    """The drive a ``[drive]`` table names, for the path's ``axes``: ``None`` (ideal), one model for
    every axis, or a tuple with one per axis (thesis Table 6.3)."""
    from research import drives

    if d.model == "ideal":
        return None
    if d.model == "identified":
        return identified
    if d.model == "parameters":
        return d.parameters.model()
    if d.model in PER_AXIS_DRIVES:
        return tuple(getattr(drives, PER_AXIS_DRIVES[d.model])(a) for a in axes)
    return drives.virtual_drive(d.model)


def identified_drive(d, base):
    """The eq 6.3 :class:`~research.drives.ClosedLoopModel` in ``d.identified_file`` (a file written by
    :func:`research.identification.save_identified`, relative to the config folder ``base``).

    Raises:
        ConfigError: the file is missing, corrupt or not a valid model (the loader's reason), or its model
            cannot drive the simulator (not eq 6.3, or unstable); the message names the key and the file.
    """
    from research.errors import ConfigError, ParameterError
    from research.identification import StructureFit, load_identified

    file = base / d.identified_file
    where = f"key 'drive.identified_file' = {d.identified_file!r} ({file})"
    try:
        fit = load_identified(file)
        return fit.closed_loop_model() if isinstance(fit, StructureFit) else fit.model()
    except (ConfigError, ParameterError) as e:
        raise ConfigError(f"{where}: {e}") from None


def contour_stage(cc, path, traj: Trajectory, actual: np.ndarray) -> tuple[dict, dict]:
    """Exact contour error of ``actual`` (the drive's positions on ``traj``'s grid) against the CAM
    ``path`` (Prévost 2012 §2.2), and the thesis' Frenet estimates (eq 4.20-4.27) with the largest
    difference to the exact error against the reference curve ``traj`` traces (what they estimate).

    Returns:
        ``(scalars [mm], arrays)``: ``max_actual_contour_error``, ``rms_actual_contour_error``,
        ``max_estimate.<name>``, ``max_estimator_error.<name>``; arrays ``contour.exact`` and
        ``contour.<name>`` per sample [mm].
    """
    from research.contour import contour_error, frenet_contour_estimates, tip_reference

    n = traj.n_samples
    actual = np.asarray(actual)[:n]
    exact = contour_error(path, actual)
    scalars = {"max_actual_contour_error": exact.max,
               "rms_actual_contour_error": float(np.sqrt(np.mean(exact.distance ** 2)))}
    arrays = {"contour.exact": exact.distance, "contour.t": np.asarray(traj.t)}
    if cc.estimators:
        to_reference = contour_error(traj, actual).distance
        est = frenet_contour_estimates(tip_reference(traj), np.asarray(traj.t), actual, cc.min_speed_ratio)
        arrays["contour.exact_to_reference"] = to_reference
        for name in cc.estimators:
            e = np.asarray(getattr(est, name))
            scalars[f"max_estimate.{name}"] = float(np.max(e))
            scalars[f"max_estimator_error.{name}"] = float(np.max(np.abs(e - to_reference)))
            arrays[f"contour.{name}"] = e
    return scalars, arrays


def compensation_stage(cc, path, traj: Trajectory, drive):
    """CEC of the setpoint ``traj`` through ``drive`` towards the CAM ``path`` (Prévost 2012 eq 4).

    Returns:
        ``(scalars, result)``: ``cec_error_before`` / ``cec_error_after`` (max exact ``|e_T|`` [mm]), their ratio
        ``cec_error_ratio`` and ``cec_simulations``; the :class:`~research.contour.CompensationResult` (its ``setpoint`` is the
        compensated :class:`Trajectory`).
    """
    from research.contour import cec_problem, mirror_compensation, mirror_passes, mirror_single_pass

    problem = cec_problem(path, traj, drive, friction=cc.friction, spacing=cc.spacing_mm)
    if cc.method == "single_pass":
        res = mirror_single_pass(problem)
    elif cc.method == "passes":
        res = mirror_passes(problem, cc.passes)
    else:
        res = mirror_compensation(problem, method=cc.method, tolerance=cc.tolerance_um * 1e-3,
                                  max_steps=cc.max_steps, throw=False)
    scalars = {"cec_error_before": res.before.max, "cec_error_after": res.after.max,
               "cec_simulations": float(res.simulations)}
    if res.before.max > 0:  # left out when the setpoint already follows the path exactly
        scalars["cec_error_ratio"] = float(res.after.max / res.before.max)
    return scalars, res


def frequency_response_stage(fc, drive, axes: tuple[str, ...]) -> tuple[dict, dict]:
    """Tracking and disturbance responses (thesis eq 6.1) of ``drive`` (one model, or one per axis) on
    ``fc``'s frequencies, its poles (eq 6.13) and the -3 dB bandwidth of ``|x/x_r|`` (the first frequency
    where it falls below 1/sqrt(2), by log-linear interpolation; left out if it stays above in the range).

    Returns:
        ``(scalars, arrays)``: ``drive_wn_hz``, ``drive_zeta``, ``drive_p_hz``, ``drive_bandwidth_hz``
        (suffixed ``.<axis>`` for per-axis drives); arrays ``bode.f``, ``bode.tracking`` and
        ``bode.disturbance`` (complex, per axis for per-axis drives).
    """
    from research.drives import frequency_response

    f = np.logspace(np.log10(fc.start_hz), np.log10(fc.stop_hz), fc.num)
    models = dict(zip(axes, drive)) if isinstance(drive, tuple) else {"": drive}
    scalars, arrays = {}, {"bode.f": f}
    for axis, model in models.items():
        tag = f".{axis}" if axis else ""
        fr = frequency_response(model, f)
        track = np.asarray(fr.tracking)
        wn, zeta, p = model.closed_loop_model().pole_parameters()
        mag = np.abs(track)
        below = np.flatnonzero(mag < 1 / np.sqrt(2))
        scalars |= {f"drive_wn_hz{tag}": float(wn) / (2 * np.pi), f"drive_zeta{tag}": float(zeta),
                    f"drive_p_hz{tag}": float(p) / (2 * np.pi)}
        if below.size and below[0] > 0:
            i = below[0]
            x = np.log(f[i - 1:i + 1])
            scalars[f"drive_bandwidth_hz{tag}"] = float(np.exp(np.interp(-np.log(np.sqrt(2)), np.log(mag[[i, i - 1]]), x[::-1])))
        arrays |= {f"bode.tracking{tag}": track, f"bode.disturbance{tag}": np.asarray(fr.disturbance)}
    return scalars, arrays


def vibration_stage(vc, base) -> tuple[dict, dict, dict]:
    """Resonance test -> modes (:func:`research.vibration.estimate_modes`) -> eq 10 delays
    (:func:`research.vibration.tune_delays`) for the dominant mode of each axis.

    Returns:
        ``(scalars, details, arrays)``: ``mode_frequency_hz.<axis>``, ``mode_damping.<axis>``,
        ``tuned_delay.T<i>`` [s]; details ``{"modes": [...], "tuned": {...}, "log": ...}``; arrays
        ``vibration.<axis>.f / psd / threshold``.
    """
    from research.vibration import TrueMode, estimate_modes, load_accel_log, synthetic_accel_log, tune_delays

    if vc.log_file is not None:
        log = load_accel_log(base / vc.log_file, unit=vc.unit)
    else:
        log = synthetic_accel_log([TrueMode(m.axis, m.frequency_hz, m.damping) for m in vc.modes], excitation="sweep",
                                  f0=vc.f0_hz, f1=vc.f1_hz, duration=vc.duration_s, rate=vc.rate_hz, snr_db=vc.snr_db,
                                  seed=vc.seed)
    survey = estimate_modes(log)
    dominant = survey.dominant()
    tuned = tune_delays(list(dominant.values()), k=vc.k)
    scalars, arrays = {}, {}
    for axis, m in dominant.items():
        scalars |= {f"mode_frequency_hz.{axis}": float(m.frequency_hz), f"mode_damping.{axis}": float(m.damping)}
    scalars |= {f"tuned_delay.T{i + 1}": float(T) for i, T in enumerate(tuned.delays_s)}
    for axis, spec in survey.spectra.items():
        arrays |= {f"vibration.{axis}.f": spec.frequency_hz, f"vibration.{axis}.psd": spec.psd,
                   f"vibration.{axis}.threshold": spec.threshold}
    details = {"log": {"source": log.source, "samples": int(log.t.size), "sample_rate_hz": float(1 / log.sample_period)},
               "modes": [{"axis": m.axis, "frequency_hz": m.frequency_hz, "frequency_sd_hz": m.frequency_sd_hz,
                          "damping": m.damping, "damping_sd": m.damping_sd, "peak_psd": m.peak_psd, "flags": list(m.flags)}
                         for s in survey.spectra.values() for m in s.modes],
               "tuned": {"delays_s": list(tuned.delays_s), "axes": list(tuned.axes),
                         "frequencies_hz": list(tuned.frequencies_hz), "k": [int(k) for k in tuned.k]}}
    return scalars, details, arrays


def spectrum_stage(sc) -> tuple[dict, dict, dict]:
    """FIR chain frequency response (Sencer 2015 eq 8-9, :func:`research.interpolators.magnitude_response`) and
    the eq 10 delays of ``sc.modes_hz`` (:func:`research.interpolators.delays_for_modes`).

    Returns:
        ``(scalars, details, arrays)``: ``spectrum_gain.<chain>.mode<j>`` (|M| of chain ``T<i>`` (one filter),
        ``given`` or ``tuned`` at mode j, counted from 1), ``spectrum_null_gain.T<i>`` (largest |M| of the given
        chain at ``k / T_i``, k = 1..zeros), ``spectrum.tuned_delay.T<i>`` [s]; details ``{"delays_s", "modes_hz",
        "tuned_delays_s"}``; arrays ``spectrum.f`` [Hz] and ``spectrum.<chain>`` (|M|).
    """
    from research.interpolators import delays_for_modes, magnitude_response

    delays = np.asarray(sc.delays_ms) * 1e-3
    chains = {f"T{i + 1}": delays[i:i + 1] for i in range(delays.size)} | {"given": delays}
    details = {"delays_s": delays.tolist(), "modes_hz": list(sc.modes_hz)}
    scalars = {}
    if sc.modes_hz:
        tuned = np.asarray(delays_for_modes(sc.modes_hz, k=sc.k), dtype=np.float64)
        chains["tuned"] = tuned
        details["tuned_delays_s"] = tuned.tolist()
        scalars |= {f"spectrum.tuned_delay.T{i + 1}": float(T) for i, T in enumerate(tuned)}
    f = np.linspace(0.0, sc.stop_hz, sc.num)
    arrays = {"spectrum.f": f} | {f"spectrum.{c}": np.asarray(magnitude_response(2 * np.pi * f, d)) for c, d in chains.items()}
    for c, d in chains.items():
        for j, m in enumerate(sc.modes_hz):
            scalars[f"spectrum_gain.{c}.mode{j + 1}"] = float(magnitude_response(2 * np.pi * m, d))
    for i, T in enumerate(delays):
        zeros = 2 * np.pi * np.arange(1, sc.zeros + 1) / T
        scalars[f"spectrum_null_gain.T{i + 1}"] = float(np.max(np.asarray(magnitude_response(zeros, delays))))
    return scalars, details, arrays


def startup_stage(sc) -> tuple[dict, dict, dict]:
    """The blended start ``x = m t (1 - exp(-alpha t^order))`` (DiMarco 2015 eq 3-5) for each alpha.

    The feed's peak is the zero of the acceleration (Brent, ``xtol`` 1e-15 s) between the samples either side of the
    sampled maximum (the sampled maximum itself when it sits at the span's end).

    Returns:
        ``(scalars, details, arrays)``: ``startup_peak_feed.alpha<i>`` [mm/s], ``startup_peak_time.alpha<i>`` [s],
        ``startup_initial_acceleration.alpha<i>`` [mm/s^2] (i from 1, in the config's order); details
        ``{"alphas", "feed_mm_per_s", "order"}``; arrays ``startup.t`` and ``startup.alpha<i>.x / v / a``.
    """
    from scipy.optimize import brentq

    from research.interpolators.sigmoid import Blend, Ramp, SigmoidMotion

    t = np.linspace(0.0, sc.duration_s, sc.num)
    scalars, arrays = {}, {"startup.t": t}
    for i, alpha in enumerate(sc.alphas, start=1):
        motion = SigmoidMotion(((Ramp(sc.feed_mm_per_s), Blend(alpha, sc.order)),), 0.0)
        x, v, a, _ = motion.derivatives(t)
        k = int(np.argmax(v))
        lo, hi = t[max(k - 1, 0)], t[min(k + 1, t.size - 1)]
        acc = lambda s: float(motion.derivatives(s)[2])  # noqa: E731
        peak = brentq(acc, lo, hi, xtol=1e-15) if acc(lo) > 0 > acc(hi) else float(t[k])  # else: at the span's end
        scalars |= {f"startup_peak_feed.alpha{i}": float(motion.derivatives(peak)[1]), f"startup_peak_time.alpha{i}": peak,
                    f"startup_initial_acceleration.alpha{i}": float(a[0])}
        arrays |= {f"startup.alpha{i}.x": x, f"startup.alpha{i}.v": v, f"startup.alpha{i}.a": a}
    details = {"alphas": list(sc.alphas), "feed_mm_per_s": sc.feed_mm_per_s, "order": sc.order}
    return scalars, details, arrays


def five_axis_contour_stage(fc) -> tuple[dict, dict, dict]:
    """Thesis §4.5 (:func:`research.contour.five_axis_contour_study`) with ``fc``'s drives and sample period.

    Returns:
        ``(scalars, details, arrays)``: ``five_axis.max_actual_contour_error`` [mm] and, per estimator
        (basic, shifted, compensated), ``five_axis.mean_estimator_error.<name>`` (mean |estimate - exact| over the
        moving samples) and ``five_axis.max_estimator_error.<name>`` [mm]; details ``{"samples", "moving"}``;
        arrays ``five_axis.t``, ``five_axis.exact``, ``five_axis.<name>``, ``five_axis.delay`` [s].
    """
    from research import drives
    from research.contour import five_axis_contour_study

    axes = ("x", "y", "z", "a", "c")  # the axis order of the eq 4.36 trajectory (thesis Table 6.3)
    axis_drives = tuple(getattr(drives, PER_AXIS_DRIVES[fc.drive])(a) for a in axes)
    st = five_axis_contour_study(drives=axis_drives, sample_period=fc.sample_period_ms * 1e-3, friction=fc.friction)
    moving = np.linalg.norm(np.asarray(st.reference.v)[:, :3], axis=1) > fc.moving_speed_ratio * 50.0
    scalars = {"five_axis.max_actual_contour_error": float(np.max(st.exact))}
    arrays = {"five_axis.t": st.t, "five_axis.exact": st.exact, "five_axis.delay": np.asarray(st.estimates.delay)}
    for name in ("basic", "shifted", "compensated"):
        d = st.discrepancy(name)
        scalars |= {f"five_axis.mean_estimator_error.{name}": float(np.mean(d[moving])),
                    f"five_axis.max_estimator_error.{name}": float(np.max(d))}
        arrays[f"five_axis.{name}"] = np.asarray(getattr(st.estimates, name))
    return scalars, {"samples": int(st.t.size), "moving": int(np.count_nonzero(moving))}, arrays
