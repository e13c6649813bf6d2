"""Run one experiment config end to end (``python -m research run CONFIG``).

The result is looked up in the content-addressed store (:mod:`research.experiments.store`,
``<cache>/store/``) under the hash of the config, the code version and the input files; only a miss
computes (:func:`~research.experiments.evaluate.evaluate`). Either way the run leaves a readable
view in ``<cache>/<name>/`` (``results.json``, ``trajectory.npz``) and the figure in
``paper_figures/<name>.png``, all written atomically.

Example:
    >>> from pathlib import Path
    >>> import tempfile
    >>> tmp = Path(tempfile.mkdtemp())
    >>> _ = (tmp / "e.toml").write_text('name = "e"\\nreproduces = "-"\\n[path]\\nname = "corner90"\\n[output]\\nfigure = false\\n')
    >>> first = run_experiment(tmp / "e.toml", cache_dir=tmp / "c", log=lambda s: None)
    >>> again = run_experiment(tmp / "e.toml", cache_dir=tmp / "c", log=lambda s: None)
    >>> first.cached, again.cached, again.key == first.key
    (False, True, True)
"""

from __future__ import annotations

import io
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from research.experiments import json_text
from research.experiments.config import ExperimentConfig, input_files, load_config
from research.experiments.paper_numbers import check_paper_numbers
from research.experiments.store import COSMETIC, ResultStore, atomic_write, code_version, file_digest, result_key

if TYPE_CHECKING:
    from research.trajectory import Trajectory

DEFAULT_CACHE = Path(".cache") / "results"
DEFAULT_FIGURES = Path("paper_figures")
#: ``details`` entries of stages that are not interpolator runs
STAGE_DETAILS = ("identification", "vibration", "spectrum", "startup", "mtp", "five_axis_contour", "control",
                 "feedrate", "identified_contour", "identification_ch6", "optimality")
#: the visible results folder of the command line (one folder per experiment)
DEFAULT_RESULTS = Path("results")


@dataclass(frozen=True)
class RunResult:
    """What one run produced, and where it was written.

    Attributes:
        config: the validated config.
        key: its store key (hash of config + code version + input files).
        record: the results (``scalars`` with ``units``, ``details`` per interpolator, provenance).
        cached: the result came from the store (nothing was recomputed).
        results_file: ``<cache>/<name>/results.json``.
        figure_file: the figure, or ``None`` when ``output.figure`` is off.
    """

    config: ExperimentConfig
    key: str
    record: dict
    cached: bool
    results_file: Path
    figure_file: Path | None

    def trajectory(self) -> Trajectory:
        """The first interpolator's sampled trajectory (read back from ``trajectory.npz``)."""
        from research.trajectory import Trajectory

        return Trajectory.load(self.results_file.parent / "trajectory.npz")

    def arrays(self) -> dict[str, np.ndarray]:
        """The stored arrays (``arrays.npz``: ``<label>.t/q/v/a/j``, drive and stage outputs); empty if none."""
        return _read_npz(self.results_file.parent / "arrays.npz")

    def paper_checks(self) -> list:
        """The config's ``[[paper]]`` numbers against this result (:func:`check_paper_numbers`)."""
        return check_paper_numbers(self.config, self.record)


def hashed_config(cfg: ExperimentConfig) -> dict:
    """The part of a config that sets its results (cosmetic fields dropped), JSON-ready. On a G-code
    path it also says which interpolators take the program's F words (``feed_mm_per_s`` not
    written): a written 250 mm/s and the default 250 mm/s run different feeds there."""
    doc = cfg.model_dump(mode="json", exclude=set(COSMETIC))
    if cfg.path is not None and getattr(cfg.path, "gcode", None) is not None:
        doc["program_feeds"] = ["feed_mm_per_s" not in ic.model_fields_set for ic in cfg.interpolators]
    return doc


def config_key(cfg: ExperimentConfig, base: Path, *, kind: str = "point") -> str:
    """Store key of a config whose relative file names are read from ``base``.

    ``kind``: ``"point"`` for a sweep point's record (scalars only), ``"run"`` for a ``run`` entry (the
    full record with the trajectory and figure); the two never share an entry, so a ``run`` after a
    ``sweep`` of the same config cannot be served a sweep point's record (issue 16).
    """
    return result_key(hashed_config(cfg), {k: base / f for k, f in input_files(cfg).items()}, kind=kind)


