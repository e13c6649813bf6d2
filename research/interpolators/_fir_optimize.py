"""Optimized FIR cornering: per-corner overlaps and per-block feeds chosen for the least cycle time.

A named extension (issue 19), not Sencer 2015's method: the paper fixes the filter delays and takes
each corner's overlap ``T_k`` from the tolerance alone (eq 13/14) at the commanded feed. Here the
delays stay fixed (they are what keeps the machine's modes quiet, eq 10) and the plan's other
degrees of freedom are optimized together::

    minimize   sum_k T_v,k + T_d + sum_k (T_d - T_k)                        (eq 11: the cycle time)
    over       0 <= T_k <= T_d  (M - 1 corners); per block a head, body and tail piece of shares
               h_k, 1 - h_k - t_k, t_k of its length at feeds F_min <= F_h,k, F_b,k, F_t,k <= F,
               T_v,k = L_k (h_k / F_h,k + (1 - h_k - t_k) / F_b,k + t_k / F_t,k)
    subject to |V_k - p(t)| <= eps at every vertex     (exact profile: ``_fir_verify.corner_distances``)
               dist(p(t_i), path) <= eps on samples every ``sample_period`` along the motion
               |q^(nu)_a(t)| <= limit_a,nu, nu = 1..3, on every piece of the exact profile

Two searches solve it. The default, ``"smooth"`` (``_fir_reorder``, ``_fir_smooth``), writes the
profile in closed form (each pulse filtered is a B-spline CDF) with the order of its break points
fixed, so that every constraint above, and the residual vibration of given structural modes, is
smooth; IPOPT solves that, the order is re-linearised at the answer a bounded number of times, and
only answers verified on the exact profile are kept. The older SLSQP runs (``"paper"``,
``"safe"``) work on the exact profile directly (below). The best verified answer is then polished
(``_fir_polish``: overlaps and block feeds raised one at a time, every move verified exactly).


The profile is the one ``plan_fir`` builds (``_fir_blocks.build_profile``: exact piecewise
polynomial, differentiable in ``T_k`` and ``F_k``); peaks are exact per piece (ends, and where the
next derivative vanishes, in closed form for up to three filters), their gradients by the envelope
theorem (a peak's location is held). SciPy's SLSQP solves the problem with JAX Jacobians; constraint
samples are grouped by their maximum (``_GROUP`` per row) to keep the QP small.

Feasibility is never left to the solver: the answer is checked on the exact profile (corner
errors, ``path_deviations`` every ``check_period``, ``_fir_piece_peaks.corner_peak_ratios``) and, if it
breaks anything, pulled back by bisection along the segment to the best feasible start plan
(the limit-holding ``plan_fir`` where its plan fits this parametrization, else exact stops at the
closed-form safe feeds), so the result always holds the tolerance and the limits.

The head and tail pieces let a corner be approached slowly without slowing the whole of both
blocks: on the diamond a continuing axis doubles its jerk at any overlap below ``2 T_2`` (its
stop and start jerk phases add), so with one feed per block only an exact stop or a slow block
holds the envelope.

Scope: G01 paths (``Polyline``), up to three filters,
paths of tens of blocks (the dense Jacobian grows as ``M^2``); the start and stop ramps are the
filters' own.
"""

from __future__ import annotations

import time
from functools import partial

import jax
import jax.numpy as jnp
import numpy as np
from scipy.optimize import minimize

from research.errors import ParameterError, PathError
from research.interpolators._fir_blocks import build_profile
from research.interpolators._fir_chain import check_delays
from research.interpolators._fir_kernels import verified_bound
from research.interpolators._fir_limits import LIMIT_RTOL, feed_caps
from research.interpolators._fir_piece_peaks import corner_peak_ratios
from research.interpolators._fir_polish import polish
from research.interpolators._fir_reorder import mode_tuples, profile_residuals, smooth_search
from research.interpolators._fir_verify import certify_settings, corner_distances, path_deviations
from research.interpolators._fir_settle import _pulse_table
from research.interpolators.fir import CHECK_PERIOD, FIRPlan, _as_toolpath, plan_fir
from research.limits import AxisLimits
from research.paths.polyline import Polyline
from research.piecewise import DEGENERATE_PIECE, NumpyPiecewise

