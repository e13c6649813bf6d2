"""Tool-path geometry: polylines, the G-code reader and named benchmark paths."""

from research.paths.library import PATHS, named_path
from research.paths.polyline import Polyline

__all__ = ["PATHS", "Polyline", "named_path"]