def run_experiment(config_file: str | Path, *, cache_dir: str | Path = DEFAULT_CACHE,
                   figures_dir: str | Path = DEFAULT_FIGURES, log=print, force: bool = False,
                   results_dir: str | Path | None = None) -> RunResult:
    """Run the experiment in ``config_file`` (or fetch it from the store) and save its results and figure.

    Args:
        config_file: TOML experiment config (see :mod:`research.experiments.config`).
        cache_dir: the store is ``<cache_dir>/store``.
        figures_dir: where the figure goes (``<name>.png``).
        results_dir: the readable results folder ``<results_dir>/<name>/`` (``results.json``,
            ``trajectory.npz``, ``arrays.npz``, ``figure.png``, ``config.toml`` as run, ``report.md``, and
            ``drive_model.json`` from an identification stage: the model as ``save_identified`` writes it);
            ``None``: ``<cache_dir>`` (the command line passes ``results/``, :data:`DEFAULT_RESULTS`).
        log: progress callback taking one string (``print`` by default).
        force: recompute even if the store has the result (the entry is kept; the new one is not stored).

    Raises:
        ConfigError: a bad config. StoreError: the store or an output folder cannot be written.
    """
    cfg, base = load_config(config_file)
    store = ResultStore(Path(cache_dir) / "store")
    key = config_key(cfg, base, kind="run")
    entry = None if force else store.get(key)
    want_figure = cfg.output.figure and ((cfg.path is not None and cfg.feedrate is None) or cfg.control is not None)
    stem = cfg.name
    if cfg.sweep is not None:  # the sweep's own outputs keep their names; this run is the base point
        stem = f"{cfg.name}_base"
        log(f"note: {config_file} has a [sweep] table over {list(cfg.sweep.parameters)}; `run` computes only the "
            f"base point (the config without [sweep]) and writes it as {stem!r}; "
            f"`python -m research sweep {config_file}` runs the sweep")
    log(f"[1/3] {cfg.name}: key {key[:12]} (code {code_version()}) " + ("found in the store" if entry else "computing"))
    files: dict[str, bytes] = {}
    if entry is None:
        ev = _evaluate(cfg, base, log)
        record = {
            "experiment": cfg.name, "reproduces": cfg.reproduces, "key": key, "code_version": code_version(),
            "config": cfg.model_dump(mode="json"),
            "inputs": {k: file_digest(base / f) for k, f in input_files(cfg).items()},
        } | ev.record | _legacy_view(ev.record)
        runs = ev.objects.get("runs", [])
        if runs:
            buf = io.BytesIO()
            runs[0][2].save(buf)
            files["trajectory.npz"] = buf.getvalue()
            buf = None  # (its own copy of the bytes: hundreds of MB on a long program)
        if "drive_model.json" in ev.objects:
            files["drive_model.json"] = ev.objects["drive_model.json"]
        if want_figure:
            files["figure.png"] = _figure(cfg, ev)
        if not (force and store.get(key) is not None):  # force recomputes without touching a stored entry
            entry = store.put(key, record, ev.arrays, files)
            record, files = entry.record, {}
        cached = False
    else:
        record, cached = entry.record, True
        if want_figure and entry.file("figure.png") is None:  # stored by a run with output.figure = false
            ev = _evaluate(cfg, base, log)
            store.add_file(key, "figure.png", _figure(cfg, ev))
            entry, cached = store.get(key), False
    shown = ", ".join(f"{k} = {v:.6g} {record['units'][k]}" for k, v in record["scalars"].items())
    log(f"[2/3] results: {shown}")
    out = Path(cache_dir if results_dir is None else results_dir) / stem
    results_file = atomic_write(out / "results.json", json_text.dumps(record, indent=2).encode())
    # files of a stored entry are read back through their manifest checksums (never served damaged)
    stored = (lambda name: entry.read_bytes(name) if entry.file(name) else None) if entry else files.get
    written = ["results.json"]
    for name in ("trajectory.npz", "arrays.npz", "drive_model.json"):  # large: copied in pieces
        if entry:
            data = entry.chunks(name) if entry.file(name) else None
        else:
            data = files.get(name) if name != "arrays.npz" else _npz(ev.arrays)
        if data:
            atomic_write(out / name, data)
            written.append(name)
    figure_file = None
    if want_figure:
        png = stored("figure.png")
        figure_file = atomic_write(Path(figures_dir) / f"{stem}.png", png)
        atomic_write(out / "figure.png", png)
        written.append("figure.png")
    written += _export(cfg, record, out)
    atomic_write(out / "config.toml", Path(config_file).read_bytes())
    result = RunResult(cfg, key, record, cached, results_file, figure_file)
    result.paper_checks()  # a [[paper]] key the result does not have is a ConfigError now, not in a test later
    atomic_write(out / "report.md", _report(result, config_file, written + ["config.toml"]).encode())
    log(f"[3/3] results in {out}/ (results.json, report.md, config.toml"
        + "".join(f", {n}" for n in written[1:]) + ")" + (f"; figure: {figure_file}" if figure_file else "")
        + ("; (cached)" if cached else ""))
    return result


