"""Named 5-axis tool paths as pose B-splines (:class:`~research.paths.pose_spline.PoseSpline`) for
feed-rate scheduling (Sencer 2009 thesis ch 3).

- :func:`eq436_spline`: the thesis' eq 4.36 test path (helical tip, varying A/C), fitted with a
  quintic B-spline in ``(P, O)``.
- :func:`blade_flank_path`: a public stand-in for the thesis' impeller path. The thesis' test path
  (Fig 3.8: 196 CL points of a jet-impeller blade, flank milling, 300 mm) is not public, so this path
  is generated here with the features the thesis describes: 300 mm long, the tool tip going around a
  blade-like loop whose curvature peaks near the start, in the middle and near the end (the
  "trailing and leading edges"), with a leaning tool axis that follows the blade normal, so the C
  table turns fastest where the tip curvature is highest.
"""

from __future__ import annotations

import numpy as np

from research.errors import PathError
from research.paths.kinematics5 import sencer2009_eq436, tool_orientation
from research.paths.pose_spline import PoseSpline

BLADE_LENGTH = 300.0  # mm, the length of the thesis' impeller path (§3.6)


def eq436_spline(n_samples: int = 801) -> PoseSpline:
    """Thesis eq 4.36 path (tip length 273.87 mm) as a quintic pose B-spline through ``n_samples``
    samples of ``l`` in ``[0, 4 pi]`` (with 801 samples the tip length is within 1e-9 mm)."""
    return PoseSpline.from_five_axis_path(sencer2009_eq436(n_samples))


def blade_flank_poses(n_samples: int = 601, length: float = BLADE_LENGTH) -> tuple[np.ndarray, np.ndarray]:
    """Tool tips [mm] and tool axes of :func:`blade_flank_path`, ``(n_samples, 3)`` each.

    Geometry, for ``theta`` from ``-0.45`` to ``2 pi - 0.25`` rad:

        tip  = k [50 cos(theta), 25 sin(theta) + 10, 12 (theta - theta_0) / (theta_1 - theta_0)]   [mm]
        lean = 15 deg + 10 deg sin^2(theta)
        O    = cos(lean) z + sin(lean) n(theta),   n = outward unit normal of the loop in the xy plane

    with ``k`` chosen so that the tip path is ``length`` mm long. The loop's curvature peaks at
    ``theta = 0, pi, 2 pi`` (the ends of the major axis, 1/k * 0.08 /mm), i.e. near 8 %, 50 % and
    92 % of the path; the tool axis leans 15-25 deg from vertical (``a`` never reaches the ``a = 0``
    singularity) and turns with the blade normal (``c`` sweeps about 1.1 turns).
    """
    if not (isinstance(n_samples, (int, np.integer)) and n_samples >= 50):
        raise PathError(f"blade_flank_poses: n_samples must be an integer >= 50, got {n_samples!r}")
    if not (np.isfinite(length) and length > 0):
        raise PathError(f"blade_flank_poses: length must be > 0 mm, got {length!r}")
    th0, th1 = -0.45, 2 * np.pi - 0.25
    th = np.linspace(th0, th1, int(n_samples))

    def tip(scale, theta):
        return scale * np.column_stack([50 * np.cos(theta), 25 * np.sin(theta) + 10, 12 * (theta - th0) / (th1 - th0)])

    fine = np.linspace(th0, th1, 200001)
    unit_length = float(np.sum(np.linalg.norm(np.diff(tip(1.0, fine), axis=0), axis=1)))
    P = tip(length / unit_length, th)
    normal = np.column_stack([25 * np.cos(th), 50 * np.sin(th), np.zeros_like(th)])
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    lean = np.radians(15.0 + 10.0 * np.sin(th) ** 2)
    O = np.cos(lean)[:, None] * np.array([0.0, 0.0, 1.0]) + np.sin(lean)[:, None] * normal
    return P, O


def blade_flank_path(n_samples: int = 601, length: float = BLADE_LENGTH) -> PoseSpline:
    """The public blade-flank path of :func:`blade_flank_poses` as a quintic pose B-spline."""
    P, O = blade_flank_poses(n_samples, length)
    return PoseSpline.from_poses(P, O, degree=5, name="blade_flank")


def helix_path(turns: float = 1.0, radius: float = 20.0, pitch: float = 5.0, n_per_turn: int = 64,
               centre: float = 30.0) -> PoseSpline:
    """A helix around the vertical line through ``(centre, 0)`` [mm] with the tool axis tilted 20 deg
    towards it: a short, smooth path for tests and for scaling studies (length grows linearly with
    ``turns``). Off the C axis, the C table's turning moves X and Y too."""
    if not (turns > 0 and radius > 0 and pitch >= 0 and n_per_turn >= 8):
        raise PathError(f"helix_path: need turns > 0, radius > 0, pitch >= 0, n_per_turn >= 8; got {turns}, {radius}, {pitch}, {n_per_turn}")
    th = np.linspace(0.0, 2 * np.pi * turns, max(int(np.ceil(n_per_turn * turns)) + 1, 7))
    P = np.column_stack([centre + radius * np.cos(th), radius * np.sin(th), pitch * th / (2 * np.pi)])
    O = tool_orientation(np.full_like(th, np.radians(20.0)), th + np.pi / 2)
    return PoseSpline.from_poses(P, np.asarray(O), degree=5, name=f"helix_{turns:g}")
