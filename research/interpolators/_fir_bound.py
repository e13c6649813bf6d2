"""A lower bound on the cycle time of any fixed-delay FIR plan (issue 19: why a target is missed).

The family bounded is the one :func:`plan_fir` and :func:`optimize_fir` search: the reference
``r(u)`` runs along the polyline at speed ``<= F`` (block pulses of feed ``<= F``, eq 5), dwelling
``g_k = T_d - T_k >= 0`` at the vertices (eq 11), and the output is ``q(t) = int h(s) r(t - s) ds``
with ``h`` the fixed FIR kernel (the cascade of the ``n`` boxes, support ``T_d``, eq 2-4). The
cycle time is ``T = T_ref + T_d`` with ``T_ref = sum L / F + sum_k l_k``, ``l_k`` the time lost
(to slower feeds and dwells) around corner ``k``.

Bound at one corner (turning angle ``theta``, vertex ``V``). Let the window of ``q(t)`` hold
reference points on the two legs only, at distances ``a`` (before ``V``) and ``b`` (after); then
``q(t) - V = -A u_1 + B u_2`` with ``A = int h a``, ``B = int h b``, and
``|q - V|^2 = (A + B)^2 - 2 A B (1 + cos theta) >= (A + B)^2 sin^2(theta / 2)``, so a corner error
``<= eps`` needs ``int h(s) |rho(t - s)| ds <= eps / sin(theta / 2)`` (``rho``: arc length from
``V``). With a loss ``l`` spent within ``R`` of ``V``, speed ``<= F`` puts the reference at
``|rho(u)| >= min(F dist(u, I), R)`` for an interval ``I`` of length ``l`` (the reference is
*farther* from ``V`` the less time it loses), hence

    F m_R(l) <= eps / sin(theta / 2),   m_R(l) = min_c int h(s) min(dist(s, [c, c + l]), R / F) ds   (B1)

and the least ``l`` meeting (B1), ``l*_k``, bounds corner ``k``'s loss. ``R_k`` is half the
shorter leg (so the losses of neighbouring corners lie on disjoint stretches and add), or the
whole leg where it ends the path (the reference rests there). The window must hold only points of
the two legs: the bound is stated only where ``F T_d <= L`` for every leg that does not end the path (a window
holds the passage of ``V`` and spans ``T_d``; long-block paths: corner90, the diamond);
elsewhere only the trivial ``sum L / F + T_d`` is returned (``_fir_window_bound`` (B2) bounds
those paths). Limits are not used: the bound holds for every limit set, and a plan that meets it
is optimal within the family.
"""

from __future__ import annotations

import numpy as np

from research.paths.polyline import Polyline

#: time step [s] of the kernel quadrature in (B1)
_DS = 2e-5


def fir_kernel(delays, ds: float = _DS) -> tuple[np.ndarray, np.ndarray]:
    """``(s, h)``: the FIR kernel (cascade of unit-area boxes of widths ``delays`` [s]) on a grid of ``ds``."""
    h = np.ones(1)
    for T in delays:
        n = max(int(round(T / ds)), 1)
        h = np.convolve(h, np.full(n, 1.0 / n))
    s = (np.arange(h.size) + 0.5) * ds
    return s, h / h.sum()


def mean_distance(loss: float, cap: float, s: np.ndarray, h: np.ndarray) -> float:
    """``m_R(l)`` of (B1) [s]: the kernel-weighted mean time distance to the best-placed interval
    of length ``loss``, each distance capped at ``cap`` [s] (the kernel is symmetric, so the
    centred interval is searched with a few offsets around it)."""
    mid = 0.5 * (s[0] + s[-1])
    best = np.inf
    for off in np.linspace(-0.5, 0.5, 41) * (s[-1] - s[0]):
        c0 = mid + off - 0.5 * loss
        d = np.maximum(np.maximum(c0 - s, s - (c0 + loss)), 0.0)
        best = min(best, float(np.sum(h * np.minimum(d, cap))))
    return best


def corner_loss(theta: float, feed: float, delays, tolerance: float, reach: float) -> float:
    """Least loss ``l*`` [s] around one corner that meets (B1) (bisection)."""
    s, h = fir_kernel(delays)
    target = tolerance / max(np.sin(0.5 * theta), 1e-12) / feed
    cap = reach / feed
    if mean_distance(0.0, cap, s, h) <= target:
        return 0.0
    lo, hi = 0.0, float(s[-1] - s[0])
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if mean_distance(mid, cap, s, h) <= target else (mid, hi)
    return lo


def fir_cycle_lower_bound(path: Polyline, feed: float, delays, tolerance: float) -> tuple[float, bool]:
    """Lower bound [s] on the cycle time of any fixed-delay FIR plan along ``path``.

    Returns:
        ``(bound, with_corners)``: ``sum L / F + T_d + sum_k l*_k`` and True where every corner
        satisfies the window condition of the module docstring; else ``(sum L / F + T_d, False)``.
    """
    L = path.lengths
    Td = float(np.sum(delays))
    base = float(np.sum(L) / feed + Td)
    M = L.size
    if M < 2:
        return base, True
    u = np.diff(path.points, axis=0) / L[:, None]
    total = 0.0
    for k in range(M - 1):
        reach = []
        for leg in (k, k + 1):
            end = leg == 0 or leg == M - 1  # the reference rests at the path's end: never leaves the leg
            if not end and feed * Td > L[leg]:
                return base, False  # one window may reach past the leg's far vertex
            reach.append(L[leg] if end else 0.5 * L[leg])
        R = min(reach)
        theta = float(np.arccos(np.clip(u[k] @ u[k + 1], -1.0, 1.0)))
        total += corner_loss(theta, feed, delays, tolerance, R)
    return base + total, True