#: constraint samples (peak pieces, deviation samples) merged into one row by their maximum
_GROUP = 4
#: bisection steps back towards the feasible start when the solver's answer breaks a constraint
_BACKTRACK = 12
#: re-solves with the constraints tightened by the exact check's excess (sampled deviation)
_MARGIN_ROUNDS = 3
#: an SLSQP iterate within this of its own constraints is worth the exact check
_NLP_SLACK = 1e-7
#: paths of up to this many blocks get head / body / tail pieces in the "smooth" search
_PIECED = 12
#: feeds are kept above this share of the commanded feed (a positive pulse length bound)
_FEED_FLOOR = 1e-3


def optimize_fir(path: Polyline, feed: float, delays, tolerance: float, limits: AxisLimits | None = None, *,
                 max_iter: int = 150, starts=("smooth",), sample_period: float = 2e-3,
                 check_period: float = CHECK_PERIOD, modes=(), residual_vibration=None, rounds: int = 6, piece_shares=None,
                 full_output: bool = False):
    """FIR plan with per-corner overlaps and per-block feeds that minimise the cycle time.

    Args:
        path: G01 tool path [mm].
        feed: commanded feed ``F`` [mm/s], the upper bound of every block's feed.
        delays: FIR delays ``T_1 .. T_n`` [s], 2 or 3 filters when ``limits`` bound the jerk.
        tolerance: cornering tolerance ``eps`` [mm], > 0.
        limits: per-axis velocity / acceleration / jerk limits [mm/s, mm/s^2, mm/s^3], or ``None``.
        max_iter: SLSQP iterations per start.
        starts: the searches, in turn: ``"smooth"`` (``_fir_reorder.smooth_search``: the closed-form
            profile with its break order fixed, IPOPT, re-linearised up to ``rounds`` times, from
            the fastest feasible start plan), and SLSQP on the exact profile from ``"paper"``
            (eq 13/14 overlaps at ``F``, usually infeasible) and / or ``"safe"`` (the fastest
            feasible start plan); the fastest verified answer is kept.
        sample_period: spacing [s] of the path-deviation samples inside the optimization.
        check_period: spacing [s] of the final path-deviation check (as in :func:`plan_fir`).
        modes: structural modes ``(axis, frequency_hz, damping)`` (or objects with those fields,
            e.g. ``research.optimal.StructuralMode``) whose residual vibration (eq V3) the
            ``"smooth"`` search must keep within ``residual_vibration`` [mm] per mode (default: the
            plain ``plan_fir`` plan's, on its exact profile); SLSQP runs ignore them.
        rounds: NLP solves of the ``"smooth"`` search at most.
        piece_shares: fixed shares of each block's pieces in the ``"smooth"`` search (default: head,
            body and tail of 1/4, 1/2, 1/4 on paths of up to :data:`_PIECED` blocks, one piece
            per block beyond: the NLP grows with the number of breaks).
        full_output: also return a dict ``{"start_time", "runs", "kept", "quiet", "polish", "wall_time"}``: cycle time
            of the feasible start plan [s]; per start its SLSQP iterations, message, the solver's
            own cycle time [s], the share ``backtrack`` of the step to it kept feasible (NaN: an
            earlier iterate was kept) and the resulting time [s] (``"smooth"``: per NLP round its
            ``time``, ``status``, ``iterations``, ``verified``, ``margin``, ``swaps``); ``"optimized"``,
            ``"plan_fir"`` (limit-holding) or ``"plan_fir_plain"`` (without limits); ``"quiet"``: the result meets the residual bound (True without
            ``modes``); ``"polish"``: cycle time [s] ``before`` and ``after`` the verified coordinate
            ascent of ``_fir_polish`` and its number of exact ``checks``; wall time [s].

    Returns:
        A :class:`FIRPlan` (``rounds`` = 0), or ``(plan, info)`` with ``full_output``; the
        limit-holding or the plain ``plan_fir`` plan where that is faster and verifies (exact peaks
        within the limits, residual within its bound; ``info["kept"]``), so the result is never
        slower than either where it verifies.

    Raises:
        PathError: ``path`` is not a Polyline.
        ParameterError: bad feed, tolerance, delays or limits.
    """
    if not isinstance(path, Polyline):
        raise PathError(f"optimize_fir takes a Polyline (G01 blocks), got {type(path).__name__}")
    d_np = np.asarray(delays, dtype=np.float64).reshape(-1)
    check_delays(d_np)
    if not (np.isfinite(feed) and feed > 0):
        raise ParameterError(f"feed F must be finite and > 0 mm/s, got {feed!r}")
    if not (np.isfinite(tolerance) and tolerance > 0):
        raise ParameterError(f"optimize_fir needs a cornering tolerance eps > 0 mm, got {tolerance!r}")
    if limits is not None and limits.n_axes != path.dim:
        raise ParameterError(f"limits have {limits.n_axes} axes but the path has {path.dim}")
    if d_np.size > 3 or (limits is not None and d_np.size < 2 and np.any(np.isfinite(limits.jerk))):
        raise ParameterError("optimize_fir with limits supports 2 or 3 filters (exact peaks; one filter gives unbounded jerk)")
    modes = mode_tuples(modes)
    t_wall = time.perf_counter()
    problem = _Problem(path, float(feed), d_np, float(tolerance), limits, sample_period)
    plain = plan_fir(path, float(feed), d_np, float(tolerance), check_period=check_period)
    if modes and residual_vibration is None:
        residual_vibration = profile_residuals(plain.position, modes)
    residual = None if not modes else np.broadcast_to(np.asarray(residual_vibration, dtype=np.float64), (len(modes),))
    x_safe, t_safe, x_start, held, other_starts = problem.start(check_period, modes, residual)
    n_c, M = problem.M - 1, problem.M
    bounds = [(0.0, 1.0)] * n_c + [(_FEED_FLOOR, 1.0)] * (3 * M) + [(0.0, 1.0)] * (2 * M)
    lower, upper = np.array([b[0] for b in bounds]), np.array([b[1] for b in bounds])
    scale = 1.0 / t_safe
    shares = np.zeros((M, n_c + 5 * M))  # h_k + t_k <= 1
    shares[np.arange(M), n_c + 3 * M + np.arange(M)] = shares[np.arange(M), n_c + 4 * M + np.arange(M)] = -1.0
    x_best, t_best, runs = x_safe, t_safe, []
    if modes and not problem.holds(problem.plan(x_safe, check_period), modes, residual):
        t_best = np.inf  # the start plan rings more than allowed: any quiet answer beats it
    for name in starts:
        if name not in ("paper", "safe", "smooth"):
            raise ParameterError(f"optimize_fir starts must be 'smooth', 'paper' or 'safe', got {name!r}")
        if name == "smooth":
            sh = piece_shares if piece_shares is not None else ((0.25, 0.5, 0.25) if M <= _PIECED else (1.0,))
            x_s, log = smooth_search(problem, x_safe, check_period, modes=modes, residual=residual, rounds=rounds, shares=sh)
            for x0 in other_starts if modes and x_s is None and not np.isfinite(t_best) else ():
                # no quiet plan from a start that rings: the other feasible starts, fastest first
                x_s, more = smooth_search(problem, x0, check_period, modes=modes, residual=residual, rounds=rounds,
                                          shares=sh)
                log += more
                if x_s is not None:
                    break
            run = {"start": name, "iterations": sum(r["iterations"] for r in log), "status": log[-1]["status"] if log else "",
                   "solver_time": min((r["time"] for r in log), default=np.nan), "backtrack": np.nan, "time": t_safe,
                   "rounds": log}
            if x_s is not None and problem.time(x_s) < t_best:
                x_best, t_best = x_s, problem.time(x_s)
                run["time"] = t_best
            runs.append(run)
            continue
        iterates = []  # SLSQP's iterates that meet its own constraints: it may wander off later

        def keep(x):
            x = _clean(x, lower, upper, n_c, M)
            if problem.time(x) < t_best and np.min(problem.constraints(x)) >= -_NLP_SLACK:
                iterates.append(x)

        x0, iterations, margin = (x_start if name == "paper" else x_safe), 0, 0.0
        for _ in range(_MARGIN_ROUNDS + 1):
            problem.data["margin"] = jnp.asarray(margin)
            res = minimize(lambda x: problem.time(x) * scale, x0,
                           jac=lambda x: problem.time_grad(x) * scale, bounds=bounds, method="SLSQP",
                           constraints=[{"type": "ineq", "fun": problem.constraints, "jac": problem.jacobian},
                                        {"type": "ineq", "fun": lambda x: 1.0 + shares @ x, "jac": lambda x: shares}],
                           options={"maxiter": int(max_iter), "ftol": 1e-10}, callback=keep)
            x0, iterations = _clean(res.x, lower, upper, n_c, M), iterations + int(res.nit)
            # deviation samples miss what lies between them: tighten by twice the exact excess, solve again
            excess = problem.excess(x0, check_period)
            if excess <= LIMIT_RTOL or np.min(problem.constraints(x0)) < -1e-6:
                break
            margin += 2.0 * excess
        problem.data["margin"] = jnp.asarray(0.0)
        x_opt = x0
        run = {"start": name, "iterations": iterations, "status": str(res.message), "margin": margin,
               "solver_time": problem.time(x_opt), "backtrack": 0.0, "time": t_safe}
        # verified in order of cycle time: the solver's answer, then its feasible-looking iterates
        for x in sorted([x_opt] + iterates, key=problem.time):
            if problem.time(x) >= t_best:
                break
            if problem.feasible(x, check_period):
                x_best, t_best = x, problem.time(x)
                run["time"], run["backtrack"] = t_best, float("nan") if x is not x_opt else 1.0
                break
        if run["time"] == t_safe and problem.time(x_opt) < t_best:  # pull back towards the safe start
            theta = _pull_back(problem, x_safe, x_opt, check_period)
            x_run = x_safe + theta * (x_opt - x_safe)
            if theta > 0 and problem.time(x_run) < t_best:
                x_best, t_best = x_run, problem.time(x_run)
                run["time"], run["backtrack"] = t_best, theta
        runs.append(run)
    polished = {"before": t_best, "after": t_best, "checks": 0}
    if np.isfinite(t_best):  # x_best verified (tolerance, limits and, with modes, the residual)
        def verified(x):
            if not problem.feasible(x, check_period):
                return False
            return not modes or bool(np.all(profile_residuals(problem.plan(x, check_period).position, modes)
                                            <= residual * (1 + 1e-6) + 1e-9))

        x_best, polished["checks"] = polish(problem, x_best, verified)
        t_best = polished["after"] = problem.time(x_best)
    plan = problem.plan(x_best, check_period)
    kept = "optimized"
    # never slower than the limit-holding or the plain plan_fir, where that plan holds the limits
    # (exact peaks) and the residual bound: the plain plan holds limits taken from its own peaks and
    # the residual bound taken from its own residual (the study's convention (a)), where the
    # limit-holding plan can ring more
    for other, name in ((held, "plan_fir"), (plain, "plan_fir_plain")):
        if float(other.cycle_time) < float(plan.cycle_time) and problem.holds(other, modes, residual):
            plan, kept = other, name
    if not full_output:
        return plan
    quiet = not modes or bool(np.all(profile_residuals(plan.position, modes) <= residual * (1 + 1e-6) + 1e-9))
    return plan, {"start_time": t_safe, "runs": runs, "kept": kept, "quiet": quiet, "polish": polished,
                  "wall_time": time.perf_counter() - t_wall}


