"""Per-axis velocity, acceleration and jerk of FIR-overlap cornering: feed caps and exact peaks.

Beyond Sencer 2015: plain overlap superposes the slow-down of one block and the speed-up of the
next, so an axis whose velocity reverses sees up to twice its nominal acceleration and jerk. Two
facts make a limit-holding variant possible:

* A block on its own (exact stop, ``T_k = 0``) is a filtered pulse of length ``T_v``: per axis its
  peaks are ``F |u_i|`` (velocity), ``F |u_i| / T_1`` (acceleration) and ``F |u_i| / (T_1 T_2)``
  (jerk) with ``T_1 >= T_2`` the two longest delays (Sencer 2015 §2.1; further filters only
  smooth) -- but twice that jerk when ``T_v < T_1 + T_2``, because the first filter's acceleration
  steps at ``T_1`` and ``T_v`` then fall in one window of the second filter. Capping each block's
  feed accordingly makes every block safe alone.
* With overlap, the profile is still piecewise polynomial, so the peaks near each corner are found
  exactly (at break points, and where the next derivative vanishes) and the overlap of a corner
  that breaks a limit is shrunk; at ``T_k = 0`` the corner is two safe blocks, so the loop ends.
"""

from __future__ import annotations

import numpy as np

from research.errors import ParameterError
from research.limits import AxisLimits


def feed_caps(lengths: np.ndarray, directions: np.ndarray, delays: np.ndarray, limits: AxisLimits) -> np.ndarray:
    """Largest feed [mm/s] per block for which the block alone keeps every axis limit.

    Args:
        lengths: ``(M,)`` block lengths [mm]; directions: ``(M, d)`` unit vectors.
        delays: FIR delays [s]; limits: per-axis limits.
    """
    d = np.sort(np.asarray(delays, dtype=np.float64))[::-1]
    if d.size < 2 and np.any(np.isfinite(limits.jerk)):
        raise ParameterError("a jerk limit needs at least two FIR filters: one filter gives unbounded jerk")
    if d.size > 3:
        raise ParameterError("limit-holding FIR cornering supports up to three filters (exact peaks)")
    u = np.abs(np.asarray(directions, dtype=np.float64))
    with np.errstate(divide="ignore", invalid="ignore"):
        va = np.min(np.where(u > 0, np.minimum(limits.velocity, limits.acceleration * d[0])[None, :] / u, np.inf), axis=1)
        if d.size < 2:
            return va
        long_block = np.min(np.where(u > 0, limits.jerk[None, :] * d[0] * d[1] / u, np.inf), axis=1)
        # a block shorter than T1 + T2 in time doubles its jerk; F <= L / (T1 + T2) keeps it long
        short_block = np.maximum(0.5 * long_block, np.minimum(long_block, np.asarray(lengths) / (d[0] + d[1])))
        jerk_cap = np.where(np.asarray(lengths) / long_block >= d[0] + d[1], long_block, short_block)
    return np.minimum(va, jerk_cap)


def arc_limit_caps(radii: np.ndarray, delays: np.ndarray, limits: AxisLimits) -> np.ndarray:
    """Largest feed [mm/s] per arc block (``inf`` radius: no cap) for which the arc alone keeps
    every axis limit, bounding each derivative by its steady part plus its transient part:
    ``F <= v``, ``F / T_1 + F^2 / R <= a``, ``F / (T_1 T_2) + F^2 / (R T_2) + F^3 / R^2 <= j``
    (the start and stop pulse edges of a line, plus the centripetal acceleration ``F^2 / R`` and
    its rotation ``F^3 / R^2`` switched on through the shortest filter). Conservative: the
    smallest limit over the axes is used, since an arc's tangent sweeps its plane."""
    d = np.sort(np.asarray(delays, dtype=np.float64))[::-1]
    r = np.asarray(radii, dtype=np.float64)
    v, a, j = float(np.min(limits.velocity)), float(np.min(limits.acceleration)), float(np.min(limits.jerk))
    T1, T2 = d[0], (d[1] if d.size > 1 else d[0])

    def excess(F):
        acc = F / T1 + F**2 / r - a
        jerk = F / (T1 * T2) + F**2 / (r * T2) + F**3 / r**2 - j if np.isfinite(j) else -np.ones_like(F)
        return np.maximum(acc, jerk)

    lo, hi = np.zeros_like(r), np.full(r.shape, v)
    ok = excess(hi) <= 0
    lo = np.where(ok, hi, lo)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        good = excess(mid) <= 0
        lo, hi = np.where(ok | ~good, lo, mid), np.where(ok | good, hi, mid)
    return np.where(np.isfinite(r), lo, np.inf)


#: pieces shorter than this [s] are ignored by :func:`corner_peak_ratios`: two breaks that coincide up
#: to rounding leave a piece of ~1e-16 s carrying both neighbours' jerk, which no motion realizes
DEGENERATE_PIECE = 1e-12


