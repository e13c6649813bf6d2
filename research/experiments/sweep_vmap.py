"""The sweep fast path: :func:`~research.experiments.fir_model.fir_metrics` under ``jax.jit(jax.vmap)``.

Points that differ from the base config only in FIR feed, delays, tolerance and mode frequency or
damping are stacked into arrays and evaluated ``chunk`` at a time in one compiled call, with the
autodiff sensitivities (:func:`~research.experiments.fir_model.sensitivities`). Each chunk is one
store entry (keyed by the chunk's inputs, the path and the code version), so an interrupted sweep
resumes at the first unfinished chunk. Points where the closed forms are not exact (a block shorter
than the filter, :func:`fir_metrics` ``exact``) or not finite are handed back for the general path.
"""

from __future__ import annotations

from functools import partial

import jax
import jax.numpy as jnp
import numpy as np

from research.experiments.config import ExperimentConfig
from research.experiments.fir_model import SCALARS, fir_metrics, sensitivities
from research.experiments.store import ResultStore, result_key
from research.experiments.sweep_points import Point


def eligible(cfg: ExperimentConfig, base_dir=None) -> str | None:
    """``None`` when the fast path can evaluate ``cfg``'s kind of experiment, else the reason it cannot.

    ``base_dir`` is the folder G-code paths are read from (the config's): a program with arcs or
    ``G64 P`` tolerances goes to the general path, because the closed forms model one tolerance on a
    polyline while ``plan_fir`` keeps arcs as arcs and each block's ``G64 P`` tolerance."""
    if cfg.path is None or cfg.identification is not None:
        return "identification studies need the general path"
    if len(cfg.interpolators) != 1 or cfg.interpolators[0].kind != "fir":
        return "the fast path models one FIR interpolator"
    if cfg.interpolators[0].optimized:
        return "the optimized FIR (interpolator.optimized) needs the general path"
    if cfg.interpolators[0].limits is not None:
        return "the limit-holding FIR (interpolator.limits) needs the general path"
    if cfg.path.gcode is not None and "feed_mm_per_s" not in cfg.interpolators[0].model_fields_set:
        return "per-block G-code feeds need the general path"
    if cfg.drive is not None and cfg.drive.model != "ideal":
        return "catalog drive dynamics need the general path"
    if cfg.path.gcode is not None and base_dir is not None:
        from research.experiments.config import read_program

        program = read_program(cfg.path, base_dir)
        if np.any(program.blocks.is_arc):
            return "G-code arcs (planned as arcs) need the general path"
        if np.any(np.isfinite(program.block_tolerance)):
            return "the program's G64 P tolerances (per block) need the general path"
        if np.any(~np.isnan(program.block_pauses)):
            return "the program's G4 / M0 / M1 pauses need the general path"
    return None


def _skeleton(cfg: ExperimentConfig) -> dict:
    """The config with every fast-path parameter blanked (their count kept): points sharing it share
    everything the compiled model does not take as an input."""
    d = cfg.model_dump(mode="json", exclude={"name", "reproduces", "description", "output", "sweep"})
    ic = d["interpolator"][0]
    ic |= {"feed_mm_per_s": None, "tolerance_um": None, "delays_ms": len(ic["delays_ms"])}
    if d.get("drive"):
        d["drive"]["modes"] = [m | {"frequency_hz": None, "damping": None} for m in d["drive"]["modes"]]
    return d


def split(points: list[Point], base: ExperimentConfig) -> tuple[list[Point], list[Point]]:
    """``(fast, general)``: valid points the fast path can take, and the rest that validated."""
    ref = _skeleton(base)
    fast, general = [], []
    for p in points:
        if p.config is None:
            continue
        (fast if _skeleton(p.config) == ref else general).append(p)
    return fast, general


