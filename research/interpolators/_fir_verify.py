"""Exact checks of an FIR plan against its tool path: vertex errors and path deviation.

Two measures of the distance between trajectory and programmed path, both on the exact profile:

* the **corner error** of Sencer 2015 (eq 13/14): distance from each vertex to the trajectory,
  searched around the instant the averaging window is centred on the corner's gap;
* the **path deviation**: distance from the trajectory to the path (lines and arcs), on samples
  every ``check_period`` plus the corner instants. Between vertices of short blocks and along
  arcs the trajectory can leave the path where no vertex sees it.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from research.paths.toolpath import ToolPath
from research.interpolators._fir_kernels import corner_distances as _corner_kernel
from research.interpolators._fir_kernels import sampled_line_distances
from research.piecewise import NumpyPiecewise, PiecewisePolynomial, bucket_size

_GRID = 9  # grid points per corner window for the corner-error search
_NEWTON_STEPS = 4


def corner_distances(position: PiecewisePolynomial, vertices: Array, centre: Array, half_window: Array) -> Array:
    """Distance [mm] from each vertex ``(C, d)`` to the profile, searched in ``centre +- half_window`` [s].

    A grid of 9 points finds the basin; safeguarded Newton steps on ``|p(t) - V|^2`` (exact
    derivatives of the profile) refine it. Any point of the trajectory gives an upper bound on the
    true distance, so the result is never optimistic. Shapes are padded to bucketed sizes so paths
    of similar size share one compiled function.
    """
    C = vertices.shape[0]
    if C == 0:
        return jnp.zeros(0)
    pad = bucket_size(C, 16) - C
    centre_p = jnp.concatenate([jnp.asarray(centre), jnp.zeros(pad)])
    vert_p = jnp.concatenate([jnp.asarray(vertices), jnp.zeros((pad, vertices.shape[1]))])
    return _corner_distances(position, vert_p, centre_p, jnp.asarray(half_window), jnp.arange(C + pad) < C)[:C]


@jax.jit
def _corner_distances(position, vertices, centre, half_window, real):
    offsets = jnp.linspace(-1.0, 1.0, _GRID)
    grid = centre[:, None] + half_window * offsets[None, :]  # (C, G)
    p = position(grid)
    d2 = jnp.sum((p - vertices[:, None, :]) ** 2, axis=-1)
    best = jnp.argmin(d2, axis=1)
    t = jnp.take_along_axis(grid, best[:, None], axis=1)[:, 0]
    step = half_window * (offsets[1] - offsets[0])
    lo, hi = t - step, t + step

    def newton(_, t):
        p, v, a = position.derivatives(t, 3)
        e = p - vertices
        slope = jnp.sum(e * v, axis=1)
        curvature = jnp.sum(v * v, axis=1) + jnp.sum(e * a, axis=1)
        t_new = jnp.where(curvature > 0, t - slope / jnp.where(curvature > 0, curvature, 1.0), t)
        return jnp.clip(t_new, lo, hi)

    t = jax.lax.fori_loop(0, _NEWTON_STEPS, newton, t)
    squared = jnp.minimum(jnp.sum((position(t) - vertices) ** 2, axis=1), jnp.min(d2, axis=1))
    positive = squared > 0
    return jnp.where(real & positive, jnp.sqrt(jnp.where(positive, squared, 1.0)), 0.0)


def vertex_distances(position: NumpyPiecewise, vertices: np.ndarray, centre: np.ndarray, half_window: float) -> np.ndarray:
    """:func:`corner_distances` on concrete arrays, compiled (``_fir_kernels.corner_distances``): the
    same grid and Newton steps without JAX dispatch, for the planner's checks (the JAX form stays
    the differentiable one). Agrees with it to rounding."""
    if vertices.shape[0] == 0:
        return np.zeros(0)
    return _corner_kernel(np.ascontiguousarray(position.breaks), np.ascontiguousarray(position.coeffs),
                          np.ascontiguousarray(vertices, dtype=np.float64), np.ascontiguousarray(centre, dtype=np.float64),
                          float(half_window), _GRID, _NEWTON_STEPS)


def path_deviations(position: NumpyPiecewise, path: ToolPath, starts: np.ndarray, centre: np.ndarray, Td: float,
                    tol_block: np.ndarray, check_period: float):
    """Largest sampled distance from the trajectory to ``path`` and where it breaks the tolerance.

    Args:
        position: the exact profile (NumPy evaluator); path: the programmed path.
        starts: ``(M,)`` pulse start of each block [s]; centre: ``(M - 1,)`` corner instants [s].
        Td: total filter delay [s]; tol_block: ``(M,)`` tolerance per block [mm].
        check_period: sample spacing [s].

    Returns:
        ``(max_deviation [mm], {vertex: deviation}, {block: deviation})``; distances are upper
        bounds (:meth:`ToolPath.distance_bound`), equal to the distance on all but crowded paths.
        Violations within
        ``T_d / 2`` of a corner instant are charged to that corner, others to the block whose input
        the window is centred on (the inside of an arc).
    """
    t0, t1 = float(position.breaks[0]), float(position.breaks[-1])
    n = int(np.ceil((t1 - t0) / check_period)) + 1
    t = np.concatenate([t0 + np.arange(n) * check_period, centre, [t1]])
    t = np.clip(t, t0, t1)
    M = path.n_blocks
    # first the blocks the window is centred on (almost every sample is within tolerance of them),
    # then, for the rest, the k nearest path samples as well
    q, block, dist = _three_block_distance(path, position, t, starts, Td)
    limit = tol_block[block]
    near = np.full(t.size, -1)
    if M > 1:
        k = np.clip(np.searchsorted(centre, t), 1, M - 1)
        j = np.where(np.abs(centre[k - 1] - t) <= np.abs(centre[np.minimum(k, M - 2)] - t), k - 1, np.minimum(k, M - 2))
        close = np.abs(centre[j] - t) <= 0.5 * Td
        near = np.where(close, j, -1)
        tol_v = np.minimum(tol_block[:-1], tol_block[1:])
        limit = np.where(close, np.minimum(limit, tol_v[np.maximum(j, 0)]), limit)
    bad = dist > limit * (1.0 + 1e-9) + 1e-9
    if bad.any():
        dist[bad] = np.minimum(dist[bad], path.distance_bound(q[bad], near=block[bad]))
        bad = dist > limit * (1.0 + 1e-9) + 1e-9
    i = np.flatnonzero(bad)
    # a violation near a corner instant, or on a line, is charged to a vertex; inside an arc to the arc
    to_vertex = (near[i] >= 0) | ~path.is_arc[block[i]]
    iv, ib = i[to_vertex], i[~to_vertex]
    at_vertex: dict[int, float] = {}
    if M > 1 and iv.size:
        jj = np.where(near[iv] >= 0, near[iv], np.clip(block[iv], 0, M - 2))
        worst = np.full(M - 1, -np.inf)
        np.maximum.at(worst, jj, dist[iv])
        at_vertex = {int(v): float(worst[v]) for v in np.flatnonzero(worst > -np.inf)}
    at_block: dict[int, float] = {}
    if ib.size:
        worst = np.full(M, -np.inf)
        np.maximum.at(worst, block[ib], dist[ib])
        at_block = {int(b): float(worst[b]) for b in np.flatnonzero(worst > -np.inf)}
    return float(dist.max()), at_vertex, at_block


def _three_block_distance(path: ToolPath, position: NumpyPiecewise, t: np.ndarray, starts: np.ndarray, Td: float):
    """Trajectory samples at ``t``, the block each one's window is centred on, and the distance [mm]
    from each sample to the nearest of blocks ``block - 1 .. block + 1``.

    Lines by one compiled pass (``_fir_kernels.sampled_line_distances``); arc candidates through
    ``ToolPath._block_distance`` (exact for planar arcs). Returns ``(q (N, d), block (N,), dist (N,))``."""
    M = path.n_blocks
    if "line_segments" not in path._cache:
        ab = np.ascontiguousarray(path.ends - path.starts)
        ab2 = np.einsum("kd,kd->k", ab, ab)
        inv = np.where(ab2 > 0, 1.0 / np.where(ab2 > 0, ab2, 1.0), 0.0)
        path._cache["line_segments"] = (np.ascontiguousarray(path.starts, dtype=np.float64), ab, inv)
    a, ab, inv = path._cache["line_segments"]
    q, block, d2 = sampled_line_distances(np.ascontiguousarray(position.breaks), np.ascontiguousarray(position.coeffs),
                                          np.ascontiguousarray(t, dtype=np.float64), np.ascontiguousarray(starts), 0.5 * Td,
                                          a, ab, inv)
    if path.is_arc.any():
        nb = np.clip(block[:, None] + np.arange(-1, 2)[None, :], 0, M - 1)
        arc = path.is_arc[nb]
        if arc.any():
            rows = np.nonzero(arc)
            d2[rows] = path._block_distance(q[rows[0]], nb[rows]) ** 2
    return q, block, np.sqrt(d2.min(axis=1))
