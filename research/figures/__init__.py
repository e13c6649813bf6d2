"""Regenerated paper figures: one module per figure, each with ``NAME``, ``REPRODUCES`` and
``make_figure(out_dir, fast=False) -> list[Path]``. ``python -m research figures`` runs them all."""

from __future__ import annotations

import importlib
from types import ModuleType

#: registered figure modules, in the order they are regenerated
FIGURE_MODULES = (
    "research.figures.fir_spectrum",
    "research.figures.fir_cornering",
    "research.figures.sencer2015_fig6",
    "research.figures.drive_bode",
    "research.figures.dimarco2015_fig3",
    "research.figures.dimarco2015_mtp",
    "research.figures.prevost2012_fig5",
    "research.figures.prevost2012_fig6",
    "research.figures.contour_sencer2009_fig4_6",
    "research.figures.identification_ch6",
    "research.figures.sencer2009_fig3_11",
    "research.figures.vibration_calibration",
    "research.figures.sencer2009_fig5_7",
    "research.figures.sencer2009_fig5_9",
    "research.figures.sencer2009_fig5_10",
    "research.figures.sencer2009_fig5_feedforward",
)


def registry() -> dict[str, ModuleType]:
    """``{NAME: module}`` of every registered figure."""
    modules = [importlib.import_module(m) for m in FIGURE_MODULES]
    return {m.NAME: m for m in modules}
