"""Named benchmark tool paths from the papers [mm].

``named_path(name)`` returns a :class:`Polyline`; ``PATHS`` lists the names and their sources.
"""

from __future__ import annotations

import numpy as np

from research.errors import PathError
from research.paths.polyline import Polyline
from research.paths.toolpath import ToolPath


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


def random_program(rng: np.random.Generator, arcs: bool = True) -> ToolPath:
    """A seeded random 2-D CAM-like program of 3-9 blocks [mm]: a first line of 0.5-30 mm, then lines of
    0.02, 0.1, 0.5, 2, 10 or 30 mm at any turn and, with ``arcs``, (half the blocks) arcs of R 1-40 mm
    sweeping 0.2-3 rad, tangent or not. The draws come from ``rng`` in a fixed order, so a seed gives the
    same program on every run (the property tests and ``benchmarks/bench_cam.py`` share them)."""
    tp = ToolPath.from_polyline(Polyline([[0.0, 0.0], [rng.uniform(0.5, 30.0), 0.0]]))
    for _ in range(int(rng.integers(2, 9))):
        end = tp.ends[-1]
        if not arcs or rng.random() < 0.5:
            ang, length = rng.uniform(-np.pi, np.pi), rng.choice([0.02, 0.1, 0.5, 2.0, 10.0, 30.0])
            step = length * np.array([np.cos(ang), np.sin(ang)])
            tp = ToolPath(tp.start, np.vstack([tp.ends, end + step]), np.vstack([tp.centers, [[np.nan, np.nan]]]),
                          np.vstack([tp.normals, [[np.nan] * 3]]), np.concatenate([tp.sweeps, [0.0]]))
        else:
            radius, sweep, side = rng.uniform(1.0, 40.0), rng.uniform(0.2, 3.0), rng.choice([-1.0, 1.0])
            ang = rng.uniform(-np.pi, np.pi)
            centre = end + radius * np.array([np.cos(ang), np.sin(ang)])
            a0 = ang + np.pi
            tp = tp.then_arc(centre + radius * np.array([np.cos(a0 + side * sweep), np.sin(a0 + side * sweep)]),
                             centre, ccw=side > 0)
    return tp
