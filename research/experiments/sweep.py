"""Sensitivity sweeps (``python -m research sweep CONFIG``).

A config with a ``[sweep]`` table (:class:`~research.experiments.config.SweepConfig`) is expanded
into points (:mod:`~research.experiments.sweep_points`); FIR/mode parameter points go through the
``jax.vmap`` fast path with autodiff sensitivities (:mod:`~research.experiments.sweep_vmap`), the
rest (and fast-path points whose closed forms are not exact) through the general path, serially or
on Dask (:mod:`~research.experiments.sweep_general`). Results are read from / written to the
content-addressed store as they come, so a re-run or an interrupted sweep recomputes nothing that
finished. The table goes to ``<cache>/sweeps/<name>/table.json`` (one row per point: swept values,
``status``, ``error``, metrics, ``d_<metric>/d_<input>``) and ``table.npz`` (numeric columns, NaN
where missing), the figure to ``paper_figures/<name>.png``.

Example (``[sweep]`` table of ``experiments/sensitivity_delays.toml``)::

    [sweep]
    mode = "grid"
    [sweep.parameters]
    "interpolator.delays_ms[0]" = { start = 120.0, stop = 180.0, num = 61 }
    "interpolator.delays_ms[1]" = { start = 70.0, stop = 110.0, num = 41 }
"""

from __future__ import annotations

import io
import json
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from tqdm.auto import tqdm

from research.errors import ConfigError
from research.experiments.config import ExperimentConfig, load_config
from research.experiments.runner import DEFAULT_CACHE, DEFAULT_FIGURES, config_key, hashed_config
from research.experiments.store import ResultStore, atomic_write
from research.experiments.sweep_envelope import OWN_CYCLE_TIME, PLANNED_AT, envelope_field, tolerance_envelope
from research.experiments.sweep_general import run_general
from research.experiments.sweep_points import expand
from research.experiments.sweep_vmap import eligible, run_fast, split


@dataclass(frozen=True)
class SweepResult:
    """A finished sweep.

    Attributes:
        config: the validated base config.
        fields: the swept fields, in order.
        rows: one dictionary per point (``index``, swept values, ``status``, ``error``, ``source``,
            metrics [s, mm], sensitivities).
        stats: counts (``points``, ``ok``, ``failed``, ``computed``, ``cached``, ``fast``, ``general``)
            and ``seconds``.
        table_file: ``table.json``; ``table.npz`` sits next to it.
        figure_file: the figure, or ``None``.
        base_sensitivities: fast-model derivatives at the base config (``None`` off the fast path).
    """

    config: ExperimentConfig
    fields: list[str]
    rows: list[dict]
    stats: dict
    table_file: Path
    figure_file: Path | None
    base_sensitivities: dict | None = field(default=None)

    def column(self, name: str) -> np.ndarray:
        """One column as floats (NaN where a row lacks it)."""
        return np.array([float(r.get(name, np.nan)) if _is_number(r.get(name)) else np.nan for r in self.rows])


