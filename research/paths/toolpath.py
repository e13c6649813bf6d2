"""`ToolPath`: a tool path of straight (G01) and circular (G02/G03) blocks, end to end [mm].

What a CAM program describes and a controller interpolates: lines and arcs, the arcs kept as arcs
(not chords) so an interpolator can treat them as curves. An arc block is a circle about an axis
``n`` (unit normal of its plane, the motion counter-clockwise about ``n``: ``G3`` in G17 has
``n = +z``, ``G2`` has ``n = -z``), swept through ``Phi > 0`` rad, possibly helical (a linear
displacement along ``n``) and possibly a spiral (start and end radius differ, the radius blended
linearly in angle, as LinuxCNC does for arcs whose end radius is within its tolerance)::

    P(phi) = c + (a0 + (a1 - a0) phi / Phi) n + (r0 + (r1 - r0) phi / Phi) (cos phi e1 + sin phi e2)

with ``e1`` the in-plane unit vector from the centre to the start, ``e2 = n x e1``, ``a0, a1`` the
axial offsets of start and end from the centre, ``0 <= phi <= Phi``.

Paths of 2 axes may hold arcs (their plane is the xy plane); 1-axis paths hold lines only.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from research.errors import PathError
from research.paths._toolpath_kernels import _arc_projection, _chord_turns, _nearest_arc, _nearest_line
from research.paths.polyline import DEFAULT_AXES, Polyline

_GAUSS = np.polynomial.legendre.leggauss(8)
_QUAD_ANGLE = 0.25 * np.pi  # Gauss-Legendre sub-interval of a spiral / helix length [rad]
#: query points per pass of :meth:`ToolPath.distance` (its candidate lists bounded: a program that
#: runs one contour 8 times took 7.6 GB for 1.4 million points in one pass); values do not depend on it
_DISTANCE_CHUNK = 1 << 14
#: tree samples whose blocks bound :meth:`ToolPath.distance` before a ball query is needed (the
#: search of ``Polyline.project``). Swept on 858,073 samples of a 76,461-chord program (2 / 4 / 8 /
#: 16 / 32: 1.92 / 0.81 / 0.79 / 1.29 / 2.64 s, the same distances; benchmarks/README.md)
NEAREST_SAMPLES = 8
#: sample points of :meth:`ToolPath._tree` per block, at most on average (8: the median block
#: length rules every program whose mean block is under 8 times its median)
TREE_SAMPLES = 8


@dataclass(frozen=True, eq=False)
class ToolPath:
    """Blocks ``0 .. M-1``; block ``k`` runs from ``ends[k - 1]`` (``start`` for ``k = 0``) to ``ends[k]``.

    Args:
        start: ``(d,)`` start point [mm], ``d`` in 1..3.
        ends: ``(M, d)`` end point of every block [mm].
        centers: ``(M, d)`` arc centres [mm] (any value, e.g. NaN, for lines); ``None``: all lines.
        normals: ``(M, 3)`` arc axes (unit vectors; motion counter-clockwise about them) or ``None``.
        sweeps: ``(M,)`` swept angle [rad]: 0 for a line, ``> 0`` for an arc (``2 pi k`` for ``k``
            full turns); ``None``: all lines.
        axes: axis names (default ``x, y, z`` cut to ``d``).

    Raises:
        PathError: bad shapes, non-finite coordinates, a zero-length block, an arc of zero radius,
            or an arc whose end point is not where its centre, axis and sweep put it (beyond
            ``1e-6 * radius + 1e-9`` mm).

    Example:
        >>> p = ToolPath.from_polyline(Polyline([[0, 0], [10, 0]])).then_arc([10, 10], [10, 5], ccw=True)
        >>> [round(float(x), 6) for x in p.lengths], p.is_arc.tolist()
        ([10.0, 15.707963], [False, True])
    """

    start: np.ndarray
    ends: np.ndarray
    centers: np.ndarray | None = None
    normals: np.ndarray | None = None
    sweeps: np.ndarray | None = None
    axes: tuple[str, ...] = ()
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    def __post_init__(self):
        start = np.array(self.start, dtype=np.float64).reshape(-1)
        ends = np.array(self.ends, dtype=np.float64)
        d = start.shape[0]
        if not 1 <= d <= 3 or ends.ndim != 2 or ends.shape[1] != d or ends.shape[0] < 1:
            raise PathError(f"ToolPath needs start (d,) and ends (M, d) with M >= 1, d in 1..3; got {start.shape}, {ends.shape}")
        M = ends.shape[0]
        sweeps = np.zeros(M) if self.sweeps is None else np.array(self.sweeps, dtype=np.float64).reshape(-1)
        if sweeps.shape != (M,) or not np.all(np.isfinite(sweeps)) or np.any(sweeps < 0):
            raise PathError(f"ToolPath.sweeps must be (M,) = ({M},) finite angles >= 0 rad, got {np.asarray(self.sweeps)!r}")
        arc = sweeps > 0
        if arc.any() and d == 1:
            raise PathError("ToolPath: a 1-axis path cannot hold arcs")
        centers = np.full((M, d), np.nan) if self.centers is None else np.array(self.centers, dtype=np.float64)
        normals = np.full((M, 3), np.nan) if self.normals is None else np.array(self.normals, dtype=np.float64)
        if centers.shape != (M, d) or normals.shape != (M, 3):
            raise PathError(f"ToolPath.centers must be (M, d) = ({M}, {d}) and normals (M, 3); got {centers.shape}, {normals.shape}")
        for name, a in (("start", start[None]), ("ends", ends), ("centers", centers[arc]), ("normals", normals[arc])):
            bad = ~np.isfinite(a)
            if bad.any():
                i = int(np.argwhere(bad)[0, 0])
                raise PathError(f"ToolPath.{name} has a non-finite value in row {i if name != 'centers' and name != 'normals' else int(np.flatnonzero(arc)[i])}")
        starts = np.vstack([start[None], ends[:-1]])
        geo = {}
        if arc.any():
            k = np.flatnonzero(arc)
            n = normals[k]
            norm = np.linalg.norm(n, axis=1)
            if np.any(np.abs(norm - 1.0) > 1e-9):
                raise PathError(f"ToolPath arc normal of block {int(k[np.argmax(np.abs(norm - 1.0))])} is not a unit vector")
            if d == 2 and np.any(np.abs(n[:, 2]) != 1.0):
                raise PathError("ToolPath: arcs of a 2-axis path must have normals (0, 0, +-1)")
            geo = _arc_geometry(_lift(starts[k]), _lift(ends[k]), _lift(centers[k]), n, sweeps[k])
            bad = geo["r0"] <= 1e-9
            if bad.any():
                raise PathError(f"ToolPath arc block {int(k[np.argmax(bad)])} has zero radius (centre on its start point)")
            miss = np.linalg.norm(geo["end_error"], axis=1)
            allowed = 1e-6 * np.maximum(geo["r0"], geo["r1"]) + 1e-9
            if np.any(miss > allowed):
                i = int(np.argmax(miss - allowed))
                raise PathError(f"ToolPath arc block {int(k[i])}: the end point is {miss[i]:.3g} mm from where its "
                                "centre, axis and sweep put it; expected a consistent arc")
            geo["index"] = k
        chord = np.linalg.norm(ends - starts, axis=1)
        lengths = chord.copy()
        if arc.any():
            lengths[arc] = geo["length"]
        scale = max(1.0, float(np.max(np.abs(np.vstack([start[None], ends])))))
        zero = np.flatnonzero(lengths <= 1e-12 * scale)
        if zero.size:
            raise PathError(f"ToolPath block {int(zero[0])} has zero length (at {starts[zero[0]].tolist()})")
        axes = tuple(self.axes) or DEFAULT_AXES[:d]
        if len(axes) != d:
            raise PathError(f"ToolPath has {d} coordinates per point but axes {axes}")
        for name, a in (("start", start), ("ends", ends), ("centers", centers), ("normals", normals), ("sweeps", sweeps)):
            a.setflags(write=False)
            object.__setattr__(self, name, a)
        object.__setattr__(self, "axes", axes)
        arc_row = np.full(starts.shape[0], -1, dtype=np.int64)  # row of each arc block in ``geo``, -1: a line
        arc_row[geo["index"] if geo else []] = np.arange(geo["index"].size if geo else 0)
        is_arc = arc.copy()
        is_arc.setflags(write=False)
        self._cache.update(geo=geo, lengths=lengths, starts=starts, arc_row=arc_row, is_arc=is_arc)

    # -- construction ------------------------------------------------------------------------
    @staticmethod
    def from_polyline(path: Polyline) -> "ToolPath":
        """The same path with every segment a line block."""
        return ToolPath(path.points[0], path.points[1:], axes=path.axes)

    def then_arc(self, end, center, *, ccw: bool, turns: int = 0, normal=None) -> "ToolPath":
        """This path with one more arc block from its end point to ``end`` about ``center`` [mm].

        ``ccw``: counter-clockwise about ``normal`` (default ``+z``, the G17 plane); ``turns``
        extra full turns. An ``end`` equal to the current end point is a full circle.
        """
        d = self.dim
        n = np.array([0.0, 0.0, 1.0] if normal is None else normal, dtype=np.float64)
        n = n / np.linalg.norm(n) * (1.0 if ccw else -1.0)
        s, e, c = _lift(self.ends[-1][None]), _lift(np.asarray(end, float).reshape(1, d)), _lift(np.asarray(center, float).reshape(1, d))
        e1, e2 = s - c, e - c
        e1 -= np.sum(e1 * n) * n
        e2 -= np.sum(e2 * n) * n
        ang = np.arctan2(np.sum(np.cross(e1, e2) * n), np.sum(e1 * e2)) % (2 * np.pi)
        if ang <= 1e-12:
            ang = 2 * np.pi if turns == 0 or ang <= 1e-12 else ang
        sweep = float(ang) + 2 * np.pi * turns
        return ToolPath(self.start, np.vstack([self.ends, np.asarray(end, float).reshape(1, d)]),
                        np.vstack([self.centers, np.asarray(center, float).reshape(1, d)]),
                        np.vstack([self.normals, n[None]]), np.concatenate([self.sweeps, [sweep]]), self.axes)

    def part(self, first: int, stop: int) -> "ToolPath":
        """Blocks ``first .. stop - 1`` as a path of their own, starting at vertex ``first``.

        Example:
            >>> p = ToolPath.from_polyline(Polyline([[0, 0], [10, 0], [10, 5], [0, 5]]))
            >>> q = p.part(1, 3)
            >>> q.start.tolist(), q.ends.tolist()
            ([10.0, 0.0], [[10.0, 5.0], [0.0, 5.0]])
        """
        if not 0 <= first < stop <= self.n_blocks:
            raise PathError(f"ToolPath.part: expected 0 <= first < stop <= {self.n_blocks} (blocks), got {first}, {stop}")
        start = self.start if first == 0 else self.ends[first - 1]
        return ToolPath(start, self.ends[first:stop], self.centers[first:stop], self.normals[first:stop],
                        self.sweeps[first:stop], self.axes)

    # -- geometry ----------------------------------------------------------------------------
    @property
    def dim(self) -> int:
        return self.start.shape[0]

    @property
    def n_blocks(self) -> int:
        return self.ends.shape[0]

    @property
    def is_arc(self) -> np.ndarray:
        """``(M,)`` True for arc blocks (read-only; made once: the planner reads it per candidate)."""
        return self._cache["is_arc"]

    @property
    def starts(self) -> np.ndarray:
        """``(M, d)`` start point of every block [mm]."""
        return self._cache["starts"]

    @property
    def lengths(self) -> np.ndarray:
        """``(M,)`` block lengths [mm] (arcs: exact for circles and helices, quadrature for spirals)."""
        return self._cache["lengths"]

    @property
    def length(self) -> float:
        return float(self.lengths.sum())

    @property
    def radii(self) -> np.ndarray:
        """``(M,)`` smallest radius of each arc block [mm], ``inf`` for lines."""
        r = np.full(self.n_blocks, np.inf)
        g = self._cache["geo"]
        if g:
            r[g["index"]] = np.minimum(g["r0"], g["r1"])
        return r

    @property
    def vertices(self) -> np.ndarray:
        """``(M - 1, d)`` junction points between consecutive blocks [mm]."""
        return self.ends[:-1]

    def tangents(self) -> tuple[np.ndarray, np.ndarray]:
        """Unit tangents ``(M, d)`` at the start and at the end of every block (made once, as every
        plan of the path reads them; copies returned, writable as compiled kernels take them)."""
        if "tangents" not in self._cache:
            self._cache["tangents"] = self._tangents()
        return tuple(t.copy() for t in self._cache["tangents"])

    def _tangents(self) -> tuple[np.ndarray, np.ndarray]:
        chord = self.ends - self.starts
        t_in = chord / np.linalg.norm(chord, axis=1, keepdims=True).clip(1e-300)
        t_out = t_in.copy()
        g = self._cache["geo"]
        if g:
            k = g["index"]
            for phi, out in ((np.zeros(k.size), t_in), (g["sweep"], t_out)):
                v = _arc_eval(g, phi, 1)
                out[k] = (v / np.linalg.norm(v, axis=1, keepdims=True))[:, : self.dim]
        return t_in, t_out

    def turning_angles(self) -> np.ndarray:
        """``(M - 1,)`` angle between the end tangent of block ``k`` and the start tangent of ``k + 1`` [rad]."""
        t_in, t_out = self.tangents()
        a, b = t_out[:-1], t_in[1:]
        dot = np.sum(a * b, axis=1)
        cross = np.linalg.norm(b - a * dot[:, None], axis=1)
        return np.arctan2(cross, dot)

    def arc_points(self, block, phi) -> np.ndarray:
        """Points ``P(phi)`` of arc block ``block`` at angles ``phi`` [rad] from its start, ``(N, d)``
        (``block``: one block, or one per angle)."""
        return self.arc_derivatives(block, phi, 0)

    def arc_derivatives(self, block, phi, order: int) -> np.ndarray:
        """``d^order P / d phi^order`` of arc block ``block`` at ``phi`` [mm / rad^order], ``(N, d)``
        (``block``: one block, or one per angle, ``(N,)``)."""
        phi = np.asarray(phi, dtype=np.float64).reshape(-1)
        blocks = np.broadcast_to(np.asarray(block, dtype=np.int64), phi.shape)
        return _arc_eval(self._arc_rows(blocks), phi, order)[:, : self.dim]

    def _arc_rows(self, blocks: np.ndarray) -> dict:
        rows = self._cache["arc_row"][blocks]
        if rows.size and rows.min() < 0:
            raise PathError(f"ToolPath block {int(blocks[np.argmin(rows)])} is not an arc")
        return _take(self._cache["geo"], rows)

    def to_polyline(self, chord_tolerance: float = 1e-3) -> tuple[Polyline, np.ndarray]:
        """Chords through every block: arcs cut into equal angles with sagitta <= ``chord_tolerance`` [mm].

        Returns:
            ``(polyline, block)``: the chords and the block index of every chord ``(M_chords,)``.
        """
        counts = self._chord_counts(chord_tolerance)
        g = self._cache["geo"]
        owner = np.repeat(np.arange(self.n_blocks), counts)
        pts = self.ends[owner]  # a block's last point is its end; an arc's others are its points
        inner = np.flatnonzero(owner[1:] == owner[:-1])  # chord ends inside one (arc) block
        if inner.size:
            blk = owner[inner]
            j = inner - (np.cumsum(counts) - counts)[blk] + 1  # the chord's index in its arc, from 1
            rows = self._cache["arc_row"][blk]
            phi = g["sweep"][rows] * j.astype(np.float64) / counts[blk].astype(np.float64)
            pts[inner] = _arc_eval(_take(g, rows), phi, 0)[:, : self.dim]
        return Polyline(np.vstack([self.start[None], pts]), self.axes), owner

    def _chord_counts(self, chord_tolerance: float) -> np.ndarray:
        """``(M,)`` chords per block: 1 for lines, equal angles of sagitta <= ``chord_tolerance`` [mm] on arcs."""
        counts = np.ones(self.n_blocks, dtype=np.int64)
        g = self._cache["geo"]
        arcs = np.flatnonzero(self._cache["arc_row"] >= 0)
        if arcs.size:
            rows = self._cache["arc_row"][arcs]
            r = np.maximum(g["r0"][rows], g["r1"][rows])
            step = np.minimum(4.0 * np.arcsin(np.sqrt(np.minimum(chord_tolerance / (2.0 * r), 1.0))), 0.5 * np.pi)
            counts[arcs] = np.maximum(1, np.ceil(g["sweep"][rows] / step).astype(np.int64))
        return counts

    def arc_chord_turns(self, chord_tolerance: float = 1e-3) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The turning of every arc block as small turns, where a curvature-driven computation needs
        it so: the direction changes between the chords of :meth:`to_polyline` (``n`` equal angles)
        at their vertices, and at a quarter chord from each end the turn from the arc's end tangent to
        its first chord and from its last chord to its end tangent (each stands for the half chord
        of turning the vertices leave out), so that an arc's turns add up to its whole turning
        ``t_out - t_in``.

        Returns:
            ``(block (N,), fraction (N,), du (N, d))``, ``n + 1`` rows per arc in path order: the arc
            block, the turn's share of the block's length (``1 / 4n``, ``j / n``, ``1 - 1 / 4n``:
            exact for circles and helices, whose arc length grows with the angle), and the change of
            unit direction there. One compiled pass over the arcs.
        """
        counts = self._chord_counts(chord_tolerance)
        arcs = np.flatnonzero(self._cache["arc_row"] >= 0)
        n = counts[arcs]
        c, nrm, e1, e2, r0, r1, a0, a1, sweep = self._geo_rows()
        block = np.repeat(arcs, n + 1)
        j = (np.arange(block.size) - np.repeat(np.cumsum(n + 1) - (n + 1), n + 1)).astype(np.float64)  # 0 .. n
        nb = np.repeat(n, n + 1).astype(np.float64)
        fraction = np.where(j == 0, 0.25 / nb, np.where(j == nb, 1.0 - 0.25 / nb, j / nb))
        t_in, t_out = self.tangents()
        du = _chord_turns(np.ascontiguousarray(self._cache["arc_row"][arcs]), n, _lift(self.starts[arcs]),
                          _lift(self.ends[arcs]), _lift(t_in[arcs]), _lift(t_out[arcs]), c, nrm, e1, e2, r0, r1,
                          a0, a1, sweep, block.size)
        return block, fraction, du[:, : self.dim]

    # -- distance ----------------------------------------------------------------------------
    def distance(self, query) -> np.ndarray:
        """Distance [mm] from each query point ``(N, d)`` to the path, ``(N,)``: exact for lines and
        planar arcs, three safeguarded Newton steps in the angle for helices and spirals (below
        1 nm for pitches and radius changes of CAM programs)."""
        q = np.asarray(query, dtype=np.float64).reshape(-1, self.dim)
        if not np.all(np.isfinite(q)):
            raise PathError("ToolPath.distance: query points contain NaN or inf")
        if len(q) > _DISTANCE_CHUNK:  # in chunks: each point's candidate list grows with the passes near it
            return np.concatenate([self._distance(q[i:i + _DISTANCE_CHUNK]) for i in range(0, len(q), _DISTANCE_CHUNK)])
        return self._distance(q)

    def _distance(self, q: np.ndarray) -> np.ndarray:
        """:meth:`distance` of finite points ``q`` ``(N, d)``, as :meth:`Polyline.project` takes it:
        the exact distance to the blocks owning the ``K`` nearest tree samples
        (:data:`NEAREST_SAMPLES`) bounds it from above (``best``); every
        block closer than ``best`` has a sample within ``best + h / 2`` (:meth:`_tree`), so where the
        ``K``-th nearest sample lies beyond that radius the bound is the distance, and the other
        points take a ball query of that radius. The minimum over a set of blocks that holds the
        nearest one, each block's distance the same arithmetic: the same values as ball queries
        alone, without their per-point lists (2.0 -> 0.80 s on the 858,073 samples of a
        76,461-chord program, benchmarks/README.md)."""
        tree, owner, h = self._tree()
        K = min(NEAREST_SAMPLES, tree.n)
        near_d, near = tree.query(q, k=K)
        near_d, near = near_d.reshape(len(q), K), near.reshape(len(q), K)
        best = self._nearest_of(q, owner[near])
        radius = best + 0.5 * h + 1e-12
        more = np.flatnonzero(near_d[:, -1] <= radius) if K < tree.n else np.zeros(0, dtype=np.int64)
        if more.size:
            balls = tree.query_ball_point(q[more], radius[more])
            lens = np.fromiter((len(c) for c in balls), dtype=np.int64, count=len(balls))
            rows = np.repeat(more, lens)
            blocks = owner[np.concatenate([np.asarray(c, dtype=np.int64) for c in balls])]
            pair = np.unique(rows * self.n_blocks + blocks)
            rows, blocks = pair // self.n_blocks, pair % self.n_blocks
            np.minimum.at(best, rows, self._block_distance(q[rows], blocks))
        return best

    def distance_bound(self, query, k: int = 8, near=None) -> np.ndarray:
        """An upper bound [mm] on :meth:`distance`: the exact distance to the blocks owning the ``k``
        sample points nearest to each query point, and their neighbours. Equal to the distance
        unless a block whose samples are all farther than ``k`` others is the closest one; cheap
        for dense paths where :meth:`distance`'s candidate balls hold thousands of blocks. What a
        tolerance check needs: a bound below the tolerance proves the point within it.
        ``near``: ``(N,)`` a block known to be close to each point (tried with its neighbours too)."""
        q = np.asarray(query, dtype=np.float64).reshape(-1, self.dim)
        tree, owner, _ = self._tree()
        k = min(k, tree.n)
        _, idx = tree.query(q, k=k)
        idx = np.asarray(idx).reshape(len(q), k)
        blocks = np.concatenate([owner[idx], np.clip(owner[idx[:, :1]] - 1, 0, None),
                                 np.clip(owner[idx[:, :1]] + 1, None, self.n_blocks - 1)], axis=1)
        if near is not None:
            near = np.asarray(near, dtype=np.int64).reshape(-1, 1)
            blocks = np.concatenate([blocks, np.clip(near + np.arange(-1, 2)[None, :], 0, self.n_blocks - 1)], axis=1)
        return self._nearest_of(q, blocks)

    def _nearest_of(self, q: np.ndarray, blocks: np.ndarray) -> np.ndarray:
        """``(N,)`` least distance [mm] from each point ``q[i]`` to the blocks ``blocks[i]`` ``(N, C)``."""
        if not self.is_arc[blocks].any():  # lines only: one compiled pass, the same arithmetic
            return _nearest_line(np.ascontiguousarray(q), np.ascontiguousarray(blocks), self.starts, self.ends)
        # each (point, block) pair once: the candidates repeat (nearest samples of one block, the
        # neighbours of ``near`` and of the nearest sample's owner); the minimum is the same
        blocks = np.sort(blocks, axis=1)
        fresh = np.ones(blocks.shape, dtype=bool)
        fresh[:, 1:] = blocks[:, 1:] != blocks[:, :-1]
        rows, cols = np.nonzero(fresh)
        d = np.full(blocks.shape, np.inf)
        d[rows, cols] = self._block_distance(q[rows], blocks[rows, cols])
        return d.min(axis=1)

    def _block_distance(self, q: np.ndarray, blocks: np.ndarray) -> np.ndarray:
        a, b = self.starts[blocks], self.ends[blocks]
        ab = b - a
        ab2 = np.sum(ab * ab, axis=1)
        # a full circle has a zero chord: its line distance is the distance to its start (replaced below)
        u = np.clip(np.sum((q - a) * ab, axis=1) / np.where(ab2 > 0, ab2, 1.0), 0.0, 1.0)
        out = np.linalg.norm(q - (a + u[:, None] * ab), axis=1)
        arc = self.is_arc[blocks]
        if arc.any():
            out[arc] = self.arc_distance(q[arc], blocks[arc])
        return out

    def arc_distance(self, query: np.ndarray, blocks: np.ndarray) -> np.ndarray:
        """Distance [mm] from each point ``query[i]`` ``(N, d)`` to arc block ``blocks[i]`` ``(N,)``
        (every one an arc), as :meth:`distance` takes it: projection angle, clamped to the sweep,
        then safeguarded Newton on ``|P(phi) - q|^2`` (exact in one step for planar circles). The
        projection angle is NumPy's ``arctan2`` (whose SIMD loop may differ from the C library's by
        an ulp) between two compiled passes that read the arc geometry by row
        (``_toolpath_kernels._arc_projection``, ``_nearest_arc``)."""
        c, n, e1, e2, r0, r1, a0, a1, sweep = self._geo_rows()
        rows = np.ascontiguousarray(self._cache["arc_row"][np.asarray(blocks)])
        q = np.ascontiguousarray(_lift(np.asarray(query, dtype=np.float64)))
        y, x = _arc_projection(q, rows, c, e1, e2)
        base = np.arctan2(y, x) % (2 * np.pi)
        return _nearest_arc(q, rows, base, c, n, e1, e2, r0, r1, a0, a1, sweep)

    def _geo_rows(self) -> tuple:
        """The arc geometry as contiguous arrays by arc row (cached): ``c, n, e1, e2, r0, r1, a0,
        a1, sweep``."""
        if "geo_rows" not in self._cache:
            g = self._cache["geo"]
            self._cache["geo_rows"] = tuple(np.ascontiguousarray(g[k]) for k in
                                            ("c", "n", "e1", "e2", "r0", "r1", "a0", "a1", "sweep"))
        return self._cache["geo_rows"]

    def _tree(self):
        """A k-d tree of sample points along the blocks, each block cut into pieces of about the
        median block length ``h`` (one sample per piece, at its middle), its owner blocks and the
        largest piece length. ``h`` is raised to ``1 / TREE_SAMPLES`` of the mean block length
        where that is longer: a program of micro-chords with one long line (a rapid to the part,
        a facing pass) would otherwise cut that line into its length over the chord length (1 m
        of line over 1 um chords: 10^9 points, tens of GB)."""
        if "tree" not in self._cache:
            h = max(float(np.median(self.lengths)), float(np.mean(self.lengths)) / TREE_SAMPLES)
            pieces = np.maximum(1, np.ceil(self.lengths / h).astype(np.int64))
            owner = np.repeat(np.arange(self.n_blocks), pieces)
            first = np.repeat(np.cumsum(pieces) - pieces, pieces)
            frac = (np.arange(owner.size) - first + 0.5) / pieces[owner]
            centres = self.starts[owner] + frac[:, None] * (self.ends[owner] - self.starts[owner])
            arc = self.is_arc[owner]
            if arc.any():
                g = self._arc_rows(owner[arc])
                centres[arc] = _arc_eval(g, frac[arc] * g["sweep"], 0)[:, : self.dim]
            # a sample point is within half an arc-length step (<= h / 2) of every point it stands for
            step = self.lengths[owner] / pieces[owner]
            from scipy.spatial import cKDTree  # imported here: a cached run never needs it

            self._cache["tree"] = (cKDTree(centres), owner, float(step.max()))
        return self._cache["tree"]


