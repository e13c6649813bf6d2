"""A lower bound on the cycle time of any fixed-delay FIR plan of one corner under per-axis jerk
limits (B3; issue 19: "optimized FIR <= 1.05x", where the tolerance alone does not decide).

B1 and B2 (``_fir_bound``, ``_fir_window_bound``) bound a fixed-delay FIR plan from the tolerance
alone. Under the FIR's own envelope (``j = F / (T1 T2)`` per axis) a plan must also keep each
axis's jerk: a pulse of feed ``F`` and length in ``(T1 - T2, T1 + T2)`` doubles it (its start's
and its end's jerk phases add), so the fixed delays cost more than B2 sees.

Family bounded (the plans of ``plan_fir(..., limits=...)`` and ``optimize_fir`` on a path of two
lines): block ``b``'s reference velocity is ``v_b(t) u_b``, ``0 <= v_b <= F_b`` (any shape: feeds,
head and tail shares, overlaps of any sign), ``int v_b = L_b``, from ``t = 0`` to ``T_ref``; the
output is the reference filtered by two moving averages of ``T1, T2`` (eq 2-4), ``T = T_ref +
T1 + T2``; it keeps the tolerance at the corner and the jerk limits ``J_a`` of every axis.

Relaxation (each constraint below is implied by the family's, so the least ``T`` it allows is a
lower bound). Time is cut into cells of ``dt`` dividing ``T1`` and ``T2``; the unknowns are the
masses ``m_b,k = int_cell v_b`` in ``[0, F_b dt]``.

- Jerk: axis ``a``'s jerk is ``sum_b u_b,a (v_b(t) - v_b(t - T1) - v_b(t - T2) + v_b(t - T1 -
  T2)) / (T1 T2)``, so its mean over a cell is that sum of the masses of four cells over ``T1 T2
  dt``, exactly; it lies within ``+-J_a``.
- Tolerance: with ``s_b(t) = int K(t - tau) v_b(tau) dtau`` (``K`` the kernel's step response,
  ``_fir_window_bound.kernel_cdf``, nondecreasing) the output is ``P0 + s_1 u_1 + s_2 u_2``; its
  distance to line 2 is ``(L_1 - s_1) sin(beta)`` and to line 1 ``s_2 sin(beta)`` (``beta`` the
  turn), each at most its distance to that block, so a point within ``eps`` of the path has ``s_2
  sin(beta) <= eps`` or ``(L_1 - s_1) sin(beta) <= eps``. Both ``s_b`` are nondecreasing, so the
  first holds up to some instant and the second from then on (a binary per output sample,
  nonincreasing: a MILP). In the constraints ``s_2 >= sum_k m_2,k K(t - b_k)`` and ``s_1 <= sum_k
  m_1,k K(t - a_k)`` (``[a_k, b_k]`` the cell), at the samples ``t = g dt``.
- Velocity and acceleration limits are left out (the bound holds without them).

A plan whose reference ends at ``T_ref`` fills ``ceil(T_ref / dt)`` cells; the least cell count
``N*`` the MILP finds feasible (by bisection; a solve that ends undecided counts as feasible) gives
``T >= (N* - 1) dt + T1 + T2``.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import Bounds, LinearConstraint, milp
from scipy.sparse import coo_matrix

from research.errors import ParameterError
from research.interpolators._fir_window_bound import kernel_cdf
from research.limits import AxisLimits
from research.paths import Polyline

#: seconds one MILP may take before it counts as feasible (the bound then stays valid, only weaker)
SOLVE_LIMIT = 120.0


def corner_limit_bound(path: Polyline, feed, delays, tolerance: float, limits: AxisLimits,
                       step: float = 1e-3) -> float:
    """Lower bound [s] on the cycle time of any fixed-delay FIR plan of a two-block ``path`` that
    keeps ``tolerance`` [mm] at its corner and the jerk limits of ``limits`` (module docstring, B3).

    Args:
        path: a polyline of two segments [mm]; feed: the blocks' feed caps [mm/s] (scalar or
            ``(2,)``); delays: the two filter delays [s]; tolerance: the corner's [mm];
            limits: per-axis limits (the jerk is read); step: the largest cell [s] (the cell is
            the largest ``T1 / n`` at most ``step`` that divides ``T2`` as well).

    Returns:
        The bound [s].

    Raises:
        ParameterError: not two segments, not two positive delays, delays with no common cell of
            at least ``step / 100``, a feed or tolerance not positive, limits for another axis count.

    Example (a bound lies below every plan of its family)::

        >>> from research.interpolators import plan_fir
        >>> corner = Polyline([[-2.0, 0.0], [0.0, 0.0], [0.0, 2.0]])
        >>> envelope = AxisLimits.fir_envelope(2, 100.0, (0.02, 0.01))
        >>> bound = corner_limit_bound(corner, 100.0, (0.02, 0.01), 0.01, envelope)
        >>> bound <= float(plan_fir(corner, 100.0, (0.02, 0.01), 0.01, limits=envelope).cycle_time)
        True
    """
    if path.n_segments != 2:
        raise ParameterError(f"corner_limit_bound: path must have two segments, got {path.n_segments}")
    d = np.asarray(delays, dtype=np.float64).reshape(-1)
    if d.size != 2 or np.any(d <= 0):
        raise ParameterError(f"corner_limit_bound: delays must be two positive delays [s], got {d.tolist()}")
    F = np.broadcast_to(np.asarray(feed, dtype=np.float64), (2,))
    if np.any(~(F > 0)) or not tolerance > 0:
        raise ParameterError(f"corner_limit_bound: feed and tolerance must be positive, got {F.tolist()}, {tolerance}")
    dt, n1, n2 = _common_cell(float(d[0]), float(d[1]), step)
    L = path.lengths
    u = (path.points[1:] - path.points[:-1]) / L[:, None]
    sin_turn = math.sqrt(max(0.0, 1.0 - float(np.dot(u[0], u[1])) ** 2))
    J = np.asarray(limits.jerk, dtype=np.float64).reshape(-1)
    if J.size != path.dim:
        raise ParameterError(f"corner_limit_bound: limits for {J.size} axes on a path of {path.dim}")

    def feasible(N: int) -> bool:
        return _feasible(N, dt, n1, n2, F, L, u, J, sin_turn, float(tolerance), d)

    lo = max(1, math.ceil(float(np.max(L / F)) / dt)) - 1  # infeasible: a block's mass exceeds its cells
    hi = lo + 1
    while not feasible(hi):
        lo, hi = hi, 2 * hi
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if feasible(mid):
            hi = mid
        else:
            lo = mid
    return (hi - 1) * dt + float(d.sum())


def _common_cell(T1: float, T2: float, step: float) -> tuple[float, int, int]:
    """``(dt, T1 / dt, T2 / dt)``: the largest ``dt = T1 / n <= step`` with ``T2 / dt`` a whole
    number (to 1e-9 relative)."""
    for n in range(max(1, math.ceil(T1 / step - 1e-9)), math.ceil(100.0 * T1 / step) + 1):
        dt = T1 / n
        m = T2 / dt
        if abs(m - round(m)) <= 1e-9 * max(1.0, m):
            return dt, n, int(round(m))
    raise ParameterError(f"corner_limit_bound: delays {T1} and {T2} s have no common cell between "
                         f"{step / 100:g} and {step:g} s")


def _feasible(N, dt, n1, n2, F, L, u, J, sin_turn, eps, delays) -> bool:
    """Whether the relaxation (module docstring) admits references within ``N`` cells."""
    G = N + n1 + n2 + 1  # output samples g dt: from the first cell to past the last output change
    nv = 2 * N + G  # masses of block 1, of block 2, then the binaries
    rows, cols, vals, lo, hi = [], [], [], [], []
    r = 0

    def add(c, v, low, high):
        nonlocal r
        rows.extend([r] * len(c))
        cols.extend(c)
        vals.extend(v)
        lo.append(low)
        hi.append(high)
        r += 1

    for b in range(2):  # each block's length
        add(list(range(b * N, (b + 1) * N)), [1.0] * N, L[b], L[b])
    scale = 1.0 / (delays[0] * delays[1] * dt)
    for a in range(u.shape[1]):  # the mean jerk of each axis over each output cell
        if not np.isfinite(J[a]) or not np.any(u[:, a]):
            continue
        for g in range(G):
            c, v = [], []
            for shift, sign in ((0, 1.0), (n1, -1.0), (n2, -1.0), (n1 + n2, 1.0)):
                k = g - shift
                if 0 <= k < N:
                    for b in range(2):
                        if u[b, a]:
                            c.append(b * N + k)
                            v.append(sign * u[b, a] * scale)
            if c:
                add(c, v, -J[a], J[a])
    if sin_turn > 0.0:
        cells = np.arange(N) * dt
        big = float(L.sum())
        for g in range(G):
            t = g * dt
            # z_g = 1: s_2 sin <= eps (s_2 from below); z_g = 0: (L_1 - s_1) sin <= eps (s_1 from above)
            add(list(range(N, 2 * N)) + [2 * N + g], list(kernel_cdf(t - cells - dt, delays) * sin_turn) + [big],
                -np.inf, eps + big)
            add(list(range(N)) + [2 * N + g], list(kernel_cdf(t - cells, delays) * sin_turn) + [big],
                L[0] * sin_turn - eps, np.inf)
            if g + 1 < G:
                add([2 * N + g, 2 * N + g + 1], [1.0, -1.0], 0.0, np.inf)
    A = coo_matrix((vals, (rows, cols)), shape=(r, nv)).tocsr()
    upper = np.concatenate([np.full(N, F[0] * dt), np.full(N, F[1] * dt), np.ones(G)])
    integrality = np.concatenate([np.zeros(2 * N), np.ones(G)])
    res = milp(np.zeros(nv), constraints=LinearConstraint(A, lo, hi), bounds=Bounds(np.zeros(nv), upper),
               integrality=integrality, options={"time_limit": SOLVE_LIMIT})
    return res.status != 2  # 2: infeasible; optimal, or undecided within the time limit, counts as feasible
