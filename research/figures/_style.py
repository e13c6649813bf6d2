"""The shared figure style, kept in :mod:`research.experiments.plot_style` (figures read from the
experiments layer; nothing there imports :mod:`research.figures`)."""

from research.experiments.plot_style import AXIS_COLOURS, STYLE, figure, mosaic, save

__all__ = ["AXIS_COLOURS", "STYLE", "figure", "mosaic", "save"]
