"""Command line: ``python -m research run CONFIG``, ``python -m research sweep CONFIG``,
``python -m research figures``, ``python -m research store verify|gc`` and
``python -m research tune LOG --path NAME`` (FIR delays from an accelerometer log, issue 20) and
``python -m research export TRAJECTORY.npz --csv FILE --gcode FILE`` (issue 16 item 7).

Errors of the input or the file system (:class:`~research.errors.ResearchError`, any ``OSError``) print
one line ``error: ...`` and exit with status 2; ``--debug`` prints the traceback as well."""

from __future__ import annotations

import argparse
import json
import sys
import time
import traceback
from pathlib import Path

from research.errors import ConfigError, ResearchError

#: ``--help`` text (the module docstring without its reST markup)
DESCRIPTION = ("Run experiment configs (run, sweep), regenerate the paper figures (figures), check or clean the "
               "results store (store verify|gc), tune FIR delays from an accelerometer log (tune LOG --path NAME) "
               "and export a stored trajectory (export TRAJECTORY.npz --csv FILE --gcode FILE). Units: mm, s (the "
               "options name theirs). An input or file-system error prints one line 'error: ...' and exits with "
               "status 2; --debug prints the traceback as well.")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of every subcommand (each option's help states its unit and its default)."""
    parser = argparse.ArgumentParser(prog="python -m research", description=DESCRIPTION)
    parser.add_argument("--debug", action="store_true", help="print the traceback of an error")
    sub = parser.add_subparsers(dest="command", required=True)

    run = sub.add_parser("run", help="run one experiment config (TOML) and save results + figure")
    run.add_argument("config", type=Path, help="experiment file, e.g. experiments/sencer2015_diamond.toml")
    run.add_argument("--cache", type=Path, default=Path(".cache/results"), help="results root (default .cache/results)")
    run.add_argument("--figures", type=Path, default=Path("paper_figures"), help="figure folder (default paper_figures)")
    run.add_argument("--force", action="store_true", help="recompute even when the store has the result")
    run.add_argument("--results", type=Path, default=Path("results"),
                     help="results folder: <results>/<name>/ gets results.json, arrays, figure, config, report.md "
                          "(default results)")

    sw = sub.add_parser("sweep", help="run (or resume) the [sweep] of an experiment config")
    sw.add_argument("config", type=Path, help="experiment file with a [sweep] table, e.g. experiments/sensitivity_delays.toml")
    sw.add_argument("--cache", type=Path, default=Path(".cache/results"), help="results root (default .cache/results)")
    sw.add_argument("--figures", type=Path, default=Path("paper_figures"), help="figure folder (default paper_figures)")
    sw.add_argument("--engine", choices=("auto", "vmap", "dask", "serial"), help="sweep engine (default: the config's sweep.engine, itself auto by default)")
    sw.add_argument("--scheduler", metavar="ADDRESS", help="Dask scheduler (default: a LocalCluster)")
    sw.add_argument("--workers", type=int, help="LocalCluster worker processes (default: CPU count)")
    sw.add_argument("--retry-failed", action="store_true", help="recompute points stored as failures")
    sw.add_argument("--no-progress", action="store_true", help="no progress bar")
    sw.add_argument("--results", type=Path, default=Path("results"),
                    help="results folder: <results>/<name>/ gets table.json/.npz, figure, config, report.md (default results)")

    figs = sub.add_parser("figures", help="regenerate the registered paper figures")
    figs.add_argument("--only", action="append", metavar="NAME", help="only this figure (repeatable; default: every registered figure)")
    figs.add_argument("--out", type=Path, default=Path("paper_figures"), help="output folder (default paper_figures)")
    figs.add_argument("--list", action="store_true", help="list the registered figures and exit")
    figs.add_argument("--cache", type=Path, default=Path(".cache/results"),
                      help="results store of the config figures (default .cache/results)")
    figs.add_argument("--results", type=Path, default=Path("results"),
                      help="readable results of the config figures: <results>/<name>/ (default results)")

    st = sub.add_parser("store", help="check or clean the results store")
    st_sub = st.add_subparsers(dest="action", required=True)
    for name, text in (("verify", "check every entry against its manifest of SHA-256 checksums (exit 1 if any is bad)"),
                       ("gc", "remove damaged entries and leftovers of interrupted writes")):
        a = st_sub.add_parser(name, help=text)
        a.add_argument("--cache", type=Path, default=Path(".cache/results"), help="results root (default .cache/results)")
        if name == "gc":
            a.add_argument("--stale-code", action="store_true", help="also remove entries of other code versions")
            a.add_argument("--dry-run", action="store_true", help="list what would be removed, remove nothing")

    tn = sub.add_parser("tune", help="accelerometer log(s) -> modes -> FIR delays (eq 10) -> a config, "
                                     "with the residual vibration before and after")
    tn.add_argument("logs", type=Path, nargs="+", help="resonance-test log(s): .csv (#time,accel_x,accel_y,accel_z), .npz, .mat")
    tn.add_argument("--path", required=True, help="named path the tuned config runs, e.g. diamond")
    tn.add_argument("--out", type=Path, help="config to write (default tuned_<first log stem>.toml)")
    tn.add_argument("--feed", type=float, default=250.0, help="feed F [mm/s] (default 250)")
    tn.add_argument("--tolerance-um", type=float, default=500.0, help="cornering tolerance [um] (default 500)")
    tn.add_argument("--before-ms", type=float, nargs="+", default=[148.0, 89.0], help="delays to compare against [ms] (default 148 89: Sencer 2015 §4)")
    tn.add_argument("--k", type=int, choices=(1, 2), default=1, help="eq 10 zero: 1 (shortest delay; default) or 2")
    tn.add_argument("--unit", default="mm/s^2", help="acceleration unit of the log: mm/s^2 (Klipper; default), m/s^2 or g")
    tn.add_argument("--time-unit", default="s", help="time unit of the log: s (default), ms or us")
    tn.add_argument("--full-scale", type=float, help="sensor range [the unit of --unit] (samples at it are clipping; default none: a flat top at a "
                    "column's extreme is flagged instead)")
    tn.add_argument("--band", type=float, nargs=2, metavar=("LO", "HI"), help="band to search [Hz] (default: 3 PSD bins to 0.8 x Nyquist)")
    tn.add_argument("--window", choices=("boxcar", "hann"), default="boxcar",
                    help="boxcar: whole record (sweeps, tones; default); hann: Welch (random excitation)")
    tn.add_argument("--resolution-hz", type=float, help="PSD bin width [Hz] (default: 1 / record length)")

    ex = sub.add_parser("export", help="a stored trajectory (.npz, e.g. results/<name>/trajectory.npz) to CSV and/or "
                                       "a G-code stream")
    ex.add_argument("trajectory", type=Path, help="trajectory file written by a run (Trajectory.save)")
    ex.add_argument("--csv", type=Path, help="CSV to write: t [s], q, v, a, j per axis [mm, mm/s, mm/s^2, mm/s^3], units in the header")
    ex.add_argument("--gcode", type=Path, help="G-code stream to write: one G1 per sample, F its mean speed [mm/min]; "
                    "coordinates in mm")
    ex.add_argument("--tolerance-um", type=float, default=0.0, help="G64 P tolerance of the stream [um] (default 0: G61, exact path)")

    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return {"run": _run, "sweep": _sweep, "figures": _figures, "store": _store, "tune": _tune,
                "export": _export}[args.command](args)
    except (ResearchError, OSError) as e:
        if args.debug:
            traceback.print_exc()
        print(f"error: {_one_line(e)}", file=sys.stderr)
        return 2


def _one_line(e: BaseException) -> str:
    """The message of ``e``; a plain ``OSError`` as ``<file>: <reason>`` (no traceback)."""
    if isinstance(e, OSError) and not isinstance(e, ResearchError):
        where = " -> ".join(str(f) for f in (e.filename, e.filename2) if f)
        text = f"{where}: {e.strerror or e}" if where else str(e) or type(e).__name__
        return f"{text} ({type(e).__name__}; --debug for the traceback)"
    return str(e)


def _store(args) -> int:
    from research.experiments.store import gc_store, verify_store

    root = args.cache / "store"
    if args.action == "verify":
        good, problems = verify_store(root)
        for p in problems:
            print(f"BAD {p.folder}: {p.reason}")
        print(f"{root}: {good} valid entries, {len(problems)} problems")
        return 1 if problems else 0
    problems, stale = gc_store(root, dry_run=args.dry_run, stale_code=args.stale_code)
    verb = "would remove" if args.dry_run else "removed"
    for p in problems:
        print(f"{verb} {p.folder}: {p.reason}")
    for f in stale:
        print(f"{verb} {f}: written by another code version")
    print(f"{root}: {verb} {len(problems)} damaged entries or leftovers, {len(stale)} stale entries")
    return 0


#: File suffixes of G-code programs, which ``run`` does not take in place of a config.
GCODE_SUFFIXES = (".nc", ".ngc", ".gcode", ".tap", ".cnc", ".mpf", ".eia")


def _run(args) -> int:
    from research.experiments import format_summary, run_experiment

    if Path(args.config).suffix.lower() in GCODE_SUFFIXES:
        raise ConfigError(
            f"{args.config}: a G-code program, not an experiment config (TOML); write a config with [path] "
            f'gcode = "{Path(args.config).name}" and [interpolator] kind = "fir", delays_ms (your machine\'s) and '
            "tolerance_um (where the program gives no G64 P), as experiments/cam_part_arc.toml, and run that")
    result = run_experiment(args.config, cache_dir=args.cache, figures_dir=args.figures, force=args.force,
                            results_dir=args.results)
    print()
    print(format_summary(result))
    print(f"\nresults: {result.results_file.parent}/ (report.md: summary and figure together)")
    return 0


def _sweep(args) -> int:
    from research.experiments.sweep import format_sweep, run_sweep

    result = run_sweep(args.config, cache_dir=args.cache, figures_dir=args.figures, engine=args.engine,
                       scheduler=args.scheduler, workers=args.workers, retry_failed=args.retry_failed,
                       show_progress=not args.no_progress, results_dir=args.results)
    print()
    print(format_sweep(result))
    print(f"\nresults: {result.table_file.parent}/ (report.md: summary and figure together)")
    return 0


def _figures(args) -> int:
    from research.figures import catalog, figure_module, render

    figures = catalog()  # names and descriptions from the modules' source: nothing heavy is imported
    if args.list:
        for name, entry in figures.items():
            print(f"{name}: {entry.reproduces}" + (f" [{entry.config}]" if entry.config else ""))
        return 0
    names = args.only or list(figures)
    unknown = [n for n in names if n not in figures]
    if unknown:
        raise ResearchError(f"unknown figure(s) {unknown}; registered: {sorted(figures)}")
    args.out.mkdir(parents=True, exist_ok=True)
    manifest = []
    started = time.perf_counter()
    for i, name in enumerate(names, 1):
        print(f"[{i}/{len(names)}] {name}: started ({time.perf_counter() - started:.0f} s elapsed) - "
              f"{figures[name].reproduces}", flush=True)
        start = time.perf_counter()
        module = figure_module(name)
        done = render(name, args.out, cache_dir=args.cache, results_dir=args.results)
        seconds = time.perf_counter() - start
        cached = " (from the store)" if done.run.cached else ""
        print(f"[{i}/{len(names)}] {name}: done in {seconds:.1f} s{cached}: " + ", ".join(str(f) for f in done.files),
              flush=True)
        checks = done.run.paper_checks()
        for c in checks:
            print(f"      paper: {c.line()}", flush=True)
        manifest.append({
            "name": name,
            "reproduces": module.REPRODUCES,
            "config": module.CONFIG,  # the experiment config the figure is made from
            "module": module.__name__,
            "files": [Path(f).name for f in done.files],
            "seconds": round(seconds, 2),
            "paper": [{"key": c.key, "value": c.value, "expected": c.expected, "tolerance": c.tolerance,
                       "source": c.source, "ok": c.ok, "reproduced": c.reproduced, "reason": c.reason} for c in checks],
        })
    (args.out / "manifest.json").write_text(json.dumps(manifest, indent=2))
    return 0


def _export(args) -> int:
    """``export``: a saved trajectory to CSV and/or G-code."""
    from research.experiments.export import trajectory_csv, trajectory_gcode
    from research.trajectory import Trajectory

    if args.csv is None and args.gcode is None:
        raise ResearchError("export: give --csv FILE and/or --gcode FILE")
    try:
        traj = Trajectory.load(args.trajectory)
    except (KeyError, ValueError) as e:
        raise ResearchError(f"{args.trajectory}: not a trajectory file written by a run ({e})") from None
    if args.csv is not None:
        args.csv.write_text(trajectory_csv(traj))
        print(f"wrote {args.csv} ({traj.n_samples} samples, axes {', '.join(traj.axes)})")
    if args.gcode is not None:
        args.gcode.write_text(trajectory_gcode(traj, args.tolerance_um * 1e-3))
        print(f"wrote {args.gcode}")
    return 0


def _tune(args) -> int:
    """``tune``: modes from the log(s), eq 10 delays, residual vibration before/after on the path, a config."""
    import numpy as np

    from research.experiments.config import load_config
    from research.experiments.fir_model import fir_metrics
    from research.paths import PATHS, named_path
    from research.vibration import (
        MARGIN_TOLERANCE,
        estimate_modes,
        format_robustness,
        load_accel_log,
        robustness_margin,
        robustness_table,
        tune_delays,
    )

    if args.path not in PATHS:
        raise ResearchError(f"--path: unknown path {args.path!r}; expected one of {sorted(PATHS)}")
    points = np.asarray(named_path(args.path).points)
    path_axes = ("x", "y", "z")[: points.shape[1]]
    chosen, unused = {}, []
    for file in args.logs:
        log = load_accel_log(file, unit=args.unit, time_unit=args.time_unit, full_scale=args.full_scale)
        if log.resampling:
            r = log.resampling
            print(f"{file}: irregular time stamps resampled ({r['method']}) to {r['median_period_s'] * 1e3:.4g} ms; "
                  f"largest step {r['max_step_s'] * 1e3:.4g} ms at t = {r['at_time_s']:.6g} s")
        survey = estimate_modes(log, band_hz=tuple(args.band) if args.band else None,
                                resolution_hz=args.resolution_hz, window=args.window)
        print(f"{file}: {log.n_samples} samples at {log.sample_rate:.6g} Hz, band {survey.band_hz[0]:.3g}-"
              f"{survey.band_hz[1]:.4g} Hz, resolution {survey.resolution_hz:.3g} Hz")
        for m in survey.modes:
            flags = f"  FLAGS: {', '.join(m.flags)}" if m.flags else ""
            print(f"  mode {m.axis}: {m.frequency_hz:.4f} +- {m.frequency_sd_hz:.4f} Hz, damping {m.damping:.4f} "
                  f"+- {m.damping_sd:.4f}{flags}")
        for ax, m in survey.dominant().items():
            if ax not in path_axes:
                unused.append(m)
            elif ax not in chosen or m.peak_psd > chosen[ax].peak_psd:
                chosen[ax] = m
    for m in unused:
        print(f"  not tuned: the {m.axis} mode at {m.frequency_hz:.4f} Hz (axis {m.axis!r} is not an axis of "
              f"path {args.path!r} {path_axes})")
    if not chosen:
        raise ResearchError(f"no mode on the axes {path_axes} of path {args.path!r} in {[str(f) for f in args.logs]}")
    modes = [chosen[a] for a in path_axes if a in chosen]
    tuned = tune_delays(modes, k=args.k)
    idx = tuple(path_axes.index(m.axis) for m in modes)
    hz = np.array([m.frequency_hz for m in modes])
    zeta = np.array([m.damping for m in modes])
    eps = args.tolerance_um * 1e-3

    def metrics(delays_s, f=hz, z=zeta, axes=idx):
        return fir_metrics(points, args.feed, np.asarray(delays_s), eps, f, z, axes=axes)

    before, after = metrics(np.asarray(args.before_ms) * 1e-3), metrics(np.asarray(tuned.delays_s))
    print(f"eq 10 (k = {args.k}): delays " + ", ".join(f"T{i + 1} = {T * 1e3:.2f} ms ({a} {f:.3f} Hz)" for i, (T, a, f)
          in enumerate(zip(tuned.delays_s, tuned.axes, tuned.frequencies_hz))))
    print(f"path {args.path}, F = {args.feed:g} mm/s, eps = {args.tolerance_um:g} um:")
    for label, m, d in (("before", before, args.before_ms), ("after", after, [T * 1e3 for T in tuned.delays_s])):
        per_mode = ", ".join(f"{mo.axis} {mo.frequency_hz:.3f} Hz {float(r) * 1e3:.3f} um" for mo, r in zip(modes, m["residual"]))
        exact = "" if bool(m["exact"]) else " (blocks shorter than T_d: closed form approximate)"
        print(f"  {label:6s} delays {[round(x, 2) for x in d]} ms: cycle time {float(m['cycle_time']):.4f} s, residual "
              f"vibration {per_mode}{exact}")

    def path_residual(i, f_true):  # i indexes the tuned (longest-delay-first) order
        j = [m.axis for m in modes].index(tuned.axes[i])
        return float(metrics(tuned.delays_s, np.array([f_true]), zeta[j:j + 1], (idx[j],))["residual"][0])

    print("robustness (true mode = estimate x (1 + error), delays kept); the estimates' own 2-sigma: " + ", ".join(
        f"{m.axis} +-{200 * m.frequency_sd_hz / m.frequency_hz:.2g} %" for m in modes))
    print(format_robustness(robustness_table(tuned, residual_fn=path_residual)))
    for r in robustness_margin(tuned):
        lo = "< -50 %" if r["low"] is None else f"{r['low'] * 100:+.1f} %"
        hi = "> +50 %" if r["high"] is None else f"{r['high'] * 100:+.1f} %"
        text = (f"R <= {MARGIN_TOLERANCE:.0%} for frequency errors {lo} .. {hi}" if r["ratio_at_estimate"] <= MARGIN_TOLERANCE
                else f"R = {r['ratio_at_estimate']:.3g} > {MARGIN_TOLERANCE:.0%} even at the estimate (damping)")
        print(f"  margin {r['axis']} {r['frequency_hz']:.3f} Hz: {text}")
    out = args.out or Path(f"tuned_{args.logs[0].stem}.toml")
    name = "".join(c if c.isalnum() or c in "_-." else "_" for c in out.stem)[:64]
    mode_lines = ", ".join(f'{{ axis = "{m.axis}", frequency_hz = {m.frequency_hz!r}, damping = {m.damping!r} }}' for m in modes)
    text = (f"# written by `python -m research tune` from {', '.join(str(f) for f in args.logs)} (issue 20)\n"
            f"# modes: " + "; ".join(f"{m.axis} {m.frequency_hz:.4f} +- {m.frequency_sd_hz:.4f} Hz, zeta {m.damping:.4f} "
                                      f"+- {m.damping_sd:.4f}" + (f" [{', '.join(m.flags)}]" if m.flags else "") for m in modes) + "\n"
            f'name = "{name}"\nreproduces = "FIR delays tuned by eq 10 (Sencer 2015) to modes measured in '
            f'{args.logs[0].name}"\n\n[path]\nname = "{args.path}"\n\n[interpolator]\nkind = "fir"\n'
            f"feed_mm_per_s = {float(args.feed)!r}\ndelays_ms = {[T * 1e3 for T in tuned.delays_s]!r}\n"
            f"tolerance_um = {float(args.tolerance_um)!r}\n\n[drive]\nmodel = \"ideal\"\nmodes = [{mode_lines}]\n")
    out.write_text(text)
    load_config(out)  # the written config must load (ConfigError otherwise)
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
