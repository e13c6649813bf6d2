"""Programs with arcs for the FIR benchmarks: CAM-style arc-fitted passes and seeded arc chains.

* :func:`arc_fitted` turns a chord polyline into G-code the way a CAM post's arc filter does: runs
  of consecutive points that lie within ``fit_tol`` of one circle become one ``G2``/``G3`` block
  (G17, centre ``I J`` incremental, 4 decimals like real posts), the rest stay ``G1`` lines; the
  text is read back with ``parse_gcode``, so the arcs carry the rounding of real files (radius
  mismatches up to a few um, accepted as LinuxCNC does).
* :func:`freeform_passes` gives bench_cam's freeform curve as flat waterline passes (``z`` of each
  pass constant: G17 arcs cannot follow the 3-D curve's waviness), tessellated at one chord
  tolerance.
* :func:`offset_pocket` is a rectangular pocket of offset rings with small corner fillets (CAM
  corner smoothing) joined by stepovers.
* :func:`arc_chain` is a seeded chain of tangent arcs of alternating sense with a line every
  ``line_every`` arcs (``1``: every arc between two lines), the shape of arc-fitted contours.

Fitting is greedy from the first point: the span grows while every point and every chord middle
of it is within ``fit_tol`` of the circle through its first, middle and last points and the
points turn one way; radii outside ``[R_MIN, R_MAX]`` are left as lines.
"""

from __future__ import annotations

import numpy as np

import bench_cam
from research.paths.gcode import parse_gcode
from research.paths.toolpath import ToolPath

R_MIN, R_MAX = 0.5, 2000.0  # radii [mm] an arc filter emits (beyond: lines)


def _circle(a: np.ndarray, b: np.ndarray, c: np.ndarray):
    """Centre (2,) and radius of the circle through three 2-D points, or None (collinear)."""
    d = 2.0 * (a[0] * (b[1] - c[1]) + b[0] * (c[1] - a[1]) + c[0] * (a[1] - b[1]))
    if abs(d) < 1e-12:
        return None
    sa, sb, sc = a @ a, b @ b, c @ c
    centre = np.array([sa * (b[1] - c[1]) + sb * (c[1] - a[1]) + sc * (a[1] - b[1]),
                       sa * (c[0] - b[0]) + sb * (a[0] - c[0]) + sc * (b[0] - a[0])]) / d
    return centre, float(np.linalg.norm(a - centre))


