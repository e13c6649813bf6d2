"""Re-linearised fixed-order solves of the smooth FIR NLP (``_fir_smooth``), verified exactly.

``smooth_search`` starts from a feasible plan of ``_fir_optimize._Problem`` (one feed per block,
pieces of shares ``(1/4, 1/2, 1/4)``), and for at most ``rounds`` rounds: builds the NLP of the
current plan's break order (``_fir_smooth.build_nlp``), solves it with IPOPT, maps the answer back
onto the ``_Problem`` variables and checks it on the exact profile (corner errors, path deviation,
exact per-piece peaks: ``_Problem.feasible``) and its residual vibration (closed form S2, exact
for the piecewise-polynomial profile). A verified answer faster than the best so far is kept; a
verified round that gains less than :data:`REL_GAIN` ends the search; otherwise the next round
is linearised at the answer, with tied events swapped where the order constraint's multiplier
asks for it. An answer that fails the exact check tightens the sampled constraints
(velocity, tube) by :data:`MARGINS` in turn and is solved again from the same order.
"""

from __future__ import annotations

import numpy as np

from research.errors import ParameterError
from research.interpolators import _fir_smooth as sm
from research.piecewise import NumpyPiecewise

#: relative tightening of the sampled (velocity, tube) constraints after a failed exact check
MARGINS = (0.0, 2e-3, 1e-2, 3e-2)
#: a verified round that gains less than this share of the best cycle time ends the search (the
#: 0.1 % convergence criterion issue 19 item 3 sets for the OCP's grid refinement); measured on
#: cam30 at bench_cam's setting, rounds 4 and 5 gained 0.013 % together for 40 % of the time
REL_GAIN = 1e-3


def to_z(problem, layout: sm.Layout, x: np.ndarray) -> np.ndarray:
    """``_Problem`` variables ``x`` (head/body/tail shares equal to ``layout.shares``) -> ``z``."""
    M, F = problem.M, problem.F
    f3 = x[M - 1: 4 * M - 1].reshape(3, M) * F
    P = layout.shares.size
    feeds = f3.T if P == 3 else f3[1][:, None]
    tau = (layout.shares[None, :] * layout.L[:, None] / feeds).ravel()
    g = layout.Td * (1.0 - x[: M - 1])
    plan = problem.plan(x, 1.0)
    return np.concatenate([tau, g, np.asarray(plan.corner_times)])


def to_x(problem, layout: sm.Layout, z: np.ndarray) -> np.ndarray:
    """``z`` -> ``_Problem`` variables (feeds ``s L / tau`` per piece)."""
    M, F, P = problem.M, problem.F, layout.shares.size
    tau = z[: layout.n_pieces].reshape(M, P)
    feeds = layout.shares[None, :] * layout.L[:, None] / tau / F
    if P == 1:
        feeds = np.repeat(feeds, 3, axis=1)
        h = t = np.full(M, 0.25)
    else:
        h, t = np.full(M, layout.shares[0]), np.full(M, layout.shares[-1])
    T = 1.0 - z[layout.n_pieces: layout.n_pieces + M - 1] / layout.Td
    return np.concatenate([np.clip(T, 0.0, 1.0), feeds.T.ravel(), h, t])