def _clean(x, lower, upper, n_c: int, M: int) -> np.ndarray:
    """``x`` inside its bounds, with head and tail shares that add to at most 1."""
    x = np.clip(np.asarray(x, dtype=np.float64), lower, upper)
    excess = np.maximum(x[n_c + 3 * M:n_c + 4 * M] + x[n_c + 4 * M:] - 1.0, 0.0)
    x[n_c + 3 * M:n_c + 4 * M] -= excess
    return x


def _pull_back(problem, x_safe, x_opt, check_period: float) -> float:
    """Largest share ``theta`` of the step from the feasible ``x_safe`` to ``x_opt`` found feasible
    (1 if ``x_opt`` is; else :data:`_BACKTRACK` bisections; 0 if none)."""
    if problem.feasible(x_opt, check_period):
        return 1.0
    lo, hi = 0.0, 1.0
    for _ in range(_BACKTRACK):
        mid = 0.5 * (lo + hi)
        if problem.feasible(x_safe + mid * (x_opt - x_safe), check_period):
            lo = mid
        else:
            hi = mid
    return lo


class _Problem:
    """The NLP of :func:`optimize_fir` in scaled variables ``x = [T_k / T_d (M - 1), F_h,k / F,
    F_b,k / F, F_t,k / F (M each), h_k, t_k (M each)]``."""

    def __init__(self, path: Polyline, feed: float, delays: np.ndarray, eps: float, limits, sample_period: float):
        self.path, self.F, self.eps, self.limits = path, feed, eps, limits
        self.tp = _as_toolpath(path)
        table = _pulse_table(self.tp)
        self.M = M = self.tp.n_blocks
        self.Td = float(delays.sum())
        self.delays = jnp.asarray(delays)
        self.L = self.tp.lengths
        self.vertices = jnp.asarray(self.tp.vertices)
        nominal = float(np.sum(self.L) / feed + M * self.Td)
        # a power of two of samples, so that paths of similar duration share the compiled functions
        self.n_samples = max(1 << int(np.ceil(np.log2(max(nominal / sample_period, 1.0)))), _GROUP)
        real = table.block < M
        self.data = {
            "start": jnp.asarray(self.tp.start), "geo": jnp.asarray(table.geo), "block": jnp.asarray(table.block),
            "gap": jnp.asarray(table.gap), "line": jnp.asarray(real & ~table.gap),
            "role": jnp.asarray(np.where(table.role < 0, 1, table.role)), "blk": jnp.asarray(np.minimum(table.block, M - 1)),
            "L": jnp.asarray(self.L), "pad": jnp.zeros(table.m_pad - M + 1), "Td": jnp.asarray(self.Td),
            "delays": self.delays, "feed": jnp.asarray(feed), "eps": jnp.asarray(eps), "vertices": self.vertices,
            "P0": jnp.asarray(path.points[:-1]), "P1": jnp.asarray(path.points[1:]),
            "lim": None if limits is None else jnp.asarray(np.stack([limits.velocity, limits.acceleration, limits.jerk])),
            "margin": jnp.asarray(0.0),
        }

    # -- objective (eq 11) and constraints --------------------------------------------------------
    def time(self, x) -> float:
        return float(_cycle(jnp.asarray(x), self.data, self.M))

    def time_grad(self, x) -> np.ndarray:
        return np.asarray(_cycle_grad(jnp.asarray(x), self.data, self.M))

    def constraints(self, x) -> np.ndarray:
        return np.asarray(_constraints(jnp.asarray(x), self.data, self.M, self.n_samples))

    def jacobian(self, x) -> np.ndarray:
        return np.asarray(_jacobian(jnp.asarray(x), self.data, self.M, self.n_samples))

    def excess(self, x, check_period: float) -> float:
        """Largest relative excess of the exact checks (error / eps - 1, peak / limit - 1)."""
        plan = self.plan(x, check_period)
        worst = max(float(np.max(np.asarray(plan.corner_errors), initial=0.0)), plan.path_deviation) / self.eps - 1.0
        if self.limits is not None:
            pos_np = NumpyPiecewise(np.asarray(plan.position.breaks), np.asarray(plan.position.coeffs))
            span = corner_peak_ratios(pos_np, np.array([float(plan.position.start)]), np.array([float(plan.position.end)]), self.limits)
            worst = max(worst, float(span[0]) - 1.0)
        return worst

    # -- exact checks and plans ---------------------------------------------------------------------
    def plan(self, x, check_period: float) -> FIRPlan:
        starts, ends, position, centre = _profile(jnp.asarray(x), self.data, self.M)
        M = self.M
        pos_np = NumpyPiecewise(np.asarray(position.breaks), np.asarray(position.coeffs))
        dev, _, _ = path_deviations(pos_np, self.tp, np.asarray(starts[:M]), np.asarray(centre[: M - 1]), self.Td,
                                    np.full(M, self.eps), check_period, certify=certify_settings(check_period))
        x = np.asarray(x)
        cruise = np.max(x[M - 1: 4 * M - 1].reshape(3, M), axis=0) * self.F
        return FIRPlan(starts[:M], ends[:M] - starts[:M], jnp.asarray(x[: M - 1] * self.Td), jnp.asarray(cruise),
                       self.delays, position, centre[: M - 1], self.vertices, float(dev), 0, self.tp.axes)

    def feasible(self, x, check_period: float) -> bool:
        """Every vertex and every checked sample within ``eps`` and every exact peak within the limits."""
        plan = self.plan(x, check_period)
        slack = verified_bound(self.eps)  # as plan_fir's verification
        if self.M > 1 and float(np.max(np.asarray(plan.corner_errors))) > slack:
            return False
        if plan.path_deviation > slack:
            return False
        if self.limits is not None:
            pos_np = NumpyPiecewise(np.asarray(plan.position.breaks), np.asarray(plan.position.coeffs))
            span = corner_peak_ratios(pos_np, np.array([float(plan.position.start)]), np.array([float(plan.position.end)]), self.limits)
            if span[0] > 1.0 + LIMIT_RTOL:
                return False
        return True

    def holds(self, plan: FIRPlan, modes=(), residual=None) -> bool:
        """``plan``'s exact per-piece peaks within the limits and, with ``modes``, its residual
        vibration (exact profile) within ``residual``."""
        if self.limits is not None:
            pos_np = NumpyPiecewise(np.asarray(plan.position.breaks), np.asarray(plan.position.coeffs))
            span = corner_peak_ratios(pos_np, np.array([float(plan.position.start)]), np.array([float(plan.position.end)]), self.limits)
            if span[0] > 1.0 + LIMIT_RTOL:
                return False
        return not modes or bool(np.all(profile_residuals(plan.position, modes) <= np.asarray(residual) * (1 + 1e-6) + 1e-9))

    def start(self, check_period: float, modes=(), residual=None):
        """``(x_safe, its cycle time, x_start, held, others)``: the fastest feasible of the limit-holding
        ``plan_fir`` plans mapped onto ``x`` (overlaps, and each block's mean feed ``L / T_v``) and
        exact stops at the closed-form safe feeds (``_fir_limits.feed_caps``; feasible by
        construction), with ``modes`` the fastest of those whose residual vibration is within
        ``residual`` if any is (a faster start that rings more would leave the search no quiet
        plan to fall back on); and the solver's start, the paper's plan (eq 13/14 overlaps at ``F``),
        feasible or not: SLSQP starts from infeasible points, and exact stops would trap it (a
        limit broken at any overlap > 0 has no gradient at ``T_k = 0``); and the limit-holding
        ``plan_fir`` plan itself (its head and tail pieces need not fit ``x``); ``others``: the
        other feasible points, fastest first (further starts for a search that finds no quiet plan
        from ``x_safe``)."""
        M = self.M
        safe = np.full(M, self.F)
        if self.limits is not None:
            safe = np.minimum(safe, feed_caps(self.L, self.tp.tangents()[0], np.asarray(self.delays), self.limits))
        def point(overlaps, feeds):  # one feed per block, head and tail of 1/4 (the same profile)
            f = np.clip(feeds / self.F, _FEED_FLOOR, 1.0)
            return np.concatenate([np.clip(overlaps / self.Td, 0.0, 1.0), f, f, f, np.full(2 * M, 0.25)])

        best, held = [point(np.zeros(M - 1), safe)], None
        for refine in (True, False):
            p = plan_fir(self.path, self.F, np.asarray(self.delays), self.eps, refine=refine, limits=self.limits)
            held = p if held is None else held
            x = point(np.asarray(p.overlaps), self.L / np.asarray(p.pulse_times))
            if self.feasible(x, check_period):
                best.append(x)
        quiet = [x for x in best if self.holds(self.plan(x, check_period), modes, residual)] if modes else best
        x = min(quiet or best, key=self.time)
        others = sorted((y for y in best if y is not x), key=self.time)
        paper = plan_fir(self.path, self.F, np.asarray(self.delays), self.eps, refine=False)
        return x, self.time(x), point(np.asarray(paper.overlaps), np.full(M, self.F)), held, others