def _evaluate(cfg: ExperimentConfig, base: Path, log):
    """:func:`~research.experiments.evaluate.evaluate`, imported here: a run served from the store never
    imports it (nor JAX through it)."""
    from research.experiments.evaluate import evaluate

    return evaluate(cfg, base, log=lambda s: log(f"      {s}"))


def _export(cfg: ExperimentConfig, record: dict, out: Path) -> list[str]:
    """``output.export``: each interpolator's stored trajectory as ``<label>.csv`` / ``<label>.ngc`` in ``out``."""
    if not cfg.output.export:
        return []
    from research.experiments.export import trajectory_csv, trajectory_gcode
    from research.trajectory import Trajectory

    arrays = _read_npz(out / "arrays.npz")
    written = []
    for ic in cfg.interpolators:
        label = ic.label or ic.kind
        d = record["details"][label]
        t = arrays[f"{label}.t"]
        traj = Trajectory(t, *(arrays[f"{label}.{k}"] for k in ("q", "v", "a", "j")), np.float64(d["metrics"]["cycle_time"]),
                          None, tuple(d["metrics"]["axes"]), ic.sample_period_ms * 1e-3)
        if "csv" in cfg.output.export:
            atomic_write(out / f"{label}.csv", trajectory_csv(traj).encode())
            written.append(f"{label}.csv")
        if "gcode" in cfg.output.export:
            atomic_write(out / f"{label}.ngc", trajectory_gcode(traj, cfg.output.gcode_tolerance_um * 1e-3).encode())
            written.append(f"{label}.ngc")
    return written


def _read_npz(file: Path) -> dict[str, np.ndarray]:
    if not file.exists():
        return {}
    with np.load(file, allow_pickle=False) as data:
        return {k: data[k] for k in data.files}


def _npz(arrays: dict) -> bytes | None:
    if not arrays:
        return None
    buf = io.BytesIO()
    np.savez(buf, **{k: np.asarray(v) for k, v in arrays.items()})
    return buf.getvalue()


def _report(result: RunResult, config_file, files: list[str]) -> str:
    """``report.md``: what was run, the summary table and the figure together (Markdown)."""
    cfg = result.config
    lines = [f"# {cfg.name}", ""] + ([f"Reproduces: {cfg.reproduces}", ""] if cfg.reproduces else [])
    if cfg.description:
        lines += [cfg.description, ""]
    lines += [f"Config: `{config_file}` (copy: [config.toml](config.toml)); store key `{result.key}`; code "
              f"`{result.record.get('code_version', code_version())}`" + (" (served from the store)" if result.cached else ""), ""]
    if cfg.sweep is not None:
        lines += ["Base point only: the `[sweep]` table was not run (`python -m research sweep CONFIG` runs it).", ""]
    lines += ["## Summary", "", "```", format_summary(result), "```", ""]
    if "figure.png" in files:
        lines += ["## Figure", "", "![figure](figure.png)", ""]
    lines += ["## Files", ""] + [f"- [{f}]({f})" for f in files] + [""]
    return "\n".join(lines)


def _legacy_view(record: dict) -> dict:
    """``metrics`` and ``corners`` of the first interpolator, at the top level (the README's layout)."""
    runs = [v for k, v in record["details"].items() if k not in STAGE_DETAILS]
    if not runs:
        return {}
    first = runs[0]
    corners = {"turning_angle_deg": first["turning_angle_deg"]}
    corners |= {k: first[k] for k in ("overlap_times", "corner_errors") if k in first}
    return {"metrics": first["metrics"], "corners": corners,
            "units": record["units"] | {"time": "s", "length": "mm", "overlap_times": "s", "corner_errors": "mm"}}


def _figure(cfg: ExperimentConfig, ev) -> bytes:
    """PNG of the run (Sencer 2015 Fig 6a-b layout, every interpolator in the path and feed panels)."""
    from research.experiments.plot_style import save
    from research.experiments.run_figure import plot_run

    name = f"{cfg.name}: base point of the sweep (no [sweep] applied)" if cfg.sweep is not None else cfg.name
    title = name + (f"\n{cfg.reproduces}" if cfg.reproduces else "")
    if cfg.path is None:  # a [control] study without a tool path: the ch 5 error panels
        from research.experiments.control_figure import plot_control

        fig = plot_control(ev.arrays, ev.record["details"]["control"], title=title)
    else:
        fig = plot_run(ev.objects["path"], ev.objects["runs"], title=title)
    buf = io.BytesIO()
    save(fig, buf)
    return buf.getvalue()