def corner_peak_ratios(position, lo: np.ndarray, hi: np.ndarray, limits: AxisLimits) -> np.ndarray:
    """Largest ``peak / limit`` over axes and over velocity, acceleration, jerk, in each window
    ``[lo_c, hi_c]`` [s]; exact (roots of the next derivative) for pieces of any degree.

    ``position``: a :class:`PiecewisePolynomial` or its NumPy evaluator. Pieces shorter than
    :data:`DEGENERATE_PIECE` are skipped (their continuous derivatives are the neighbours' end values)."""
    breaks = np.asarray(position.breaks)
    coeffs = np.asarray(position.coeffs)  # (K, d + 1, A) ascending local
    K, degree = coeffs.shape[0], coeffs.shape[1] - 1
    # derivative coefficients of orders 1..4 at every piece
    derivs = [coeffs]
    for _ in range(4):
        c = derivs[-1]
        derivs.append(c[:, 1:, :] * np.arange(1, c.shape[1])[None, :, None] if c.shape[1] > 1 else np.zeros_like(c))
    h = np.diff(breaks)
    limit = np.stack([limits.velocity, limits.acceleration, limits.jerk])  # (3, A)
    # candidate local times per piece: both ends, and where the next derivative vanishes
    ratio = np.zeros((K, 3, coeffs.shape[2]))
    for order in (1, 2, 3):
        c = derivs[order]
        values = [_horner(c, np.zeros(K)), _horner(c, h)]
        if order < degree:
            for tau in _real_roots(derivs[order + 1], h):
                values.append(_horner(c, tau))
        peak = np.max(np.abs(np.stack(values)), axis=0)  # (K, A)
        ratio[:, order - 1, :] = peak / limit[order - 1][None, :]
    per_piece = np.where(h > DEGENERATE_PIECE, ratio.reshape(K, -1).max(axis=1), 0.0)
    first = np.clip(np.searchsorted(breaks, lo, side="right") - 1, 0, K - 1)
    last = np.clip(np.searchsorted(breaks, hi, side="left"), first + 1, K)
    return _range_max(per_piece, first, last)


def _range_max(values: np.ndarray, first: np.ndarray, last: np.ndarray) -> np.ndarray:
    """``max(values[a:b])`` for every pair, by a sparse table (O((K + C) log K), no Python loop)."""
    table = [values]
    while (1 << len(table)) <= values.size:
        prev, half = table[-1], 1 << (len(table) - 1)
        table.append(np.maximum(prev[:-half], prev[half:]))
    length = np.maximum(last - first, 1)
    level = np.floor(np.log2(length)).astype(np.int64)
    out = np.empty(first.size)
    for lv in np.unique(level):
        sel = level == lv
        row = table[lv]
        out[sel] = np.maximum(row[first[sel]], row[last[sel] - (1 << lv)])
    return out


def _horner(c: np.ndarray, tau: np.ndarray) -> np.ndarray:
    out = c[:, -1, :]
    for m in range(c.shape[1] - 2, -1, -1):
        out = out * tau[:, None] + c[:, m, :]
    return out


def _real_roots(c: np.ndarray, h: np.ndarray) -> list[np.ndarray]:
    """Real roots in ``[0, h]`` of the per-piece, per-axis polynomials ``c`` (ascending, ``(K, m+1, A)``),
    as local times ``(K,)`` per candidate (out-of-range or complex candidates are replaced by 0).
    Degree <= 2 in closed form, higher degrees by the eigenvalues of the companion matrices."""
    deg = c.shape[1] - 1
    out = []
    if deg == 1:
        a1, a0 = c[:, 1, :], c[:, 0, :]
        with np.errstate(divide="ignore", invalid="ignore"):
            r = np.where(a1 != 0, -a0 / np.where(a1 != 0, a1, 1.0), 0.0)
        out += [r[:, k] for k in range(c.shape[2])]
    elif deg == 2:
        a2, a1, a0 = c[:, 2, :], c[:, 1, :], c[:, 0, :]
        disc = a1**2 - 4 * a2 * a0
        sq = np.sqrt(np.maximum(disc, 0.0))
        with np.errstate(divide="ignore", invalid="ignore"):
            safe = np.where(a2 != 0, a2, 1.0)
            roots = [np.where((a2 != 0) & (disc >= 0), (-a1 + s * sq) / (2 * safe), 0.0) for s in (1.0, -1.0)]
            roots.append(np.where((a2 == 0) & (a1 != 0), -a0 / np.where(a1 != 0, a1, 1.0), 0.0))
        out += [r[:, k] for r in roots for k in range(c.shape[2])]
    elif deg > 2:
        # scale time to the piece length so the companion matrix is well conditioned
        K, A = c.shape[0], c.shape[2]
        hs = np.where(h > 0, h, 1.0)
        cs = c * hs[:, None, None] ** np.arange(deg + 1)[None, :, None]
        lead = cs[:, -1, :]
        ok = np.abs(lead) > 1e-14 * np.max(np.abs(cs), axis=1)
        comp = np.zeros((K, A, deg, deg))
        comp[:, :, 1:, :-1] = np.eye(deg - 1)
        with np.errstate(divide="ignore", invalid="ignore"):
            comp[:, :, :, -1] = -np.where(ok[:, None, :], cs[:, :-1, :] / np.where(ok, lead, 1.0)[:, None, :], 0.0).transpose(0, 2, 1)
        eig = np.linalg.eigvals(comp)  # (K, A, deg)
        real = np.abs(eig.imag) <= 1e-9 * np.maximum(1.0, np.abs(eig.real))
        x = np.where(real & ok[:, :, None] & (eig.real >= 0) & (eig.real <= 1), eig.real, 0.0) * hs[:, None, None]
        out += [x[:, k, m] for k in range(A) for m in range(deg)]
    return [np.clip(np.nan_to_num(r), 0.0, h) for r in out]