def _pieces(x, data, M: int):
    """Overlaps [s], and the share and feed [mm/s] of every piece of the pulse table, from ``x``."""
    T = x[: M - 1] * data["Td"]
    f3 = x[M - 1: 4 * M - 1].reshape(3, M) * data["feed"]  # head, body, tail
    h, t = x[4 * M - 1: 5 * M - 1], x[5 * M - 1:]
    share = jnp.stack([h, 1.0 - h - t, t])
    line, role, blk = data["line"], data["role"], data["blk"]
    piece_f = jnp.where(line, f3[role, blk], 1.0)
    frac = jnp.where(line, share[role, blk], 0.0)
    piece_tv = jnp.where(line, data["L"][blk] / piece_f, 1.0)
    return T, frac, piece_tv


def _profile(x, data, M: int):
    """``build_profile`` of the plan ``x``: block starts, ends, exact position, corner instants."""
    T, frac, piece_tv = _pieces(x, data, M)
    gaps = jnp.concatenate([data["Td"] - T, data["pad"]])
    return build_profile(data["start"], data["geo"], data["block"], data["gap"], frac, piece_tv, gaps, data["delays"])


@partial(jax.jit, static_argnums=2)
def _cycle(x, data, M: int):
    """Eq 11: ``sum T_v + T_d + sum (T_d - T_k)`` [s]."""
    f3 = x[M - 1: 4 * M - 1].reshape(3, M) * data["feed"]
    h, t = x[4 * M - 1: 5 * M - 1], x[5 * M - 1:]
    tv = data["L"] * (h / f3[0] + (1.0 - h - t) / f3[1] + t / f3[2])
    return jnp.sum(tv) + data["Td"] + jnp.sum(data["Td"] * (1.0 - x[: M - 1]))


