"""Reference for the B-spline feed schedule: a direct path-parametrized minimum-time OCP in time.

States ``x = [s, s', s'']`` (arc length [mm] and its rates), control ``u = s'''`` piecewise constant
on ``N`` equal intervals of a free final time ``T`` (``h = T / N``), exact triple-integrator shooting.
The axis constraints are eq 3.27 with ``Q_s, Q_ss, Q_sss`` of the path as cubic B-spline
interpolants in ``s`` (CasADi ``interpolant``, 0.1 mm grid): at every node and at ``checks`` points
inside every interval, velocity and acceleration, and the jerk with the control on each side of a
node. ``0 <= s' <= F``; rest at both ends. Unlike a feed profile polynomial in ``s`` this formulation
starts from rest exactly (the jerk can jump at ``t = 0``), so it is the yardstick of the B-spline
method, up to its time grid.
"""

from __future__ import annotations

import time

import casadi as ca
import numpy as np

_IPOPT = {"print_level": 0, "tol": 1e-8, "acceptable_tol": 1e-6, "max_iter": 3000, "mu_strategy": "adaptive"}


def solve_ocp(path, machine, limits, feed: float, intervals: int, guess: np.ndarray, duration: float,
              checks: int = 1, grid_step: float = 0.1, options: dict | None = None):
    """Solve the OCP.

    Args:
        path, machine, limits, feed: the problem (``feed`` [mm/s]).
        intervals: ``N``.
        guess: ``(4, N + 1)`` warm start ``s, s', s'', s'''`` at the nodes of ``[0, duration]``.
        duration: warm-start final time [s].
        checks: extra check points per interval (equally spaced inside).
        grid_step: interpolation grid of the path derivatives [mm].
    Returns:
        ``(T, states (3, N + 1), jerks (N,), stats dict)``; stats has ``status``, ``success``,
        ``iterations``, ``solve_time``, ``build_time``.
    """
    t0 = time.perf_counter()
    S = path.length
    grid = np.linspace(0.0, S, max(int(np.ceil(S / grid_step)) + 1, 8))
    d = path.axis_derivatives(machine, grid)
    table = np.hstack([d.Q_s, d.Q_ss, d.Q_sss])  # (M, 15)
    interp = ca.interpolant("Qd", "bspline", [grid], table.ravel(order="C"))
    N = int(intervals)
    T = ca.SX.sym("T")
    X = ca.SX.sym("X", 3, N + 1)
    U = ca.SX.sym("U", N)
    h = T / N
    v, a, j = (np.asarray(x, dtype=np.float64) for x in (limits.velocity, limits.acceleration, limits.jerk))
    g, lo, hi = [], [], []

    def flow(x, u, tau):
        return ca.vertcat(x[0] + x[1] * tau + x[2] * tau**2 / 2 + u * tau**3 / 6,
                          x[1] + x[2] * tau + u * tau**2 / 2, x[2] + u * tau)

    def axis_rows(x, u_list):
        q = interp(ca.fmin(ca.fmax(x[0], 0.0), S))
        qs, qss, qsss = q[0:5], q[5:10], q[10:15]
        rows = [qs * x[1] / v, (qss * x[1] ** 2 + qs * x[2]) / a]
        rows += [(qsss * x[1] ** 3 + 3 * qss * x[1] * x[2] + qs * u) / j for u in u_list]
        return rows

    for k in range(N):
        g.append(X[:, k + 1] - flow(X[:, k], U[k], h))
        lo.append(np.zeros(3))
        hi.append(np.zeros(3))
    for k in range(N + 1):
        us = ([U[k - 1]] if k > 0 else []) + ([U[k]] if k < N else [])
        rows = axis_rows(X[:, k], us)
        for c in range(1, checks + 1) if k < N else ():
            xm = flow(X[:, k], U[k], h * c / (checks + 1))
            rows += axis_rows(xm, [U[k]])
            g.append(xm[1] / feed)
            lo.append(np.zeros(1))
            hi.append(np.ones(1))
        g += rows
        lo += [-np.ones(5)] * len(rows)
        hi += [np.ones(5)] * len(rows)
    w = ca.vertcat(T, ca.vec(X), U)
    big = np.inf
    lbx = np.concatenate([[1e-3], np.tile([0.0, 0.0, -big], N + 1), np.full(N, -big)])
    ubx = np.concatenate([[big], np.tile([S, feed, big], N + 1), np.full(N, big)])
    lbx[1:4] = ubx[1:4] = 0.0  # start at rest
    lbx[1 + 3 * N:4 + 3 * N] = ubx[1 + 3 * N:4 + 3 * N] = [S, 0.0, 0.0]  # stop at rest on the end
    solver = ca.nlpsol("ocp", "ipopt", {"x": w, "f": T, "g": ca.densify(ca.vertcat(*g))},
                       {"ipopt": {**_IPOPT, **(options or {})}, "print_time": False})
    build = time.perf_counter() - t0
    x0 = np.concatenate([[duration], guess[:3].T.ravel(), guess[3, :N]])
    t1 = time.perf_counter()
    sol = solver(x0=x0, lbx=lbx, ubx=ubx, lbg=np.concatenate(lo), ubg=np.concatenate(hi))
    solve = time.perf_counter() - t1
    st = solver.stats()
    z = np.asarray(sol["x"]).ravel()
    status = str(st.get("return_status", "unknown"))
    return float(z[0]), z[1:4 + 3 * N].reshape(N + 1, 3).T, z[4 + 3 * N:], {
        "status": status, "success": status in ("Solve_Succeeded", "Solved_To_Acceptable_Level"),
        "iterations": int(st.get("iter_count", 0)), "solve_time": solve, "build_time": build,
    }
