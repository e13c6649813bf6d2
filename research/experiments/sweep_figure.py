"""Figure of a sweep: each metric against the swept fields (line for one field, map for a grid of two,
lines for a grid with a field of few values).

Example: ``plot_sweep(result, Path("paper_figures/sensitivity_delays.png"))`` after
:func:`~research.experiments.sweep.run_sweep`.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from research.experiments.store import atomic_write
from research.experiments.sweep_envelope import OWN_CYCLE_TIME, PLANNED_AT

_SCALE = {"s": (1.0, "s"), "mm": (1e3, "um"), "mm/s": (1.0, "mm/s"), "-": (1.0, "-")}
_UNITS = {"cycle_time": "s", "residual_vibration": "mm", "max_corner_error": "mm", "max_contour_error": "mm",
          "peak_feed": "mm/s", "max_tracking_error": "mm"}


def field_label(field: str, cfg) -> str:
    """Axis label of a swept field from the schema: the ``Field`` description with its symbol and unit
    (``"interpolator.delays_ms[0]"`` -> ``"FIR delays T_1 [ms]"``, ``"drive.modes[1].frequency_hz"`` ->
    ``"natural frequency [Hz] (mode 2, y)"``); the raw key where the schema has no description.

    Args:
        field: the swept field as written in ``[sweep.parameters]``.
        cfg: the base :class:`~research.experiments.config.ExperimentConfig` (picks the interpolator kind).
    """
    import re

    from research.experiments.config import ExperimentConfig
    from research.experiments.config_messages import models_in
    from research.experiments.sweep_points import parse_field

    try:
        parts = parse_field(field)
    except ValueError:
        return field
    models, node, desc, index, where = [ExperimentConfig], cfg, None, None, []
    for i, part in enumerate(parts):
        if isinstance(part, int):
            if desc is not None and i == len(parts) - 1:
                index = part  # an element of a list field (delays_ms[0])
            elif isinstance(node, list) and 0 <= part < len(node):
                node = node[part]
                models = [type(node)]
                if hasattr(node, "axis"):
                    where.append(f"mode {part + 1}, {node.axis}")
            continue
        if isinstance(node, list) and len(node) == 1:  # interpolator.x on a single interpolator
            node = node[0]
            models = [type(node)]
        field_info = next((m.model_fields[part] for m in models if part in m.model_fields), None)
        if field_info is None:
            return field
        desc = field_info.description
        node = getattr(node, part, None)
        models = models_in(field_info.annotation) or models
    if not desc:
        return field
    desc = re.sub(r"\s*\([^()]*\)$", "", desc)  # a trailing remark: "damping ratio [-] (2 %: ...)"
    if len(desc) > 48:  # a description, not a label: the key itself
        desc = str(parts[-1])
    if index is not None:
        desc = re.sub(r"\b([A-Za-z])_i\b", lambda m: f"{m.group(1)}_{index + 1}", desc)
        if f"_{index + 1}" not in desc:
            desc += f" [{index}]"
    return desc + (f" ({'; '.join(where)})" if where else "")


#: a grid field with at most this many values is drawn as one line per value (no invented map cells)
MAX_LINES = 6
#: a panel whose values spread less than this (relative) is constant: no colour map, no contours
CONSTANT_SPREAD = 1e-6
#: values spanning more than this ratio (all > 0) get a log colour scale
LOG_SPAN = 10.0


def colour_scale(z: np.ndarray) -> str:
    """``"constant"`` (spread below :data:`CONSTANT_SPREAD` of the largest value: solver noise, not a
    result), ``"log"`` (positive values spanning more than :data:`LOG_SPAN`) or ``"linear"``."""
    v = z[np.isfinite(z)]
    if v.size == 0:
        return "constant"
    top = np.max(np.abs(v))
    if np.ptp(v) <= CONSTANT_SPREAD * max(top, np.finfo(float).tiny):
        return "constant"
    return "log" if np.min(v) > 0 and np.max(v) / np.min(v) > LOG_SPAN else "linear"


def base_value(field: str, cfg):
    """The base config's value of a swept field (the paper's point for a paper config), or ``None``."""
    from research.experiments.sweep_points import parse_field

    try:
        node = cfg.model_dump()
        for part in parse_field(field):
            if isinstance(node, list) and isinstance(part, str) and len(node) == 1:
                node = node[0]
            node = node[part]
    except (ValueError, KeyError, IndexError, TypeError):
        return None
    return node if isinstance(node, (int, float)) and not isinstance(node, bool) else None


def eq10_nulls(field: str, cfg, lo: float, hi: float) -> list[tuple[float, str]]:
    """Where Sencer 2015 eq 10 puts a zero of the FIR chain on a mode of the config's drive, for a swept
    FIR delay: ``T = k / f`` [ms] within ``[lo, hi]``, labelled with the mode."""
    import re

    if not re.fullmatch(r"interpolator(\[\d+\])?\.delays_ms\[\d+\]", field) or cfg.drive is None:
        return []
    out = []
    for m in cfg.drive.modes:
        for k in range(1, 6):
            T = 1e3 * k / m.frequency_hz
            if lo <= T <= hi:
                out.append((T, f"eq 10: {k}/f_{m.axis} = {T:.1f} ms"))
    return out


def plot_sweep(result, target: Path) -> Path:
    """Write the sweep's figure (PNG) to ``target`` atomically and return it.

    One panel per metric: a line against one field; for a grid of two fields a colour map (log scale
    where the values span decades, no map for a constant metric) with the base config's point marked
    and eq 10's nulls drawn on swept FIR delays, or one line per value when a field has at most
    :data:`MAX_LINES` values."""
    from matplotlib.colors import LogNorm

    from research.experiments.plot_style import figure, save

    fields, cfg = result.fields, result.config
    ok = [r for r in result.rows if r["status"] == "ok"]
    metrics = [k for k in ok[0] if k not in fields and not k.startswith("d_") and k not in ("index", PLANNED_AT, OWN_CYCLE_TIME)
               and isinstance(ok[0][k], float)][:6]
    n = len(metrics)
    cols = min(n, 3)
    fig, axs = figure((n + cols - 1) // cols, cols, figsize=(4.2 * cols, 3.4 * ((n + cols - 1) // cols)), squeeze=False)
    x = [result.column(f) for f in fields]
    grid = cfg.sweep.mode == "grid" and len(fields) == 2
    base = [base_value(f, cfg) for f in fields]
    for ax, m in zip(axs.ravel(), metrics):
        scale, unit = _SCALE.get(_UNITS.get(m.split(".")[0], "-"), (1.0, "-"))
        y = result.column(m) * scale
        kind = colour_scale(y)
        if kind == "constant":
            ax.text(0.5, 0.5, f"{m} = {np.nanmax(y):.6g} {unit} at every point\n(spread below "
                              f"{CONSTANT_SPREAD:g} of it)", transform=ax.transAxes, ha="center", va="center", fontsize=8)
            ax.set(xticks=[], yticks=[])
        elif grid and min(np.unique(x[0]).size, np.unique(x[1]).size) <= MAX_LINES:
            few = 0 if np.unique(x[0]).size <= np.unique(x[1]).size else 1
            other = 1 - few
            for i, v in enumerate(np.unique(x[few])):
                sel = x[few] == v
                order = np.argsort(x[other][sel])
                ax.plot(x[other][sel][order], y[sel][order], "o-", ms=3, color=f"C{i}", label=f"{v:g}")
            ax.legend(title=field_label(fields[few], cfg), fontsize=6, title_fontsize=6)
            ax.set(xlabel=field_label(fields[other], cfg), ylabel=f"{m} [{unit}]")
            if kind == "log":
                ax.set_yscale("log")
        elif grid:
            u0, u1 = np.unique(x[0]), np.unique(x[1])
            z = np.full((u1.size, u0.size), np.nan)
            z[np.searchsorted(u1, x[1]), np.searchsorted(u0, x[0])] = y
            norm = LogNorm(np.nanmin(z), np.nanmax(z)) if kind == "log" else None
            im = ax.pcolormesh(u0, u1, z, shading="nearest", cmap="viridis", norm=norm)
            if np.isfinite(z).sum() > 3:
                levels = np.geomspace(np.nanmin(z), np.nanmax(z), 9)[1:-1] if kind == "log" else 8
                ax.contour(u0, u1, z, colors="w", linewidths=0.5, levels=levels)
            fig.colorbar(im, ax=ax, label=f"{m} [{unit}]" + (" (log scale)" if kind == "log" else ""))
            ax.set(xlabel=field_label(fields[0], cfg), ylabel=field_label(fields[1], cfg))
            for T, text in eq10_nulls(fields[0], cfg, u0.min(), u0.max()):
                ax.axvline(T, color="w", ls="--", lw=0.7)
                ax.text(T, u1.max(), text, color="w", rotation=90, va="top", ha="right", fontsize=5)
            for T, text in eq10_nulls(fields[1], cfg, u1.min(), u1.max()):
                ax.axhline(T, color="w", ls="--", lw=0.7)
                ax.text(u0.max(), T, text, color="w", va="bottom", ha="right", fontsize=5)
            if None not in base:
                ax.plot(*base, "r*", ms=9, mec="w", label="base config")
                ax.legend(loc="lower right", fontsize=6)
        else:
            order = np.argsort(x[0])
            ax.plot(x[0][order], y[order], ".-" if len(fields) == 1 else ".", ms=3)
            own = result.column(OWN_CYCLE_TIME) * scale if m == "cycle_time" else y
            if len(fields) == 1 and np.any(np.abs(own - y) > 0):  # the tolerance envelope took a tighter plan
                ax.plot(x[0][order], own[order], "x", ms=4, color="0.5", label="own plan (envelope: the faster "
                                                                               "plan of a tighter tolerance)")
                ax.legend(fontsize=6)
            if base[0] is not None and len(fields) == 1:
                ax.axvline(base[0], color="r", ls=":", lw=0.8, label="base config")
                ax.legend(fontsize=6)
            ax.set(xlabel=field_label(fields[0], cfg), ylabel=f"{m} [{unit}]")
            if kind == "log":
                ax.set_yscale("log")
        ax.set_title(m)
    for ax in axs.ravel()[n:]:
        ax.axis("off")
    fig.suptitle(f"{cfg.name}: {cfg.reproduces}", fontsize=8)
    buf = io.BytesIO()
    save(fig, buf)
    return atomic_write(target, buf.getvalue())
