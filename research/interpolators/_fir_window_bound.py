"""A lower bound on the cycle time of any fixed-delay FIR plan for blocks shorter than the window (B2).

Issue 13 / 19: on short-block paths (blocks shorter than ``F T_d``) the two-leg bound of
``_fir_bound`` (B1) is not stated, because one filter window holds several vertices. (B2) needs no
such condition.

Family bounded (as in B1; the plans of :func:`plan_fir` and :func:`optimize_fir`): the reference
``r(u)`` runs forward along the polyline at speed ``<= F`` (block pulses of feeds ``<= F``, eq 5,
with dwells ``g_k = T_d - T_k >= 0`` between them, eq 11), resting at the path's start for
``u <= 0`` and at its end after ``T_ref``; the output is ``q(t) = int h(s) r(t - s) ds`` with ``h``
the fixed kernel of the filter cascade (eq 2-4, support ``T_d``, mass 1); ``T = T_ref + T_d``.
Each vertex ``V_k`` must be passed within ``eps``: ``min_t |q(t) - V_k| <= eps`` (eq 13/14's
corner error, verified on the exact profile by ``plan_fir``).

Derivation. Let ``rho(u)`` be the reference's arc length minus ``V_k``'s (nondecreasing, slope
``<= F``) and cut the path into stretches ``[-R1_k, R2_k]`` around the vertices at the block
midpoints (the first / last stretch reaches the path's end). Let ``u_in = sup{u: rho <= -R1}``,
``u_out = inf{u: rho >= R2}``; the loss in the stretch is ``l_k = u_out - u_in - (R1 + R2) / F >= 0``
and the stretches' time intervals are disjoint, so ``T_ref >= sum L / F + sum_k l_k``. With
``u_in = 0`` (time shift), speed ``<= F`` and monotonicity give, for every such reference,

    rho(u) in [lo(u), hi(u)],  hi(u) = -R1 + F max(u, 0),
    lo(u) = -R1 + F u (u < 0);  max(-R1, R2 - F (u_out - u)) (0 <= u <= u_out);  R2 (u > u_out)

(``hi`` drops the exit bound ``R2 + F (u - u_out)``, which keeps the intervals nested: they grow
with ``l``). For any unit vector ``n``, ``n . (q(t) - V_k) = int h(s) phi_n(rho(t - s)) ds`` with
``phi_n(rho) = n . (P(s_k + rho) - V_k)`` (``P``: the path by arc length), and so

    |q(t) - V_k| >= max_n int h(s) w_n(t - s) ds,   w_n(u) = min { phi_n(rho) : rho in [lo(u), hi(u)] }   (B2)

(the max over ``n`` may depend on ``t``: for each ``t`` every ``n`` bounds ``|q(t) - V_k|``).
``m(l) = min_t max_n int h w_n`` is nonincreasing in ``l`` (the intervals are nested), so the
least loss with ``m(l) <= eps``, ``l*_k``, found by bisection, bounds ``l_k`` from below, and

    T >= sum L / F + T_d + sum_k max(l*_k, l*_k(reversed path))

(the reversed path is a plan of the same family with the same kernel, ``h`` being symmetric:
anchoring the nested intervals at the exit instead gives a second valid ``l*_k``).

Numerics, all on the safe side: ``w_n`` is bounded below per time cell of width ``ds`` (the
interval's lower end at the cell's start, upper end at its end; ``phi_n`` is linear between
vertices, so its minimum over an interval is exact from the ends and the vertices inside; beyond
``reach`` from ``V_k`` the minimum over the whole rest of the path stands in), the kernel's exact
mass per cell (the CDF of a sum of uniforms), and for ``t`` between grid points the smaller of two
neighbouring cells. Limits and the path tolerance between vertices are not used: the bound holds
for every limit set. Directions ``n``: :data:`N_DIRECTIONS` evenly spread unit vectors (2-D:
angles; 3-D: a Fibonacci sphere) and each vertex's bisector; more only tighten it (the bound is
valid for any set).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.signal import fftconvolve

from research.errors import ParameterError
from research.paths.polyline import Polyline

#: directions ``n`` of (B2) besides each vertex's bisector; swept on cam30 at bench_cam's setting
#: (2-D, every direction valid, more only tighten): 8 -> 1.7925 s, 24 -> 1.8087 s, 72 -> 1.8589 s,
#: 144 -> 1.8643 s (5, 9, 28, 57 s): 72 is within 0.3 % of 144 at half its cost
N_DIRECTIONS = 72
#: bisection steps on the loss (resolution ``T_d / 2^steps``)
_STEPS = 18


def kernel_cdf(x, delays) -> np.ndarray:
    """The filter kernel's distribution function at ``x`` [s] (the share of a unit step the cascade
    of unit-area boxes of widths ``delays`` [s] has passed): the CDF of a sum of uniforms,
    ``G(x) = sum_S (-1)^|S| (x - sum S)_+^n / (n! prod T)``, clipped to ``[0, 1]``."""
    T = np.asarray(delays, dtype=np.float64)
    n = T.size
    x = np.asarray(x, dtype=np.float64)
    cdf = np.zeros_like(x)
    for mask in range(1 << n):
        sub = [T[i] for i in range(n) if mask >> i & 1]
        cdf += (-1) ** len(sub) * np.maximum(x - sum(sub), 0.0) ** n
    return np.clip(cdf / (math.factorial(n) * np.prod(T)), 0.0, 1.0)


def kernel_cell_masses(delays, ds: float) -> np.ndarray:
    """Exact mass of the filter kernel (cascade of unit-area boxes of widths ``delays`` [s]) in
    each cell ``[m ds, (m + 1) ds]``: differences of :func:`kernel_cdf`."""
    T = np.asarray(delays, dtype=np.float64)
    cdf = kernel_cdf(np.arange(int(math.ceil(T.sum() / ds)) + 1) * ds, T)
    cdf[-1] = 1.0
    return np.diff(cdf)


def directions(dim: int, count: int = N_DIRECTIONS) -> np.ndarray:
    """``(count', dim)`` unit vectors spread over the circle / sphere (``dim`` = 1: +-1)."""
    if dim == 1:
        return np.array([[1.0], [-1.0]])
    if dim == 2:
        a = 2 * np.pi * np.arange(count) / count
        return np.column_stack([np.cos(a), np.sin(a)])
    i = np.arange(count) + 0.5
    z = 1 - 2 * i / count
    r = np.sqrt(1 - z * z)
    a = np.pi * (1 + 5 ** 0.5) * i
    return np.column_stack([r * np.cos(a), r * np.sin(a), z])


class _Vertex:
    """(B2) at one vertex of one orientation of the path: ``m(l)`` and the least loss ``l*``."""

    def __init__(self, path_pts, s_v, k: int, R1: float, R2: float, feed: float, H: np.ndarray, ds: float,
                 dirs: np.ndarray, reach: float):
        V = path_pts[k]
        rho_v = s_v - s_v[k]
        self.F, self.H, self.ds, self.R1, self.R2 = feed, H, ds, R1, R2
        self.lo_dom, self.hi_dom = rho_v[0], rho_v[-1]
        phi_v = (path_pts - V) @ dirs.T  # (M + 1, n_dir): phi_n at the vertices
        self.rho_v, self.phi_v = rho_v, phi_v
        self.D = reach
        near = np.abs(rho_v) < reach
        self.rho_near, self.phi_near = rho_v[near], phi_v[near]
        # min of phi_n beyond the reach on either side (vertices and the cut points)
        cut_lo, cut_hi = self._phi(np.array([max(-reach, self.lo_dom)])), self._phi(np.array([min(reach, self.hi_dom)]))
        self.far_lo = np.min(np.vstack([phi_v[rho_v <= -reach], cut_lo]), axis=0)
        self.far_hi = np.min(np.vstack([phi_v[rho_v >= reach], cut_hi]), axis=0)

    def _phi(self, rho: np.ndarray) -> np.ndarray:
        """``phi_n(rho)`` ``(len(rho), n_dir)`` (linear between vertices)."""
        rho = np.clip(rho, self.lo_dom, self.hi_dom)
        i = np.clip(np.searchsorted(self.rho_v, rho, side="right") - 1, 0, self.rho_v.size - 2)
        seg = self.rho_v[i + 1] - self.rho_v[i]
        f = ((rho - self.rho_v[i]) / seg)[:, None]
        return self.phi_v[i] + f * (self.phi_v[i + 1] - self.phi_v[i])

    def _range_min(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Lower bound ``(len(a), n_dir)`` of ``min phi_n`` over ``[a_i, b_i]`` (exact inside the reach)."""
        a = np.clip(a, self.lo_dom, self.hi_dom)
        b = np.clip(b, self.lo_dom, self.hi_dom)
        ac, bc = np.maximum(a, -self.D), np.minimum(b, self.D)
        out = np.minimum(self._phi(ac), self._phi(bc))
        inside = (self.rho_near[None, :] > ac[:, None]) & (self.rho_near[None, :] < bc[:, None])
        vals = np.where(inside[:, :, None], self.phi_near[None, :, :], np.inf)
        out = np.minimum(out, vals.min(axis=1))
        out = np.where((a < -self.D)[:, None], np.minimum(out, self.far_lo[None, :]), out)
        return np.where((b > self.D)[:, None], np.minimum(out, self.far_hi[None, :]), out)

    def m(self, loss: float) -> float:
        """``m(l)`` of (B2), bounded below [mm]."""
        F, ds, R1, R2 = self.F, self.ds, self.R1, self.R2
        u_out = (R1 + R2) / F + loss
        u0 = -(self.D - R1) / F - 2 * ds  # lo(u) saturated (at -reach) before u0, hi(u) = -R1
        u1 = max(u_out, (self.D + R1) / F) + 2 * ds  # both saturated after u1
        edges = u0 + np.arange(int(math.ceil((u1 - u0) / ds)) + 2) * ds
        ua, ub = edges[:-1], edges[1:]
        lo = np.where(ua < 0, -R1 + F * ua, np.where(ua <= u_out, np.maximum(-R1, R2 - F * (u_out - ua)), R2))
        hi = -R1 + F * np.maximum(ub, 0.0)
        w = self._range_min(lo, hi)  # (cells, n_dir)
        w = np.minimum(w[:-1], w[1:])  # t between grid points: two neighbouring cells
        pad = self.H.size + 1
        w = np.vstack([np.repeat(w[:1], pad, axis=0), w, np.repeat(w[-1:], pad, axis=0)])
        S = fftconvolve(w, self.H[:, None], mode="valid", axes=0)
        # FFT rounding (relative ~1e-13 of the largest |w|) taken off on the safe side
        S -= 1e-11 * max(1.0, float(np.max(np.abs(w))))
        return float(np.min(np.max(S, axis=1)))

    def least_loss(self, eps: float, Td: float) -> float:
        """Largest ``l`` found with ``m(l) > eps`` (so every plan loses more than it here), 0 if
        ``m(0) <= eps``."""
        if self.m(0.0) <= eps:
            return 0.0
        lo, hi = 0.0, Td + 4 * self.ds
        if self.m(hi) > eps:
            return hi
        for _ in range(_STEPS):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if self.m(mid) > eps else (lo, mid)
        return lo


def _losses(points: np.ndarray, feed: float, delays, eps: float, ds: float, n_dir: int) -> np.ndarray:
    """``l*_k`` of every inner vertex of ``points`` in this orientation [s]."""
    seg = np.diff(points, axis=0)
    L = np.linalg.norm(seg, axis=1)
    s_v = np.concatenate([[0.0], np.cumsum(L)])
    M = L.size
    Td = float(np.sum(delays))
    H = kernel_cell_masses(delays, ds)
    base = directions(points.shape[1], n_dir)
    out = np.zeros(M - 1)
    for k in range(1, M):
        R1 = L[k - 1] if k == 1 else 0.5 * L[k - 1]
        R2 = L[k] if k == M - 1 else 0.5 * L[k]
        u1, u2 = seg[k - 1] / L[k - 1], seg[k] / L[k]
        bis = u2 - u1
        dirs = base if np.linalg.norm(bis) < 1e-12 else np.vstack([base, bis / np.linalg.norm(bis)])
        reach = max(R1, R2) + feed * Td
        out[k - 1] = _Vertex(points, s_v, k, R1, R2, feed, H, ds, dirs, reach).least_loss(eps, Td)
    return out


def window_lower_bound(path: Polyline, feed: float, delays, tolerance: float, *, ds: float | None = None,
                       n_directions: int = N_DIRECTIONS) -> tuple[float, np.ndarray]:
    """Lower bound (B2) [s] on the cycle time of any fixed-delay FIR plan along ``path``.

    Args:
        path: G01 path [mm].
        feed: commanded feed ``F`` [mm/s] (every block's feed ``<= F``).
        delays: FIR delays [s] (1 to 3 filters).
        tolerance: cornering tolerance ``eps`` [mm], > 0.
        ds: time cell [s] of the quadrature (default ``T_d / 2000``, but at most ``eps / (4 F)``
            so that the cell's arc ``F ds`` stays small against ``eps``); any value gives a valid
            bound, smaller ones a tighter one.
        n_directions: directions ``n`` besides the bisectors.

    Returns:
        ``(bound, losses)``: ``sum L / F + T_d + sum_k l_k`` [s] and the per-corner losses ``l_k`` [s]
        (the larger of the two orientations).

    Raises:
        ParameterError: non-positive feed, tolerance or delays.
    """
    d = np.asarray(delays, dtype=np.float64).reshape(-1)
    if d.size < 1 or d.size > 3 or not np.all(np.isfinite(d) & (d > 0)):
        raise ParameterError(f"delays must be 1 to 3 finite values > 0 s, got {d.tolist()}")
    if not (np.isfinite(feed) and feed > 0):
        raise ParameterError(f"feed F must be finite and > 0 mm/s, got {feed!r}")
    if not (np.isfinite(tolerance) and tolerance > 0):
        raise ParameterError(f"tolerance eps must be finite and > 0 mm, got {tolerance!r}")
    Td = float(d.sum())
    if ds is None:
        ds = min(Td / 2000, tolerance / (4 * feed))
    pts = np.asarray(path.points, dtype=np.float64)
    base = float(np.sum(path.lengths) / feed + Td)
    if path.n_segments < 2:
        return base, np.zeros(0)
    fwd = _losses(pts, feed, d, tolerance, ds, n_directions)
    rev = _losses(pts[::-1], feed, d, tolerance, ds, n_directions)[::-1]
    losses = np.maximum(fwd, rev)
    return base + float(losses.sum()), losses
