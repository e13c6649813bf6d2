"""Numerical constants of the G-code reader (mm)."""

import math

MM_PER_INCH = 25.4
#: Moves shorter than this [mm] (from the last emitted vertex) produce no segment and are recorded
#: in ``GCodeProgram.no_motion_lines``.
ZERO_LENGTH_MM = 1e-9
#: Largest angle one arc chord may span [rad], whatever ``chord_tolerance`` allows.
MAX_CHORD_ANGLE = 0.5 * math.pi
#: An arc needing more chords than this is refused (the tolerance is unreasonably small for it).
MAX_CHORDS_PER_ARC = 1_000_000