_cycle_grad = jax.jit(jax.grad(_cycle.__wrapped__), static_argnums=2)


def _constraint_rows(x, data, M: int, n_samples: int):
    """All constraints as ``g(x) >= 0``, less ``data["margin"]``: vertices, path-deviation
    samples, and the limits on every piece's exact peaks (not smooth: a peak jumps when breaks
    cross; sampled limits with the jerk as a difference quotient were tried and let SLSQP diverge
    on cam30)."""
    starts, ends, position, centre = _profile(x, data, M)
    eps, Td, margin = data["eps"], data["Td"], data["margin"]
    rows = [1.0 - margin - corner_distances(position, data["vertices"], centre[: M - 1], 0.5 * Td) / eps]
    t0, t1 = position.breaks[0], position.breaks[-1]
    t = t0 + (jnp.arange(n_samples) + 0.5) / n_samples * (t1 - t0)
    rows.append(1.0 - margin - _group_max(_polyline_distance(position(t), data["P0"], data["P1"]), _GROUP) / eps)
    if data["lim"] is not None:
        rows.append(1.0 - margin - _group_max(_piece_peak_ratios(position, data["lim"]), _GROUP))
    return jnp.concatenate(rows)


_constraints = jax.jit(_constraint_rows, static_argnums=(2, 3))
_jacobian = jax.jit(jax.jacfwd(_constraint_rows), static_argnums=(2, 3))


