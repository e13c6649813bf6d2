"""Shared matplotlib style of every figure: the run and sweep figures here, and the paper figures
of :mod:`research.figures` (which import it through ``research.figures._style``)."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402

STYLE = {
    "figure.dpi": 110,
    "savefig.dpi": 150,
    "savefig.bbox": "tight",
    "font.size": 9,
    "axes.titlesize": 9,
    "axes.labelsize": 9,
    "legend.fontsize": 8,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "lines.linewidth": 1.2,
}

#: axis colours used across figures
AXIS_COLOURS = {"x": "tab:blue", "y": "tab:red", "z": "tab:green"}


def figure(*args, **kwargs):
    """``plt.subplots`` under the shared style."""
    with plt.rc_context(STYLE):
        return plt.subplots(*args, layout="constrained", **kwargs)


def mosaic(layout, **kwargs):
    """``plt.subplot_mosaic`` under the shared style."""
    with plt.rc_context(STYLE):
        return plt.subplot_mosaic(layout, layout="constrained", **kwargs)


def save(fig, path) -> None:
    """Save under the shared style and close the figure."""
    with plt.rc_context(STYLE):
        fig.savefig(path)
    plt.close(fig)
