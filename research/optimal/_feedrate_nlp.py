"""One window of the B-spline feed optimization (Sencer 2009 thesis eq 3.39-3.58) as a CasADi NLP
solved by IPOPT.

Variables: the free feed control points ``f_i`` of the window (scaled by the feed cap ``F``).
Constraints at check points ``s_k`` (fixed in ``s``, so ``Q_s, Q_ss, Q_sss`` are constants there and
every constraint is a polynomial in the ``f_i``):

- ``per_axis`` (eq 3.41, 3.46, 3.53, exact): for each axis ``i``
  ``|Q_s,i f| <= v_i``, ``|Q_ss,i f^2 + Q_s,i f f_s| <= a_i``,
  ``|Q_sss,i f^3 + 3 Q_ss,i f^2 f_s + Q_s,i f (f_s^2 + f f_ss)| <= j_i``;
- ``combined`` (eq 3.43, 3.49, 3.56, the thesis' single conservative inequality per kind, with the
  largest normalized partial derivatives of eq 3.45/3.48/3.55; absolute values split into sign
  combinations so that the constraints stay smooth);
- the feed bounds ``C_F-`` / ``C_F+`` of eq 3.57: ``f_min <= f <= F``.

Objective: ``time`` — ``T = int ds / f`` by 3-point Gauss-Legendre on every span (the minimum-time
objective of eq 3.30/3.58); or ``sum`` — the thesis' linear surrogate ``max sum_i f_i`` (eq 3.58).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import casadi as ca
import numpy as np
import scipy.sparse as sp

from research.optimal._feedrate_spline import basis

_IPOPT = {"print_level": 0, "tol": 1e-9, "acceptable_tol": 1e-6, "max_iter": 3000, "mu_strategy": "adaptive",
          "bound_relax_factor": 0.0}


@dataclass(frozen=True)
class WindowData:
    """What one window NLP needs (all in mm, s, rad).

    Attributes:
        knots: global feed knot vector.
        columns: control-point indices that influence the window's spans (``(m,)``, sorted).
        free: boolean mask over ``columns``: which are optimized (the others are fixed to ``values``).
        values: ``(m,)`` current / fixed control values [mm/s] (also the warm start of the free ones).
        checks: ``(K,)`` check points [mm]; Qs, Qss, Qsss: ``(K, 5)`` path derivatives there.
        nodes, weights: Gauss nodes [mm] and weights of ``int ds / f`` over the window's spans.
        velocity, acceleration, jerk: ``(5,)`` axis limits.
        feed: feed cap ``F`` [mm/s]; feed_min: positivity floor [mm/s].
        form: ``"per_axis"`` or ``"combined"``; objective: ``"time"`` or ``"sum"``.
    """

    knots: np.ndarray
    columns: np.ndarray
    free: np.ndarray
    values: np.ndarray
    checks: np.ndarray
    Qs: np.ndarray
    Qss: np.ndarray
    Qsss: np.ndarray
    nodes: np.ndarray
    weights: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    jerk: np.ndarray
    feed: float
    feed_min: float
    form: str
    objective: str


@dataclass(frozen=True)
class WindowSolution:
    """IPOPT's outcome for one window: control values over ``columns`` [mm/s] (fixed ones unchanged),
    status, iterations, solve / build wall time [s] and the objective (``T`` [s] or the surrogate)."""

    values: np.ndarray
    status: str
    success: bool
    iterations: int
    solve_time: float
    build_time: float
    objective: float


def _dm(matrix: np.ndarray) -> ca.DM:
    m = sp.csc_matrix(np.where(np.abs(matrix) > 1e-300, matrix, 0.0))
    return ca.DM(m)


def solve_window(data: WindowData, options: dict | None = None) -> WindowSolution:
    """Build and solve the window NLP; returns the control values (fixed ones unchanged)."""
    t0 = time.perf_counter()
    F = float(data.feed)
    cols = data.columns
    B = [basis(data.knots, data.checks, nu)[:, cols] for nu in range(3)]
    G = basis(data.knots, data.nodes, 0)[:, cols]
    nfree = int(data.free.sum())
    x = ca.SX.sym("f", nfree)
    # full window control vector: fixed values (constants) + free ones (scaled by F)
    P = np.zeros((cols.size, nfree))
    P[np.flatnonzero(data.free), np.arange(nfree)] = F
    fixed = np.where(data.free, 0.0, data.values)
    fw = ca.mtimes(_dm(P), x) + ca.DM(fixed)
    f, f1, f2 = (ca.mtimes(_dm(b), fw) for b in B)
    rows, lower, upper = _constraints(data, f, f1, f2)
    rows.append(f / F)
    lower.append(np.full(data.checks.size, data.feed_min / F))
    upper.append(np.ones(data.checks.size))
    g = ca.densify(ca.vertcat(*rows))
    if data.objective == "time":
        J = ca.dot(ca.DM(data.weights), 1.0 / ca.mtimes(_dm(G), fw))
    else:
        J = -ca.sum1(x) * (data.knots[4] - data.knots[3]) / F  # eq 3.58, scaled to about seconds
    solver = ca.nlpsol("feed", "ipopt", {"x": x, "f": J, "g": g},
                       {"ipopt": {**_IPOPT, **(options or {})}, "print_time": False})
    build = time.perf_counter() - t0
    x0 = np.clip(data.values[data.free], data.feed_min, F) / F
    t1 = time.perf_counter()
    sol = solver(x0=x0, lbx=0.0, ubx=1.5, lbg=np.concatenate(lower), ubg=np.concatenate(upper))
    solve = time.perf_counter() - t1
    stats = solver.stats()
    values = data.values.copy()
    values[data.free] = np.asarray(sol["x"]).ravel() * F
    status = str(stats.get("return_status", "unknown"))
    return WindowSolution(values, status, status in ("Solve_Succeeded", "Solved_To_Acceptable_Level"),
                          int(stats.get("iter_count", 0)), solve, build, float(sol["f"]))


def _constraints(data: WindowData, f, f1, f2):
    """Scaled constraint rows (each bounded by [-1, 1] or [-inf, 1])."""
    v, a, j = data.velocity, data.acceleration, data.jerk
    sdd = f * f1
    sddd = f * (f1 * f1 + f * f2)
    rows, lo, hi = [], [], []
    K = data.checks.size
    if data.form == "per_axis":
        for i in range(5):
            qs, qss, qsss = (ca.DM(q[:, i]) for q in (data.Qs, data.Qss, data.Qsss))
            rows += [qs * f / v[i],                                           # eq 3.41
                     (qss * f * f + qs * sdd) / a[i],                         # eq 3.46
                     (qsss * f * f * f + 3 * qss * f * sdd + qs * sddd) / j[i]]  # eq 3.53
            lo += [-np.ones(K)] * 3
            hi += [np.ones(K)] * 3
        return rows, lo, hi
    # combined (eq 3.45, 3.48, 3.55): largest normalized partials over the axes
    Qv = ca.DM(np.max(np.abs(data.Qs) / v, axis=1))
    Qa_s, Qa_ss = (ca.DM(np.max(np.abs(q) / a, axis=1)) for q in (data.Qs, data.Qss))
    Qj_s, Qj_ss, Qj_sss = (ca.DM(np.max(np.abs(q) / j, axis=1)) for q in (data.Qs, data.Qss, data.Qsss))
    rows.append(Qv * f)                                                      # eq 3.43
    for sign in (1.0, -1.0):                                                 # eq 3.49
        rows.append(Qa_ss * f * f + sign * Qa_s * sdd)
    for s1 in (1.0, -1.0):                                                   # eq 3.56
        for s2 in (1.0, -1.0):
            rows.append(Qj_sss * f * f * f + s1 * 3 * Qj_ss * f * sdd + s2 * Qj_s * sddd)
    lo += [np.full(K, -np.inf)] * len(rows)
    hi += [np.ones(K)] * len(rows)
    return rows, lo, hi