def _group_max(v, size: int):
    """Maxima of consecutive groups of ``size`` (the length padded with the last value)."""
    n = v.shape[0]
    pad = (-n) % size
    v = jnp.concatenate([v, jnp.full(pad, -jnp.inf)]) if pad else v
    return jnp.max(v.reshape(-1, size), axis=1)


def _polyline_distance(q, P0, P1):
    """Distance of each point ``(N, d)`` to the polyline of segments ``P0 -> P1`` ``(M, d)`` [mm]."""
    seg = P1 - P0
    w = q[:, None, :] - P0[None, :, :]
    s = jnp.clip(jnp.sum(w * seg[None], axis=-1) / jnp.sum(seg * seg, axis=-1)[None, :], 0.0, 1.0)
    e = w - s[..., None] * seg[None]
    d2 = jnp.min(jnp.sum(e * e, axis=-1), axis=1)
    positive = d2 > 0
    return jnp.where(positive, jnp.sqrt(jnp.where(positive, d2, 1.0)), 0.0)


def _piece_peak_ratios(position, lim):
    """Largest ``|q^(nu)_a| / limit_a,nu`` (``nu`` = 1..3, all axes) on every piece of the exact
    profile; pieces shorter than ``piecewise.DEGENERATE_PIECE`` give 0 (as in the exact check).
    Candidates: both ends and the real roots of the next derivative inside the piece (degree <= 2,
    closed form), the root held fixed under differentiation (envelope theorem)."""
    c = position.coeffs  # (K, D + 1, A) ascending local
    h = jnp.diff(position.breaks)
    out = jnp.zeros(h.shape)
    deriv = c
    for nu in (1, 2, 3):
        deriv = _poly_deriv(deriv)
        cand = [jnp.zeros_like(h), h]
        nxt = _poly_deriv(deriv)
        for tau in _roots(nxt, h):
            cand.append(tau)
        vals = jnp.stack([jnp.abs(_horner(deriv, tc)) for tc in cand])  # (C, K, A)
        out = jnp.maximum(out, jnp.max(jnp.max(vals, axis=0) / lim[nu - 1][None, :], axis=1))
    return jnp.where(h > DEGENERATE_PIECE, out, 0.0)


