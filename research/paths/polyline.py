"""`Polyline`: a tool path of straight (G01) segments in 1-3 dimensions [mm].

The geometry every corner-smoothing method works on: segment lengths, unit directions, turning
angles at the interior vertices, and the exact distance from any point to the path (a KD-tree over
short sub-segments gives candidates; exact point-segment projection decides).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from research.errors import PathError

#: sub-segment centres taken per query point by one k-nearest query in :meth:`Polyline.project`
#: (a point with more of them within its search radius gets a ball query). Swept on 265k samples of
#: a 24k-chord waterline program (benchmarks/README.md): 2 / 4 / 8 / 16 / 32 take 1.30 / 0.65 / 0.62
#: / 0.90 / 1.47 s against 1.45 s for ball queries alone; at 8, 19 points needed the ball query
_NEAREST_CENTRES = 8
#: query points projected at once by :meth:`Polyline.project` (its memory is this many points' worth)
_CHUNK = 1 << 16

DEFAULT_AXES = ("x", "y", "z")


@dataclass(frozen=True, eq=False)
class Polyline:
    """Vertices ``P_0 .. P_M`` joined by ``M`` straight segments.

    Args:
        points: ``(M + 1, d)`` vertices [mm], ``d`` in 1..3, ``M >= 1``.
        axes: axis names (default ``x, y, z`` cut to ``d``).

    Raises:
        PathError: fewer than two points, NaN/inf coordinates, or a zero-length segment (use
            :meth:`from_points` with ``merge_duplicates=True`` to drop repeated points on purpose).

    Example:
        >>> p = Polyline([[-50, 0], [0, 0], [0, 50]])
        >>> p.lengths.tolist(), round(float(np.degrees(p.turning_angles[0])), 6)
        ([50.0, 50.0], 90.0)
    """

    points: np.ndarray
    axes: tuple[str, ...] = ()
    _tree: dict = field(default_factory=dict, repr=False, compare=False)

    def __post_init__(self):
        pts = np.array(self.points, dtype=np.float64)
        if pts.ndim != 2 or pts.shape[0] < 2 or not 1 <= pts.shape[1] <= 3:
            raise PathError(f"Polyline needs (M+1, d) points with M >= 1 and d in 1..3, got shape {pts.shape}")
        bad = ~np.isfinite(pts)
        if bad.any():
            i, k = map(int, np.argwhere(bad)[0])
            raise PathError(f"Polyline point {i} has a non-finite coordinate {k}: {pts[i].tolist()}")
        lengths = np.linalg.norm(np.diff(pts, axis=0), axis=1)
        scale = max(1.0, float(np.max(np.abs(pts))))
        zero = np.flatnonzero(lengths <= 1e-12 * scale)
        if zero.size:
            i = int(zero[0])
            raise PathError(
                f"Polyline segment {i} (points {i} -> {i + 1}, at {pts[i].tolist()}) has zero length; "
                "remove repeated points or build with Polyline.from_points(..., merge_duplicates=True)"
            )
        axes = tuple(self.axes) or DEFAULT_AXES[: pts.shape[1]]
        if len(axes) != pts.shape[1]:
            raise PathError(f"Polyline has {pts.shape[1]} coordinates per point but axes {axes}")
        pts.setflags(write=False)
        object.__setattr__(self, "points", pts)
        object.__setattr__(self, "axes", axes)

    @staticmethod
    def from_points(points, axes: tuple[str, ...] = (), merge_duplicates: bool = False, tol: float = 1e-9) -> "Polyline":
        """Build a polyline, optionally dropping points closer than ``tol`` [mm] to the previous one."""
        pts = np.asarray(points, dtype=np.float64)
        if merge_duplicates and pts.ndim == 2 and len(pts) > 1:
            keep = np.concatenate([[True], np.linalg.norm(np.diff(pts, axis=0), axis=1) > tol])
            pts = pts[keep]
        return Polyline(pts, axes)

    # -- geometry ----------------------------------------------------------------------------
    @property
    def dim(self) -> int:
        return self.points.shape[1]

    @property
    def n_segments(self) -> int:
        return self.points.shape[0] - 1

    @property
    def lengths(self) -> np.ndarray:
        """Segment lengths ``L_k`` [mm], shape ``(M,)``."""
        return np.linalg.norm(np.diff(self.points, axis=0), axis=1)

    @property
    def length(self) -> float:
        """Total path length [mm]."""
        return float(self.lengths.sum())

    @property
    def arc_length(self) -> np.ndarray:
        """Cumulative arc length at each vertex [mm], shape ``(M + 1,)``, starting at 0."""
        return np.concatenate([[0.0], np.cumsum(self.lengths)])

    @property
    def directions(self) -> np.ndarray:
        """Unit direction ``u_k`` of each segment, shape ``(M, d)``."""
        return np.diff(self.points, axis=0) / self.lengths[:, None]

    @property
    def turning_angles(self) -> np.ndarray:
        """Change of direction ``beta_k`` at each interior vertex [rad], in ``[0, pi]``, shape ``(M - 1,)``.

        This is the cornering angle of Sencer 2015 (eq 12-14): 0 for collinear segments, pi for a
        full reversal.
        """
        u = self.directions
        # atan2(|u x w|, u . w) is accurate near 0 and pi, unlike arccos
        dot = np.sum(u[:-1] * u[1:], axis=1)
        cross = np.linalg.norm(u[1:] - u[:-1] * dot[:, None], axis=1)
        return np.arctan2(cross, dot)

    @property
    def corners(self) -> np.ndarray:
        """Interior vertices ``P_1 .. P_{M-1}``, shape ``(M - 1, d)``."""
        return self.points[1:-1]

    # -- distance ----------------------------------------------------------------------------
    def project(self, query) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Exact closest point on the path for each query point.

        Args:
            query: ``(N, d)`` points [mm].

        Returns:
            ``(distance [mm], segment index, parameter in [0, 1] along that segment)``, each ``(N,)``.
        """
        q = np.asarray(query, dtype=np.float64).reshape(-1, self.dim)
        if not np.all(np.isfinite(q)):
            raise PathError("Polyline.project: query points contain NaN or inf")
        if len(q) > _CHUNK:  # in chunks: the candidate arrays take ~200 bytes a point
            parts = [self._project(q[i:i + _CHUNK]) for i in range(0, len(q), _CHUNK)]
            return tuple(np.concatenate(x) for x in zip(*parts))
        return self._project(q)

    def _project(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`project` of finite points ``q`` ``(N, d)``."""
        tree, owner, h = self._subsegment_tree()
        # the K nearest sub-segment centres in one vectorized query (no per-point lists)
        K = min(_NEAREST_CENTRES, tree.n)
        dist_c, near = tree.query(q, k=K)
        dist_c, near = dist_c.reshape(len(q), K), near.reshape(len(q), K)
        # Upper bound: exact distance to the segment owning the nearest sub-segment centre.
        best_d, best_s, best_u = self._segment_distance(q, owner[near[:, 0]])
        # Every segment closer than best_d has a sub-segment centre within best_d + h/2: all of them
        # are among the K nearest unless the K-th lies within that radius (those points: a ball query)
        radius = best_d + 0.5 * h + 1e-12
        more = np.flatnonzero(dist_c[:, -1] <= radius) if K < tree.n else np.zeros(0, dtype=np.int64)
        keep = dist_c <= radius[:, None]
        keep[more] = False
        rows, cols = np.nonzero(keep)
        segs = owner[near[rows, cols]]
        if more.size:
            balls = tree.query_ball_point(q[more], radius[more])
            lens = np.fromiter((len(c) for c in balls), dtype=np.int64, count=len(balls))
            rows = np.concatenate([rows, np.repeat(more, lens)])
            segs = np.concatenate([segs, owner[np.concatenate([np.asarray(c, dtype=np.int64) for c in balls])]])
        d, _, u = self._segment_distance(q[rows], segs)
        order = np.lexsort((d, rows))
        first = np.ones(order.size, dtype=bool)
        first[1:] = rows[order][1:] != rows[order][:-1]
        pick = order[first]
        r = rows[pick]
        better = d[pick] < best_d[r]
        best_d[r[better]], best_s[r[better]], best_u[r[better]] = d[pick][better], segs[pick][better], u[pick][better]
        return best_d, best_s, best_u

    def distance(self, query) -> np.ndarray:
        """Exact distance [mm] from each query point ``(N, d)`` to the path, shape ``(N,)``."""
        return self.project(query)[0]

    def _segment_distance(self, q: np.ndarray, seg: np.ndarray):
        a = self.points[seg]
        ab = self.points[seg + 1] - a
        u = np.clip(np.sum((q - a) * ab, axis=1) / np.sum(ab * ab, axis=1), 0.0, 1.0)
        return np.linalg.norm(q - (a + u[:, None] * ab), axis=1), seg.astype(np.int64), u

    def _subsegment_tree(self):
        if "tree" not in self._tree:
            lengths = self.lengths
            h = float(np.median(lengths))
            pieces = np.maximum(1, np.ceil(lengths / h).astype(np.int64))
            owner = np.repeat(np.arange(self.n_segments), pieces)
            start = np.repeat(np.cumsum(pieces) - pieces, pieces)
            frac = (np.arange(owner.size) - start + 0.5) / pieces[owner]
            centres = self.points[owner] + frac[:, None] * (self.points[owner + 1] - self.points[owner])
            from scipy.spatial import cKDTree  # imported here: about 1 s that a cached run never needs

            self._tree["tree"] = (cKDTree(centres), owner, h)
        return self._tree["tree"]