def _fits(p: np.ndarray, i: int, j: int, fit_tol: float):
    """``(centre, ccw)`` if points ``i..j`` of ``p`` (n, 2) lie on one arc within ``fit_tol``, else None."""
    seg = p[i: j + 1]
    found = _circle(seg[0], seg[(j - i) // 2], seg[-1])
    if found is None:
        return None
    centre, radius = found
    if not R_MIN <= radius <= R_MAX:
        return None
    mids = 0.5 * (seg[1:] + seg[:-1])
    if np.max(np.abs(np.linalg.norm(np.vstack([seg, mids]) - centre, axis=1) - radius)) > fit_tol:
        return None
    d = np.diff(seg, axis=0)
    turn = d[:-1, 0] * d[1:, 1] - d[:-1, 1] * d[1:, 0]
    if not (np.all(turn > 0) or np.all(turn < 0)):
        return None
    ang = np.unwrap(np.arctan2(seg[:, 1] - centre[1], seg[:, 0] - centre[0]))
    if np.abs(ang[-1] - ang[0]) >= np.pi:  # half a turn at most per block, as arc filters emit
        return None
    return centre, bool(turn[0] > 0)


def arc_fitted(points: np.ndarray, fit_tol: float, feed_mm_per_min: float) -> tuple[str, dict]:
    """G-code of a 2-D or flat 3-D polyline ``points`` (n, 2|3) [mm], arcs where ``fit_tol`` [mm]
    allows (module docstring), and counts ``{"arcs", "lines"}``. ``z`` is taken from each point (a
    pass's points must share it for an arc)."""
    p3 = np.column_stack([points, np.zeros(len(points))]) if points.shape[1] == 2 else np.asarray(points)
    p = p3[:, :2]
    out = ["G21 G90 G17 G94", f"G1 X{p3[0, 0]:.4f} Y{p3[0, 1]:.4f} Z{p3[0, 2]:.4f} F{feed_mm_per_min:.1f}"]
    counts = {"arcs": 0, "lines": 0}
    i, n = 0, len(p)
    while i < n - 1:
        best, lo = None, i + 2
        step = 2
        while lo < n and p3[lo, 2] == p3[i, 2]:  # grow by doubling, then bisect the last step
            fit = _fits(p, i, lo, fit_tol)
            if fit is None:
                break
            best = (lo, fit)
            lo = min(lo + step, n - 1) if lo < n - 1 else n
            step *= 2
        if best is not None and best[0] + 1 < n:
            a, b = best[0] + 1, min(lo, n - 1)
            while a <= b:
                m = (a + b) // 2
                fit = _fits(p, i, m, fit_tol) if np.all(p3[i: m + 1, 2] == p3[i, 2]) else None
                if fit is not None:
                    best, a = (m, fit), m + 1
                else:
                    b = m - 1
        if best is None:
            out.append(f"G1 X{p3[i + 1, 0]:.4f} Y{p3[i + 1, 1]:.4f} Z{p3[i + 1, 2]:.4f}")
            counts["lines"] += 1
            i += 1
            continue
        j, (centre, ccw) = best
        ij = centre - p[i]
        out.append(f"{'G3' if ccw else 'G2'} X{p3[j, 0]:.4f} Y{p3[j, 1]:.4f} I{ij[0]:.4f} J{ij[1]:.4f}")
        counts["arcs"] += 1
        i = j
    out.append("M2")
    return "\n".join(out), counts


def freeform_passes(levels: int, chord_tol: float, seed: int = 0) -> np.ndarray:
    """bench_cam's waterline program (``cam_program``) with flat passes (each 0.2 mm lower, 0.5 %
    smaller), tessellated with sagitta ``chord_tol`` [mm] and rounded to 4 decimals: points (n, 3) [mm]."""
    return np.asarray(bench_cam.cam_program(seed, levels, chord_tol=chord_tol, flat=True)[0].points)


def arc_chain(n_arcs: int, seed: int, line_every: int) -> ToolPath:
    """A seeded 2-D chain of ``n_arcs`` tangent arcs (R 5-40 mm, 0.3-1.2 rad, alternating sense), a
    tangent line of 2-10 mm before every ``line_every``-th arc, written as G-code and read back."""
    rng = np.random.default_rng(seed)
    lines = ["G21 G90 G17 G94", "G1 X0 Y0 F12000"]
    p, heading = np.zeros(2), 0.0
    for k in range(n_arcs):
        if k % line_every == 0:
            p = p + rng.uniform(2.0, 10.0) * np.array([np.cos(heading), np.sin(heading)])
            lines.append(f"G1 X{p[0]:.4f} Y{p[1]:.4f}")
        radius, sweep, sense = rng.uniform(5.0, 40.0), rng.uniform(0.3, 1.2), 1.0 if k % 2 else -1.0
        centre = p + radius * sense * np.array([-np.sin(heading), np.cos(heading)])
        heading += sense * sweep
        end = centre - radius * sense * np.array([-np.sin(heading), np.cos(heading)])
        ij = centre - p
        lines.append(f"{'G3' if sense > 0 else 'G2'} X{end[0]:.4f} Y{end[1]:.4f} I{ij[0]:.4f} J{ij[1]:.4f}")
        p = end
    lines.append("M2")
    return parse_gcode("\n".join(lines)).blocks


def offset_pocket(rings: int, width: float = 60.0, height: float = 40.0, step: float = 2.0,
                  radius: float = 1.0) -> str:
    """G-code of a rectangular pocket cleared by ``rings`` offset contours, as a CAM post writes it:
    ring ``k`` is the ``width x height`` [mm] rectangle offset ``k step`` inwards, its corners
    rounded by G3 fillets of ``max(radius - 0.1 k, 0.3)`` mm (CAM corner smoothing), run counter-
    clockwise from the middle of its bottom side back to it; a G1 stepover joins each ring to the
    next (G17, 4 decimals, F 12000 mm/min). Read it with ``parse_gcode(text, start=(width / 2, 0, 0))``."""
    lines = ["G21 G90 G17 G94 F12000"]
    for k in range(rings):
        a = k * step
        w, h, r = width - 2 * a, height - 2 * a, max(radius - 0.1 * k, 0.3)
        if k:
            lines.append(f"G1 X{a + w / 2:.4f} Y{a:.4f}")
        lines += [f"G1 X{a + w - r:.4f} Y{a:.4f}", f"G3 X{a + w:.4f} Y{a + r:.4f} I0 J{r:.4f}",
                  f"G1 X{a + w:.4f} Y{a + h - r:.4f}", f"G3 X{a + w - r:.4f} Y{a + h:.4f} I{-r:.4f} J0",
                  f"G1 X{a + r:.4f} Y{a + h:.4f}", f"G3 X{a:.4f} Y{a + h - r:.4f} I0 J{-r:.4f}",
                  f"G1 X{a:.4f} Y{a + r:.4f}", f"G3 X{a + r:.4f} Y{a:.4f} I{r:.4f} J0", f"G1 X{a + w / 2:.4f} Y{a:.4f}"]
    lines.append("M2")
    return "\n".join(lines)


def slot(radius: float, length: float = 40.0) -> str:
    """G-code of a closed slot (obround) contour: two ``length`` [mm] sides joined by G3 half circles
    of ``radius`` [mm] about (length, 0) and (0, 0), run counter-clockwise from the middle of its lower
    side back to it (G17, 4 decimals, F 12000 mm/min). Read it with ``parse_gcode(text, start=(length
    / 2, -radius, 0))``."""
    r, L = radius, length
    return "\n".join(["G21 G90 G17 G94 F12000", f"G1 X{L:.4f} Y{-r:.4f}", f"G3 X{L:.4f} Y{r:.4f} I0 J{r:.4f}",
                      f"G1 X0 Y{r:.4f}", f"G3 X0 Y{-r:.4f} I0 J{-r:.4f}", f"G1 X{L / 2:.4f} Y{-r:.4f}", "M2"])