def _lift(p: np.ndarray) -> np.ndarray:
    """Pad points ``(N, d)`` to 3 coordinates."""
    return np.pad(p, ((0, 0), (0, 3 - p.shape[1])))


def _take(g: dict, rows: np.ndarray) -> dict:
    return {k: v[rows] for k, v in g.items() if k not in ("index", "end_error")}


def _arc_geometry(s, e, c, n, sweep) -> dict:
    """Frame, radii, axial offsets and length of arcs (all arrays ``(K, ...)``)."""
    rs, re = s - c, e - c
    a0, a1 = np.sum(rs * n, axis=1), np.sum(re * n, axis=1)
    p0 = rs - a0[:, None] * n
    r0 = np.linalg.norm(p0, axis=1)
    e1 = p0 / np.maximum(r0, 1e-300)[:, None]
    e2 = np.cross(n, e1)
    r1 = np.linalg.norm(re - a1[:, None] * n, axis=1)
    g = dict(c=c, n=n, e1=e1, e2=e2, r0=r0, r1=r1, a0=a0, a1=a1, sweep=sweep)
    g["end_error"] = _arc_eval(g, sweep, 0) - e
    # length: closed form for constant radius, Gauss-Legendre otherwise
    pitch = (a1 - a0) / sweep
    length = np.sqrt(r0**2 + pitch**2) * sweep
    spiral = np.flatnonzero(np.abs(r1 - r0) > 1e-12 * np.maximum(r0, 1.0))
    if spiral.size:  # Gauss-Legendre on sub-intervals of at most _QUAD_ANGLE, all spirals at once
        m = np.maximum(1, np.ceil(sweep[spiral] / _QUAD_ANGLE)).astype(np.int64)
        x, w = _GAUSS
        owner = np.repeat(spiral, m * x.size)
        sub = np.repeat(np.concatenate([np.arange(c) for c in m]), x.size)
        width = np.repeat(sweep[spiral] / m, m * x.size)
        node = np.tile(x, int(m.sum()))
        phi = width * (sub + 0.5 * (node + 1.0))
        gi = _take(g, owner)
        speed = np.linalg.norm(_arc_eval(gi, phi, 1), axis=1)
        length[spiral] = np.bincount(np.searchsorted(spiral, owner), weights=0.5 * width * np.tile(w, int(m.sum())) * speed,
                                     minlength=spiral.size)
    g["length"] = length
    return g


def _arc_eval(g: dict, phi: np.ndarray, order: int) -> np.ndarray:
    """``d^order P / d phi^order`` (3-D) at ``phi`` for arc rows ``g`` (one row per ``phi``)."""
    sweep = g["sweep"]
    dr, da = (g["r1"] - g["r0"]) / sweep, (g["a1"] - g["a0"]) / sweep
    r = g["r0"] + dr * phi
    cos, sin = np.cos(phi)[:, None], np.sin(phi)[:, None]
    e1, e2, n = g["e1"], g["e2"], g["n"]
    # d^k/dphi^k of (cos e1 + sin e2) = rotation by k * 90 deg
    rot = [(cos, sin), (-sin, cos), (-cos, -sin), (sin, -cos)]

    def ring(k):
        a, b = rot[k % 4]
        return a * e1 + b * e2

    if order == 0:
        return g["c"] + (g["a0"] + da * phi)[:, None] * n + r[:, None] * ring(0)
    # Leibniz on r(phi) * ring(phi): r is linear
    out = r[:, None] * ring(order) + order * dr[:, None] * ring(order - 1)
    if order == 1:
        out = out + da[:, None] * n
    return out
