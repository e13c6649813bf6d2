"""Tool-path geometry: polylines, the G-code reader/writer and named benchmark paths."""

from research.paths.gcode import GCodeProgram, parse_gcode, read_gcode, to_gcode
from research.paths.library import PATHS, named_path
from research.paths.polyline import Polyline

__all__ = ["GCodeProgram", "PATHS", "Polyline", "named_path", "parse_gcode", "read_gcode", "to_gcode"]
