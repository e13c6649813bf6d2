"""Numerical constants of the G-code reader (mm unless named otherwise)."""

import math

MM_PER_INCH = 25.4
#: Moves shorter than this [mm] (from the last emitted vertex) produce no segment and are recorded
#: in ``GCodeProgram.no_motion_lines``.
ZERO_LENGTH_MM = 1e-9
#: Largest angle one arc chord may span [rad], whatever ``chord_tolerance`` allows.
MAX_CHORD_ANGLE = 0.5 * math.pi
#: An arc needing more chords than this is refused (the tolerance is unreasonably small for it).
MAX_CHORDS_PER_ARC = 1_000_000
#: Largest absolute coordinate, arc centre, radius or tolerance the reader accepts [mm] (1 km).
#: Beyond it float64 leaves too few digits for the 1e-9 mm resolution of the path model (the
#: zero-length test of :class:`~research.paths.polyline.Polyline` is ``1e-12 * max |coordinate|``).
MAX_COORDINATE_MM = 1e6
#: Largest number of turns ``P`` of one ``G2``/``G3`` arc (keeps the arc-length quadrature of a spiral bounded).
MAX_ARC_TURNS = 10_000
#: Largest feed an ``F`` word may give [mm/min] (100 km/min, far above any machine).
MAX_FEED_MM_PER_MIN = 1e8

# LinuxCNC rs274ngc defaults (src/emc/rs274ngc/interp_internal.hh), used by interp_arc.cc
# arc_data_ijk / arc_data_r:
#: ``CENTER_ARC_RADIUS_TOLERANCE_MM = 2 * 0.01 * sqrt(2)`` mm: largest difference of the start and
#: end radius of a centre-format (I/J/K) arc under G21 ("any valid arc whose end points and/or
#: centre were rounded to 0.01 mm is accepted").
CENTER_ARC_RADIUS_TOLERANCE_MM = 2 * 0.01 * math.sqrt(2)
#: ``CENTER_ARC_RADIUS_TOLERANCE_INCH = 2 * 0.001 * sqrt(2)`` in: the same under G20 (in inches).
CENTER_ARC_RADIUS_TOLERANCE_INCH = 2 * 0.001 * math.sqrt(2)
#: ``SPIRAL_RELATIVE_TOLERANCE = 0.001``: a radius difference above the absolute tolerance is still
#: accepted while it is at most 0.1 % of the larger radius (a large spiral arc).
SPIRAL_RELATIVE_TOLERANCE = 0.001
#: A radius difference above this multiple of the absolute tolerance is refused whatever the radius.
#: LinuxCNC's G2/G3 documentation (docs/src/gcode/g-code.adoc, centre format arcs): "It is an error
#: if ... the distance from the current point to the center differs from the distance from the end
#: point to the center by more than (.05 inch/.5 mm) OR ((.0005 inch/.005mm) AND .1% of radius)":
#: the hard limit is 100 times the absolute tolerance of the second clause.
SPIRAL_HARD_LIMIT_FACTOR = 100.0
#: ``RADIUS_TOLERANCE_MM = 0.00005 in * 25.4`` = 0.00127 mm: an arc radius below this is a
#: zero-radius arc, and an ``R`` may be this much shorter than half the chord.
RADIUS_TOLERANCE_MM = 0.00005 * MM_PER_INCH