def smooth_search(problem, x_start: np.ndarray, check_period: float, *, modes=(), residual=None,
                  shares=(0.25, 0.5, 0.25), rounds: int = 6, max_iter: int = 300):
    """Best verified plan of the re-linearised fixed-order NLPs.

    Args:
        problem: ``_fir_optimize._Problem`` of the path.
        x_start: a plan in ``problem``'s variables with head/tail shares ``shares[0]``, ``shares[-1]``
            (one piece feed where ``shares`` has one entry).
        check_period: spacing [s] of the exact path-deviation check.
        modes: ``(axis, frequency_hz, damping)`` per structural mode; ``residual``: ``(m,)``
            residual bounds [mm] that an accepted plan must meet.
        shares: fixed shares of each block's pieces.
        rounds: NLP solves at most (re-linearisations and margin re-solves together).
        max_iter: IPOPT iterations per solve.

    Returns:
        ``(x_best or None, log)``: the fastest verified plan (``None`` if no round verified) and
        per round ``{"time", "status", "iterations", "verified", "margin", "swaps"}``.
    """
    layout = sm.Layout.build(problem.path.points, problem.F, problem.delays, shares)
    lo, hi = layout.bounds()
    z = to_z(problem, layout, np.asarray(x_start, dtype=np.float64))
    best, t_best, log = None, np.inf, []
    order, swaps, m_i = None, [], 0
    for _ in range(rounds):
        margin = MARGINS[m_i]
        nlp, lbg, ubg, fixed = sm.build_nlp(layout, z, problem.limits, problem.eps, modes, residual,
                                            margin=margin, previous=order, swap=swaps)
        z_new, lam_g, status, iters = sm.solve(nlp, lbg, ubg, z, lo, hi, max_iter)
        x = to_x(problem, layout, z_new)
        t_new = problem.time(x)
        ok = bool(np.all(np.isfinite(z_new))) and problem.feasible(x, check_period)
        if ok and modes:  # on the exact profile, independently of S2
            left = profile_residuals(problem.plan(x, check_period).position, modes)
            ok = bool(np.all(left <= np.asarray(residual) * (1 + 1e-6) + 1e-9))
        log.append({"time": t_new, "status": status, "iterations": iters, "verified": ok, "margin": margin,
                    "swaps": len(swaps)})
        if ok:
            improved = t_new < t_best * (1 - REL_GAIN)
            if t_new < t_best:
                best, t_best = x, t_new
            if not improved:
                break  # (almost) no progress across the tied events: a local optimum
            # re-linearise at the answer: its order, with tied events crossed where asked
            order = sm.order_of(fixed.ev_rows @ z_new + fixed.ev_const, fixed.order)
            swaps = sm.tied_swaps(fixed, z_new, lam_g[: fixed.n_order])
            z = z_new
        elif m_i + 1 < len(MARGINS):
            m_i += 1  # sampled constraints missed an excess between samples: tighten, same order
        else:
            break
    return best, log


def mode_tuples(modes) -> tuple[tuple[int, float, float], ...]:
    """``(axis, frequency_hz, damping)`` of each mode (objects with those attributes, e.g.
    ``research.optimal.StructuralMode``, or tuples)."""
    out = []
    for m in modes:
        a, f, zt = (m.axis, m.frequency_hz, m.damping) if hasattr(m, "axis") else tuple(m)
        if not (int(a) >= 0 and np.isfinite(f) and f > 0 and 0 < zt < 1):
            raise ParameterError(f"a mode needs axis >= 0, frequency_hz > 0 and damping in (0, 1), got {m!r}")
        out.append((int(a), float(f), float(zt)))
    return tuple(out)


def profile_residuals(position, modes, nodes: int = 8) -> np.ndarray:
    """Residual envelope [mm] (eq V3) of each mode driven by the acceleration of the exact profile
    ``position`` (a piecewise polynomial, at rest at its end): ``A = exp(-s T) |int a(t)
    exp((s - i wd) t) dt| / wd``, the integral by ``nodes``-point Gauss-Legendre on every piece
    (exact to rounding for pieces short against the period: polynomial times exponential)."""
    br = np.asarray(position.breaks, dtype=np.float64)
    co = np.asarray(position.coeffs, dtype=np.float64)
    pn = NumpyPiecewise(br, co)
    x, w = np.polynomial.legendre.leggauss(nodes)
    h = np.diff(br)
    t = br[:-1, None] + 0.5 * h[:, None] * (x[None, :] + 1.0)
    acc = pn(t.ravel(), 2).reshape(t.shape + (co.shape[2],))
    T = br[-1]
    out = []
    for axis, f, zt in modes:
        wn = 2 * np.pi * f
        s, wd = zt * wn, wn * np.sqrt(1 - zt * zt)
        # exp((s - i wd)(t - T)) keeps the factors bounded
        kern = np.exp((s - 1j * wd) * (t - T))
        integral = np.sum(0.5 * h[:, None] * w[None, :] * acc[..., axis] * kern)
        out.append(abs(integral) / wd)
    return np.array(out)