def run_sweep(config_file: str | Path, *, cache_dir: str | Path = DEFAULT_CACHE, figures_dir: str | Path = DEFAULT_FIGURES,
              engine: str | None = None, scheduler: str | None = None, workers: int | None = None,
              retry_failed: bool = False, log=print, show_progress: bool = True,
              results_dir: str | Path | None = None) -> SweepResult:
    """Run (or resume) the sweep of ``config_file``.

    Args:
        results_dir: the readable folder ``<results_dir>/<name>/`` (``table.json``, ``table.npz``,
            ``figure.png``, ``config.toml`` as run, ``report.md``); ``None``: ``<cache_dir>/sweeps`` (the
            command line passes ``results/``).
        engine: overrides ``sweep.engine`` (``auto``, ``vmap``, ``dask``, ``serial``).
        scheduler: Dask scheduler address; ``None``: a ``LocalCluster`` when the engine is Dask.
        workers: LocalCluster worker processes (default: CPU count).
        retry_failed: recompute points stored as failures.
        log: progress messages; ``show_progress``: a tqdm bar.
    """
    t0 = time.perf_counter()
    cfg, base_dir = load_config(config_file)
    points = expand(cfg, config_file)
    engine = engine or cfg.sweep.engine
    store = ResultStore(Path(cache_dir) / "store")
    rows = {p.index: {"status": "error", "error": p.error, "source": "config"} for p in points if p.config is None}
    valid = [p for p in points if p.config is not None]
    reason = eligible(cfg, base_dir)
    fast, general = ([], valid) if (engine in ("dask", "serial") or reason) else split(valid, cfg)
    if engine == "vmap" and (reason or general):
        raise ConfigError(f"{config_file}: key 'sweep.engine': the vmap path cannot take this sweep "
                          f"({reason or 'a swept field is not an FIR or mode parameter'}); use auto, dask or serial")
    why_general = reason or (f"engine = {engine!r}" if engine in ("dask", "serial") else None)
    log(f"sweep {cfg.name}: {len(points)} points over {list(cfg.sweep.parameters)}"
        + (f", {len(rows)} invalid (refused by the schema)" if rows else "") + "; "
        + (f"{len(fast)} candidates for the vmap fast path (each checked against the closed forms' domain), "
           f"{len(general)} for the general path" if fast else
           f"all {len(valid)} on the general path ({why_general or 'a swept field is not an FIR or mode parameter'})"))
    bar = tqdm(total=len(points), disable=not show_progress, unit="pt", desc=cfg.name)
    bar.update(len(rows))
    stats = {"points": len(points), "fast": 0, "general": 0, "computed": 0, "cached": 0}
    base_sens = None
    if fast:
        # the bar advances only by the points the fast path keeps; the ones it hands back are counted
        # when the general path finishes them (the bar never goes back)
        fast_rows, redo, st = run_fast(fast, cfg, base_dir, store, chunk=cfg.sweep.chunk,
                                       with_sensitivities=cfg.sweep.sensitivities, progress=bar.update)
        for i, r in fast_rows.items():
            rows[i] = {"status": "ok", "error": None, "source": "vmap"} | _chosen(r, cfg)
        general += redo
        cached_rows = len(st["cached"] & set(fast_rows))
        stats["cached"] += cached_rows
        stats["computed"] += len(fast_rows) - cached_rows
        stats["fast"] = len(fast_rows)
        log(f"vmap fast path: {len(fast_rows)} points" + (
            f"; {len(redo)} outside the closed forms' domain (block shorter than the filter, or not finite) "
            "go to the general path" if redo else ""))
        if cfg.sweep.sensitivities:
            base_sens = _chosen(_base_sensitivities(cfg, base_dir, store), cfg) or None  # None: base outside the domain
    tasks = []
    for p in general:
        key = config_key(p.config, base_dir)
        entry = store.get(key)
        if entry is not None and not (retry_failed and entry.record.get("status") == "error"):
            rows[p.index] = _row(entry.record, "cached")
            stats["cached"] += 1
            bar.update(1)
        else:
            # the point as written (a default left out stays so: the program's F words on a G-code path)
            tasks.append((p.index, key, p.config.model_dump(mode="json", exclude_unset=True)))
    if tasks:
        general_engine = engine if engine in ("dask", "serial") else ("dask" if (scheduler or len(tasks) > 2) else "serial")
        log(f"general path: {len(tasks)} points to compute ({general_engine}"
            + (f", scheduler {scheduler}" if scheduler else "") + ")")
        done = run_general(tasks, base_dir, store, engine=general_engine, scheduler=scheduler, workers=workers,
                           progress=bar.update)
        rows |= {i: _row(rec, "general") for i, rec in done.items()}
        stats["computed"] += len(tasks)
    stats["general"] = len(general)
    bar.close()
    log(f"engines: {stats['fast']} points on the vmap fast path, {stats['general']} on the general path"
        + (f", {len(points) - len(valid)} invalid" if len(points) > len(valid) else ""))
    if cfg.sweep.sensitivities and stats["general"]:
        stats["sensitivities"] = (f"unavailable for the {stats['general']} general-path points (autodiff runs on the "
                                  "vmap fast path only" + (f"; {reason}" if reason else "") + ")")
    table = [{"index": p.index} | p.values | rows[p.index] for p in points]
    tol_field = envelope_field(cfg)
    if tol_field is not None and any(_is_number(r.get("cycle_time")) for r in table):  # (metrics may leave it out)
        table, moved = tolerance_envelope(table, tol_field, list(cfg.sweep.parameters))
        stats["tolerance_envelope"] = {"field": tol_field, "moved": moved}
        log(f"tolerance envelope over {tol_field}: {moved} of {len(table)} points run the faster plan of a tighter "
            "tolerance (own plans in column own_cycle_time; sweep.tolerance_envelope = false to keep them)")
    stats |= {"ok": sum(r["status"] == "ok" for r in table), "failed": sum(r["status"] != "ok" for r in table),
              "seconds": time.perf_counter() - t0}
    out = (Path(cache_dir) / "sweeps" if results_dir is None else Path(results_dir)) / cfg.name
    table_file = _write_table(out, cfg, table, stats, base_sens)
    result = SweepResult(cfg, list(cfg.sweep.parameters), table, stats, table_file, None, base_sens)
    if cfg.output.figure and stats["ok"]:
        from research.experiments.sweep_figure import plot_sweep

        figure_file = plot_sweep(result, Path(figures_dir) / f"{cfg.name}.png")
        atomic_write(out / "figure.png", figure_file.read_bytes())
        result = SweepResult(cfg, result.fields, table, stats, table_file, figure_file, base_sens)
    atomic_write(out / "config.toml", Path(config_file).read_bytes())
    files = ["table.json", "table.npz"] + (["figure.png"] if result.figure_file else []) + ["config.toml"]
    report = [f"# {cfg.name} (sweep)", "", f"Reproduces: {cfg.reproduces}", "",
              f"Config: `{config_file}` (copy: [config.toml](config.toml))", "",
              "## Summary", "", "```", format_sweep(result), "```", ""]
    if result.figure_file:
        report += ["## Figure", "", "![figure](figure.png)", ""]
    report += ["## Files", ""] + [f"- [{f}]({f})" for f in files] + [""]
    atomic_write(out / "report.md", "\n".join(report).encode())
    log(f"sweep results in {out}/ (report.md, {', '.join(files)})")
    return result


