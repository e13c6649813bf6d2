"""Named benchmark tool paths from the papers [mm].

``named_path(name)`` returns a :class:`Polyline`; ``PATHS`` lists the names and their sources.
"""

from __future__ import annotations

import numpy as np

from research.errors import PathError
from research.paths.polyline import Polyline


def corner90() -> Polyline:
    """A single 90 deg corner: (-50, 0) -> (0, 0) -> (0, 50)."""
    return Polyline([[-50.0, 0.0], [0.0, 0.0], [0.0, 50.0]])


def diamond() -> Polyline:
    """Sencer 2015 Fig 6a: the diamond (50,0) -> (0,50) -> (-50,0) -> (0,-50) -> (50,0), four 90 deg corners
    (three interior corners; the path starts and ends at rest at (50, 0))."""
    return Polyline([[50.0, 0.0], [0.0, 50.0], [-50.0, 0.0], [0.0, -50.0], [50.0, 0.0]])


def zigzag(n_points: int = 11, pitch: float = 10.0, amplitude: float = 5.0) -> Polyline:
    """(0,0), (10,5), (20,0), (30,5), ... with ``n_points`` vertices [mm]."""
    i = np.arange(n_points)
    return Polyline(np.column_stack([pitch * i, amplitude * (i % 2)]))


def sencer2015_fig4(length: float = 2.5) -> Polyline:
    """Sencer 2015 Fig 4a: two 2.5 mm G01 lines meeting at 90 deg; the first at +45 deg, the second
    at -45 deg, so X keeps its direction and Y reverses (F_y: +F sin 45 -> -F sin 45)."""
    c = length / np.sqrt(2.0)
    return Polyline([[0.0, 0.0], [c, c], [2 * c, 0.0]])


PATHS = {
    "corner90": (corner90, "single 90 deg corner, two 50 mm lines"),
    "diamond": (diamond, "Sencer 2015 Fig 6a diamond, 50 mm half-diagonal"),
    "zigzag": (zigzag, "11-point zigzag, 10 mm pitch, 5 mm amplitude"),
    "sencer2015_fig4": (sencer2015_fig4, "Sencer 2015 Fig 4: two 2.5 mm lines, 90 deg corner"),
}


def named_path(name: str) -> Polyline:
    """The benchmark path called ``name`` (one of ``PATHS``)."""
    try:
        return PATHS[name][0]()
    except KeyError:
        raise PathError(f"unknown path {name!r}; expected one of {sorted(PATHS)}") from None