def _poly_deriv(c):
    if c.shape[1] == 1:
        return jnp.zeros_like(c)
    return c[:, 1:, :] * jnp.arange(1, c.shape[1], dtype=c.dtype)[None, :, None]


def _horner(c, tau):
    """``c`` ``(K, m + 1, A)`` at local times ``tau`` ``(K,)`` or ``(K, A)``."""
    tau = tau if tau.ndim == 2 else tau[:, None]
    out = c[:, -1, :]
    for m in range(c.shape[1] - 2, -1, -1):
        out = out * tau + c[:, m, :]
    return out


def _roots(c, h):
    """Real roots in ``[0, h]`` of per-piece, per-axis polynomials of degree <= 2, as ``(K, A)``
    local times (clipped into the piece; held fixed under differentiation)."""
    c = jax.lax.stop_gradient(c)
    deg = c.shape[1] - 1
    hh = jax.lax.stop_gradient(h)[:, None]
    if deg < 1:
        return []
    if deg == 1:
        a1, a0 = c[:, 1, :], c[:, 0, :]
        r = [jnp.where(a1 != 0, -a0 / jnp.where(a1 != 0, a1, 1.0), 0.0)]
    elif deg == 2:
        a2, a1, a0 = c[:, 2, :], c[:, 1, :], c[:, 0, :]
        disc = jnp.maximum(a1 * a1 - 4 * a2 * a0, 0.0)
        sq = jnp.sqrt(disc)
        safe = jnp.where(a2 != 0, a2, 1.0)
        r = [jnp.where(a2 != 0, (-a1 + s * sq) / (2 * safe), jnp.where(a1 != 0, -a0 / jnp.where(a1 != 0, a1, 1.0), 0.0))
             for s in (1.0, -1.0)]
    else:
        raise ParameterError("optimize_fir supports up to three filters (peaks in closed form)")
    return [jnp.clip(jnp.nan_to_num(x), 0.0, hh) for x in r]