def _chosen(row: dict, cfg: ExperimentConfig) -> dict:
    """The metrics (and their derivatives) the config asks for; residual vibration only with modes."""
    wanted = set(cfg.metrics) if cfg.metrics is not None else None
    if not (cfg.drive and cfg.drive.modes):
        wanted = (wanted if wanted is not None else {k.split("/")[0].removeprefix("d_").split(".")[0] for k in row}) - {"residual_vibration"}
    if wanted is None:
        return row
    return {k: v for k, v in row.items() if k.split("/")[0].removeprefix("d_").split(".")[0] in wanted}


def _row(record: dict, source: str) -> dict:
    if record.get("status") == "error":
        return {"status": "error", "error": record["error"], "source": source}
    return {"status": "ok", "error": None, "source": source} | record.get("scalars", {})


def _base_sensitivities(cfg: ExperimentConfig, base_dir, store: ResultStore) -> dict:
    """Fast-model values and autodiff derivatives at the base config (one compiled call, stored)."""
    from research.experiments.sweep_points import Point

    rows, _, _ = run_fast([Point(-1, {}, cfg)], cfg, base_dir, store, chunk=1, with_sensitivities=True)
    row = rows.get(-1, {})
    return {k: v for k, v in row.items() if k in ("cycle_time", "max_corner_error", "residual_vibration") or k.startswith("d_")}