def inputs(points: list[Point]) -> dict[str, np.ndarray]:
    """Stacked model inputs [mm/s, s, mm, Hz, -] of fast-path points."""
    ics = [p.config.interpolators[0] for p in points]
    modes = [p.config.drive.modes if p.config.drive else [] for p in points]
    return {
        "feed": np.array([ic.feed_mm_per_s for ic in ics]),
        "delays": np.array([ic.delays_ms for ic in ics]) * 1e-3,
        "tolerance": np.array([ic.tolerance_um for ic in ics]) * 1e-3,
        "mode_hz": np.array([[m.frequency_hz for m in ms] for ms in modes]).reshape(len(points), -1),
        "mode_damping": np.array([[m.damping for m in ms] for ms in modes]).reshape(len(points), -1),
    }


@partial(jax.jit, static_argnames=("axes", "with_sensitivities"))
def _batch(points, feed, delays, tolerance, mode_hz, mode_damping, *, axes, with_sensitivities):
    def one(f, d, e, hz, z):
        m = fir_metrics(points, f, d, e, hz, z, axes=axes)
        out = {k: m[k] for k in SCALARS} | {"exact": m["exact"], "residual": m["residual"]}
        if with_sensitivities:
            out |= sensitivities(points, f, d, e, hz, z, axes=axes)
        return out

    return jax.vmap(one)(feed, delays, tolerance, mode_hz, mode_damping)


def run_fast(points: list[Point], base: ExperimentConfig, base_dir, store: ResultStore, *, chunk: int,
             with_sensitivities: bool, progress=None) -> tuple[dict[int, dict], list[Point], dict]:
    """Evaluate fast-path points chunk by chunk (cached chunks are read from ``store``).

    Returns:
        ``(rows, redo, stats)``: ``{point index: {column: value}}`` for exact, finite points; the points
        to send to the general path; ``{"chunks", "cached_chunks"}`` counts and
        ``"cached"``, the indices read from the store.
    """
    from research.experiments.config import build_path

    path, _ = build_path(base.path, base_dir)
    axes_letters = tuple(m.axis for m in base.drive.modes) if base.drive else ()
    axes = tuple(path.axes.index(a) for a in axes_letters)
    x = inputs(points)
    rows, redo, stats = {}, [], {"chunks": 0, "cached_chunks": 0, "cached": set()}
    for start in range(0, len(points), chunk):
        part = points[start:start + chunk]
        xs = {k: v[start:start + chunk] for k, v in x.items()}
        key = result_key({"path": path.points.tolist(), "axes": list(axes), "sens": with_sensitivities,
                          "inputs": {k: v.tolist() for k, v in xs.items()}}, kind="vmap-chunk")
        entry = store.get(key)
        stats["chunks"] += 1
        if entry is not None:
            cols = entry.arrays()
            stats["cached_chunks"] += 1
            stats["cached"] |= {p.index for p in part}
        else:
            pad = chunk - len(part)  # one compiled shape for every chunk
            padded = {k: np.concatenate([v, np.repeat(v[-1:], pad, axis=0)]) for k, v in xs.items()}
            out = _batch(jnp.asarray(path.points), **{k: jnp.asarray(v) for k, v in padded.items()},
                         axes=axes, with_sensitivities=with_sensitivities)
            cols = {k: np.asarray(v)[: len(part)] for k, v in out.items()}
            store.put(key, {"kind": "vmap-chunk", "points": len(part)}, cols)
        kept = 0
        for i, p in enumerate(part):
            row = {k: float(v[i]) for k, v in cols.items() if v.ndim == 1 and k != "exact"}
            for j, a in enumerate(axes_letters):
                row[f"residual_vibration.{a}"] = float(cols["residual"][i, j])
            if not axes_letters:
                row.pop("residual_vibration", None)
            if bool(cols["exact"][i]) and all(np.isfinite(v) for v in row.values()):
                rows[p.index] = row
                kept += 1
            else:
                redo.append(p)
        if progress is not None:  # only the points kept here: the ones handed back are counted where they finish
            progress(kept)
    return rows, redo, stats
