"""Figure of a sweep: each metric against the swept fields (line for one field, map for a grid of two).

Example: ``plot_sweep(result, Path("paper_figures/sensitivity_delays.png"))`` after
:func:`~research.experiments.sweep.run_sweep`.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from research.experiments.store import atomic_write

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

    from research.experiments.config import ExperimentConfig, _models_in
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
        models = _models_in(field_info.annotation) or models
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


def plot_sweep(result, target: Path) -> Path:
    """Write the sweep's figure (PNG) to ``target`` atomically and return it."""
    from research.experiments.plot_style import figure, save

    fields = result.fields
    ok = [r for r in result.rows if r["status"] == "ok"]
    metrics = [k for k in ok[0] if k not in fields and not k.startswith("d_") and k != "index"
               and isinstance(ok[0][k], float)][:6]
    n = len(metrics)
    cols = min(n, 3)
    fig, axs = figure((n + cols - 1) // cols, cols, figsize=(4.2 * cols, 3.4 * ((n + cols - 1) // cols)), squeeze=False)
    x = [result.column(f) for f in fields]
    grid = result.config.sweep.mode == "grid" and len(fields) == 2
    for ax, m in zip(axs.ravel(), metrics):
        scale, unit = _SCALE.get(_UNITS.get(m.split(".")[0], "-"), (1.0, "-"))
        y = result.column(m) * scale
        if grid:
            u0, u1 = np.unique(x[0]), np.unique(x[1])
            z = np.full((u1.size, u0.size), np.nan)
            z[np.searchsorted(u1, x[1]), np.searchsorted(u0, x[0])] = y
            im = ax.pcolormesh(u0, u1, z, shading="nearest", cmap="viridis")
            if np.isfinite(z).sum() > 3 and np.nanmax(z) > np.nanmin(z):
                ax.contour(u0, u1, z, colors="w", linewidths=0.5, levels=8)
            fig.colorbar(im, ax=ax, label=f"{m} [{unit}]")
            ax.set(xlabel=field_label(fields[0], result.config), ylabel=field_label(fields[1], result.config))
        else:
            order = np.argsort(x[0])
            ax.plot(x[0][order], y[order], ".-" if len(fields) == 1 else ".", ms=3)
            ax.set(xlabel=field_label(fields[0], result.config), ylabel=f"{m} [{unit}]")
        ax.set_title(m)
    for ax in axs.ravel()[n:]:
        ax.axis("off")
    fig.suptitle(f"{result.config.name}: {result.config.reproduces}", fontsize=8)
    buf = io.BytesIO()
    save(fig, buf)
    return atomic_write(target, buf.getvalue())