def _write_table(out: Path, cfg: ExperimentConfig, table: list[dict], stats: dict, base_sens) -> Path:
    """``table.json`` (rows + provenance) and ``table.npz`` (numeric columns), atomically."""
    columns = list(dict.fromkeys(k for r in table for k, v in r.items() if _is_number(v)))
    arrays = {k: np.array([float(r[k]) if _is_number(r.get(k)) else np.nan for r in table]) for k in columns}
    arrays["ok"] = np.array([r["status"] == "ok" for r in table])
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    atomic_write(out / "table.npz", buf.getvalue())
    doc = {"experiment": cfg.name, "reproduces": cfg.reproduces, "config": hashed_config(cfg) | {"sweep": cfg.sweep.model_dump(mode="json")},
           "stats": stats, "base_sensitivities": base_sens,
           "units": {c: metric_unit(c) for c in dict.fromkeys(k for r in table for k in r)
                     if c not in cfg.sweep.parameters and c not in ("index", "status", "error", "source")},
           "rows": table}
    return atomic_write(out / "table.json", json.dumps(doc, indent=1).encode())


def _is_number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def format_sweep(result: SweepResult) -> str:
    """Plain-text summary: counts, metric ranges over the ok points, sensitivities at the base config."""
    s = result.stats
    lines = [f"{result.config.name}: {s['points']} points, {s['ok']} ok, {s['failed']} failed; "
             f"{s['computed']} computed, {s['cached']} from the store; {s['fast']} vmap, {s['general']} general; "
             f"{s['seconds']:.1f} s", f"table: {result.table_file}"]
    if result.figure_file:
        lines.append(f"figure: {result.figure_file}")
    ok = [r for r in result.rows if r["status"] == "ok"]
    metrics = [k for k in (ok[0] if ok else {}) if k not in result.fields and _is_number(ok[0][k])
               and not k.startswith("d_") and k != "index"]
    for k in metrics:
        col = result.column(k)
        i, j = int(np.nanargmin(col)), int(np.nanargmax(col))
        unit = metric_unit(k)
        lines.append(f"  {k + ' [' + unit + ']':<34} min {col[i]:.6g} at {_at(result, i)}; max {col[j]:.6g} at {_at(result, j)}")
    if result.base_sensitivities:
        lines.append("at the base config (autodiff; metric units per input unit: T_i in s, eps in mm, F in mm/s):")
        lines += [f"  {k:<32} {v: .6g}" for k, v in result.base_sensitivities.items()]
    elif result.config.sweep.sensitivities and s["fast"]:
        lines.append(f"sensitivities at the base config: unavailable (it is outside the closed forms' domain); "
                     f"the {s['fast']} fast-path points have d_* columns in the table")
    elif result.config.sweep.sensitivities:
        lines.append("sensitivities: unavailable (autodiff d(metric)/d(T_i, eps, F) runs on the vmap fast path only; "
                     "this sweep has no point there)")
    if s.get("sensitivities") and s["fast"]:
        lines.append(f"sensitivities: {s['sensitivities']}")
    env = s.get("tolerance_envelope")
    if env:
        lines.append(f"tolerance envelope over {env['field']}: {env['moved']} points run the faster plan of a tighter "
                     "tolerance (planned_at_tolerance_um; their own plans' times in own_cycle_time)")
    failed = [r for r in result.rows if r["status"] != "ok"]
    for r in failed[:5]:
        lines.append(f"  failed point {r['index']} {_at(result, r['index'])}: {r['error'].splitlines()[0]}")
    return "\n".join(lines)


def metric_unit(column: str) -> str:
    """Unit of a table column (``cycle_time`` -> ``s``, ``residual_vibration.x`` -> ``mm``; ``d_a/d_b`` ->
    ``unit(a)/unit(b)``), from :data:`~research.experiments.config.METRIC_UNITS`."""
    from research.experiments.config import METRIC_UNITS

    if column.startswith("d_") and "/d_" in column:
        num, den = column[2:].split("/d_", 1)
        den_unit = {"eps": "mm", "F": "mm/s"}.get(den, "s" if den.startswith("T") else "-")
        return f"{metric_unit(num)}/({den_unit})"
    if column == PLANNED_AT:
        return "um"
    if column == OWN_CYCLE_TIME:
        return "s"
    return METRIC_UNITS.get(column.split(".")[0], "-")


def _at(result: SweepResult, i: int) -> str:
    return "(" + ", ".join(f"{f.split('.')[-1]}={result.rows[i][f]:g}" if _is_number(result.rows[i][f]) else f"{f}={result.rows[i][f]}"
                           for f in result.fields) + ")"