def format_summary(result: RunResult) -> str:
    """A plain-text table of the run's results, with units."""
    rec, cfg = result.record, result.config
    rows = [("experiment", cfg.name)] + ([("reproduces", cfg.reproduces)] if cfg.reproduces else [])
    rows.append(("store key", result.key[:16] + (" (cached)" if result.cached else "")))
    if cfg.sweep is not None:
        rows.append(("note", f"base point only: [sweep] over {len(cfg.sweep.parameters)} field(s) not run "
                             "(python -m research sweep CONFIG runs it)"))
    runs = {k: v for k, v in rec["details"].items() if k not in STAGE_DETAILS}
    for (label, d), ic in zip(runs.items(), cfg.interpolators):
        m = d["metrics"]
        tag = f"{label}: " if len(runs) > 1 else ""
        if "path_blocks" in d:  # a G-code program: its blocks (arcs kept as arcs), not the chords of its polyline
            rows.append((f"{tag}blocks / arcs", f"{d['path_blocks']:,} / {d['path_arcs']:,}"))
        else:  # a polyline (or a record stored before the block counts were)
            n = len(d["turning_angle_deg"])
            rows.append((f"{tag}segments / corners", f"{n + 1:,} / {n:,}"))
        planner = d.get("planner", "plan_fir")
        rows.append((f"{tag}interpolator", ic.kind + (f" ({planner})" if ic.kind == "fir" and planner != "plan_fir" else "")))
        if ic.kind == "fir":
            rows += [(f"{tag}feed F [mm/s]", _range(np.asarray(d["feeds"]))),
                     (f"{tag}FIR delays T_i [ms]", ", ".join(f"{x:g}" for x in ic.delays_ms))]
        elif ic.kind == "time_optimal":
            rows.append((f"{tag}OCP status / iterations", f"{d['status']} / {d['iterations']}"))
        if hasattr(ic, "tolerance_um"):
            lo, hi = d.get("tolerance_um_range", (ic.tolerance_um, ic.tolerance_um))
            if lo == hi == ic.tolerance_um:
                rows.append((f"{tag}tolerance eps [um]", f"{ic.tolerance_um:g}"))
            else:  # the program's G64 P tolerances govern some blocks
                rows.append((f"{tag}tolerance eps [um]", f"{lo:g}" + (f" .. {hi:g}" if hi > lo else "")
                             + f" (the program's G64 P; {ic.tolerance_um:g} where it gives none)"))
        rows += [
            (f"{tag}cycle time [s]", f"{m['cycle_time']:.6f}"),
            (f"{tag}max corner error [um]", f"{m['max_corner_error'] * 1e3:.3f}"),
            (f"{tag}max contour error [um]", f"{m['max_contour_error'] * 1e3:.3f}"),
        ]
        if "overlap_times" in d:
            rows.append((f"{tag}overlap T_k [ms]", _range(np.asarray(d["overlap_times"]) * 1e3)))
        rows.append((f"{tag}peak feed [mm/s]", f"{m['peak_feed']:.3f}"))
        for k, axis in enumerate(m["axes"]):
            rows.append((f"{tag}peak |v|, |a|, |j| {axis} [mm/s^n]",
                         f"{m['peak_velocity'][k]:.1f}, {m['peak_acceleration'][k]:.1f}, {m['peak_jerk'][k]:.1f}"))
    shown = {"cycle_time", "max_corner_error", "max_contour_error", "peak_feed"}
    for k, v in rec["scalars"].items():
        if k.split(".")[-1] not in shown:
            unit = rec["units"][k]
            rows.append((f"{k} [um]", f"{v * 1e3:.3f}") if unit == "mm" else (f"{k} [{unit}]", f"{v:.6g}"))
    for c in result.paper_checks():
        rows.append((f"paper: {c.key}", f"{c.value:.6g} (paper {c.expected:.6g} +- {c.tolerance:.3g}, {c.source}): "
                                        + c.verdict))
    width = max(len(r[0]) for r in rows)
    return "\n".join(f"{k:<{width}}  {v}" for k, v in rows)


def _range(x: np.ndarray) -> str:
    if x.size == 0:
        return "-"
    return f"{x.min():.3f}" if np.ptp(x) < 1e-9 else f"{x.min():.3f} .. {x.max():.3f}"
