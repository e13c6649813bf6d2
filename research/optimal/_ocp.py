"""Transcription of the minimum-time tube-following problem into a CasADi ``Opti`` NLP (IPOPT).

Model (issue 6, "Time-optimal reference"): every axis is a triple integrator driven by a jerk that
is constant on each interval (``x = [p, v, a]``, ``u = j``), so over an interval of length ``h`` the
state moves by the exact Taylor polynomial (no integration error; multiple shooting with the exact
flow map)::

    p+ = p + v h + a h^2 / 2 + u h^3 / 6
    v+ = v + a h + u h^2 / 2                                                      (T1)
    a+ = a + u h

Phases: phase ``k`` follows segment ``k`` of the window (``P_k -> P_{k+1}``, unit direction
``u_k``, length ``L_k``) and has a free duration ``T_k`` split into ``N`` equal intervals
``h_k = T_k / N``. The objective is ``sum_k T_k``. Constraints, with ``w = p - P_k``:

- tube (T2): ``0 <= u_k . w <= L_k`` (between the end caps of segment ``k``) and lateral distance
  ``|n_k . w| <= eps`` in 2-D, ``|w|^2 - (u_k . w)^2 <= eps^2`` in 3-D (both convex). The set is a
  rectangle (a cylinder) inside the ``eps``-capsule of the segment, so every point that satisfies
  it is within ``eps`` of the polyline; the corner is cut on its inner side, where the two
  rectangles overlap. Imposed at every node of the phase and at ``checks`` evenly spaced points
  inside each interval (the exact cubic evaluated there);
- phase boundaries (T3): ``|p(t_k) - P_k| <= eps`` at the node that ends phase ``k - 1``;
- limits (T4): ``|v_i|, |a_i|, |j_i|`` per axis at nodes, velocity again at the check points
  (velocity is quadratic inside an interval; acceleration is linear, so its nodes are exact; jerk
  is constant); feed ``|v|^2 <= F^2`` at nodes and check points when a feed is given;
- boundary states: the window starts from a given state ``x0`` and ends at rest on its last vertex
  (the path end point for the last window; for the others a terminal state from which the rest
  of the path is always feasible, see ``_windowing``).

With structural modes (``ProblemSpec.modes``, the vibration-aware OCP) each mode's ``(delta, delta')``
is a state too, moved by its exact flow under the interval's linear acceleration (``_vibration``,
eq V2); its residual vibration at the path end and, optionally, its deflection at the nodes and
check points are bounded.

Variables are scaled (positions by a path length scale, velocity / acceleration / jerk by their
limits, time by a typical phase duration) so IPOPT sees numbers of order one; the tube and corner
constraints are divided by ``eps`` (``eps^2``). The problem is built once per window shape with the
geometry as ``Opti`` parameters and re-solved window after window.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import casadi as ca
import numpy as np

from research.optimal._vibration import mode_flow, residual_amplitude

#: IPOPT options. ``mu_strategy = "adaptive"`` (Nocedal, Waechter, Waltz 2009): on corner90 and the
#: diamond (N = 16, 24, FIR warm start) 20-24 iterations against 36-40 with the monotone
#: (Fiacco-McCormick) barrier on the same NLPs (``benchmarks/bench_optimal.py`` prints both).
DEFAULT_IPOPT = {
    "print_level": 0,
    "mu_strategy": "adaptive",
    "sb": "yes",
    "max_iter": 3000,
    "tol": 1e-8,
    "acceptable_tol": 1e-6,
}
ACCEPTED = ("Solve_Succeeded", "Solved_To_Acceptable_Level")


@dataclass(frozen=True)
class ProblemSpec:
    """Shape and constants of one window problem.

    Attributes:
        n_phases: segments in the window.
        intervals: equal intervals per phase ``N``.
        dim: number of axes ``d`` (1-3).
        velocity, acceleration, jerk: ``(d,)`` per-axis limits [mm/s, mm/s^2, mm/s^3] (finite).
        feed: bound on ``|v|`` [mm/s], or ``None``.
        tolerance: tube radius ``eps`` [mm], > 0.
        checks: check points inside each interval (at fractions ``i / (checks + 1)``).
        length_scale, time_scale: scales of position [mm] and phase duration [s].
        modes: structural modes in the dynamics (``_vibration``, eq V1-V2); ``()``: none.
        residual: bounds ``r_k`` [mm], one per mode, on its residual vibration at the end (eq V3;
            ``0``: the mode ends at rest), or ``None``; imposed only when ``terminal``.
        deflection: bound ``D`` [mm] on ``|delta|`` of each mode at nodes and check points, or ``None``.
        terminal: the window ends at the end of the path (where the residual bound applies).
    """

    n_phases: int
    intervals: int
    dim: int
    velocity: tuple[float, ...]
    acceleration: tuple[float, ...]
    jerk: tuple[float, ...]
    feed: float | None
    tolerance: float
    checks: int
    length_scale: float
    time_scale: float
    modes: tuple = ()
    residual: tuple | None = None
    deflection: float | None = None
    terminal: bool = True


@dataclass(frozen=True)
class Geometry:
    """Segments of one window: ``start``/``end`` ``(n, d)`` [mm], ``direction`` ``(n, d)`` unit,
    ``length`` ``(n,)`` [mm], ``min_duration`` ``(n,)`` lower bound on each ``T_k`` [s]."""

    start: np.ndarray
    end: np.ndarray
    direction: np.ndarray
    length: np.ndarray
    min_duration: np.ndarray


@dataclass(frozen=True)
class PhaseGrid:
    """A solution (or a guess) on the phase grid.

    Attributes:
        durations: ``(n,)`` phase durations ``T_k`` [s].
        states: ``(n N + 1, 3, d)`` node states ``[p, v, a]`` [mm, mm/s, mm/s^2].
        jerks: ``(n N, d)`` jerk on each interval [mm/s^3].
        modes: ``(n N + 1, 2, m)`` mode states ``(delta, delta')`` [mm, mm/s] at the nodes, or
            ``None`` without modes.
    """

    durations: np.ndarray
    states: np.ndarray
    jerks: np.ndarray
    modes: np.ndarray | None = None


@dataclass(frozen=True)
class SolveStats:
    """IPOPT outcome of one window: ``status`` (IPOPT return status), ``iterations``,
    ``solve_time`` [s] (wall clock of ``Opti.solve``), ``success``."""

    status: str
    iterations: int
    solve_time: float
    success: bool


class SolveFailure(Exception):
    """Internal: IPOPT did not converge; ``diagnostics`` names the worst violated constraint."""

    def __init__(self, stats: SolveStats, constraint: str, phase: int | None, violation: float):
        self.stats, self.constraint, self.phase, self.violation = stats, constraint, phase, violation
        super().__init__(stats.status)


def flow(states: np.ndarray, jerk: np.ndarray, h) -> np.ndarray:
    """Exact state after time ``h`` [s] under constant jerk (eq T1 of the module docstring).

    Args:
        states: ``(..., 3, d)`` ``[p, v, a]``.
        jerk: ``(..., d)`` [mm/s^3].
        h: ``(...)`` or scalar [s].

    Returns:
        ``(..., 3, d)`` states at ``t + h``.
    """
    h = np.asarray(h, dtype=np.float64)[..., None]
    p, v, a = states[..., 0, :], states[..., 1, :], states[..., 2, :]
    return np.stack([p + v * h + a * h**2 / 2 + jerk * h**3 / 6, v + a * h + jerk * h**2 / 2, a + jerk * h], axis=-2)


class PhaseProblem:
    """The NLP of one window shape, built once and solved for any geometry of that shape.

    Args:
        spec: the window shape and constants.
        ipopt_options: IPOPT options (merged over ``DEFAULT_IPOPT``).
    """

    def __init__(self, spec: ProblemSpec, ipopt_options: dict | None = None):
        self.spec = spec
        self._records: list[tuple[str, ca.MX, np.ndarray, np.ndarray, np.ndarray | None]] = []
        self.ipopt_options = {**DEFAULT_IPOPT, **(ipopt_options or {})}
        self._build(self.ipopt_options)

    # -- transcription -----------------------------------------------------------------------
    def _constrain(self, name, expr, lb, ub, phase=None):
        """Add ``lb <= expr <= ub`` (equality when ``lb == ub``) and remember it for diagnostics."""
        shape = expr.shape
        lb = np.broadcast_to(np.asarray(lb, dtype=np.float64), shape)
        ub = np.broadcast_to(np.asarray(ub, dtype=np.float64), shape)
        if np.array_equal(lb, ub):
            self.opti.subject_to(expr == ca.DM(lb))
        else:
            self.opti.subject_to(self.opti.bounded(ca.DM(lb), expr, ca.DM(ub)))
        self._records.append((name, expr, lb, ub, None if phase is None else np.asarray(phase)))

    def _tube(self, name, points, phase):
        """Eq T2 on the points ``(d, m)`` of phases ``phase`` ``(m,)``."""
        s, d = self.spec, self.spec.dim
        cols = [int(k) for k in phase]
        w = points - self.start[:, cols]
        u = self.direction[:, cols]
        along = ca.sum1(u * w)
        self._constrain(f"tube end caps ({name})", along / self.length[:, cols], 0.0, 1.0, phase)
        if d == 2:
            lateral = (u[0, :] * w[1, :] - u[1, :] * w[0, :]) / s.tolerance
            self._constrain(f"tube ({name})", lateral, -1.0, 1.0, phase)
        elif d == 3:
            lateral2 = (ca.sum1(w * w) - along**2) / s.tolerance**2
            self._constrain(f"tube ({name})", lateral2, -np.inf, 1.0, phase)

    def _build(self, ipopt_options: dict) -> None:
        s = self.spec
        d, n, N = s.dim, s.n_phases, s.intervals
        K = n * N
        vmax, amax, jmax = (np.asarray(x, dtype=np.float64) for x in (s.velocity, s.acceleration, s.jerk))
        Sp, Sv, Sa, Sj, St = s.length_scale, float(vmax.max()), float(amax.max()), float(jmax.max()), s.time_scale
        self.scales = np.array([Sp, Sv, Sa])
        opti = self.opti = ca.Opti()
        Z = self.Z = opti.variable(3 * d, K + 1)  # scaled node states
        W = self.W = opti.variable(d, K)  # scaled jerk
        tau = self.tau = opti.variable(1, n)  # scaled phase durations
        self.start, self.end = opti.parameter(d, n), opti.parameter(d, n)
        self.direction, self.length = opti.parameter(d, n), opti.parameter(1, n)
        self.origin, self.z0 = opti.parameter(d, 1), opti.parameter(3 * d, 1)
        self.min_tau = opti.parameter(1, n)

        p = ca.repmat(self.origin, 1, K + 1) + Sp * Z[:d, :]
        v, a, u = Sv * Z[d : 2 * d, :], Sa * Z[2 * d :, :], Sj * W
        T = St * tau
        h = ca.reshape(ca.repmat(T, N, 1), 1, K) / N  # interval lengths, phase by phase
        H = ca.repmat(h, d, 1)
        p0, v0, a0 = p[:, :-1], v[:, :-1], a[:, :-1]
        interval_phase = np.repeat(np.arange(n), N)

        # exact flow of the triple integrator (T1): multiple shooting with zero integration error
        self._constrain("dynamics p", (p[:, 1:] - (p0 + v0 * H + a0 * H**2 / 2 + u * H**3 / 6)) / Sp, 0.0, 0.0, interval_phase)
        self._constrain("dynamics v", (v[:, 1:] - (v0 + a0 * H + u * H**2 / 2)) / Sv, 0.0, 0.0, interval_phase)
        self._constrain("dynamics a", (a[:, 1:] - (a0 + u * H)) / Sa, 0.0, 0.0, interval_phase)

        # limits at the nodes (T4)
        node_phase = np.minimum(np.arange(K + 1) // N, n - 1)
        self._constrain("velocity limit", Z[d : 2 * d, :], np.tile(-vmax[:, None] / Sv, K + 1), np.tile(vmax[:, None] / Sv, K + 1), node_phase)
        self._constrain("acceleration limit", Z[2 * d :, :], np.tile(-amax[:, None] / Sa, K + 1), np.tile(amax[:, None] / Sa, K + 1), node_phase)
        self._constrain("jerk limit", W, np.tile(-jmax[:, None] / Sj, K), np.tile(jmax[:, None] / Sj, K), interval_phase)
        if s.feed is not None:
            self._constrain("feed limit", ca.sum1(v**2) / s.feed**2, -np.inf, 1.0, node_phase)

        # tube at the nodes: both ends of every phase belong to it (T2)
        cols = (np.arange(n)[:, None] * N + np.arange(N + 1)[None, :]).ravel()
        self._tube("nodes", p[:, [int(c) for c in cols]], np.repeat(np.arange(n), N + 1))
        # check points inside each interval: the exact cubic / quadratic evaluated there
        for i in range(1, s.checks + 1):
            th = H * (i / (s.checks + 1))
            pc = p0 + v0 * th + a0 * th**2 / 2 + u * th**3 / 6
            vc = v0 + a0 * th + u * th**2 / 2
            self._tube(f"check {i}/{s.checks + 1}", pc, interval_phase)
            self._constrain(f"velocity limit (check {i})", vc / Sv, np.tile(-vmax[:, None] / Sv, K), np.tile(vmax[:, None] / Sv, K), interval_phase)
            if s.feed is not None:
                self._constrain(f"feed limit (check {i})", ca.sum1(vc**2) / s.feed**2, -np.inf, 1.0, interval_phase)

        # phase boundaries within eps of their corner vertex (T3)
        if n > 1:
            bnd = [int(k * N) for k in range(1, n)]
            dist2 = ca.sum1((p[:, bnd] - self.start[:, 1:]) ** 2) / s.tolerance**2
            self._constrain("corner vertex", dist2, -np.inf, 1.0, np.arange(1, n))

        # boundary states: given start, rest at the end
        self._constrain("initial state", Z[:, 0] - self.z0, 0.0, 0.0, np.zeros(3 * d, dtype=int))
        self._constrain("end at rest", Z[d:, K], 0.0, 0.0, np.full(2 * d, n - 1))
        self._constrain("end point", (p[:, K] - self.end[:, n - 1]) / Sp, 0.0, 0.0, np.full(d, n - 1))
        self._constrain("phase duration", tau - self.min_tau, 0.0, np.inf, np.arange(n))

        if s.modes:
            self._modes(a, u, h, interval_phase)
        opti.minimize(ca.sum2(tau))
        opti.solver("ipopt", {"expand": True, "print_time": False}, ipopt_options)

    def _modes(self, a, u, h, interval_phase) -> None:
        """Mode states, their exact flow (eq V2), in-motion deflection and residual (eq V3) bounds."""
        s, opti = self.spec, self.opti
        K, m = s.n_phases * s.intervals, len(s.modes)
        amax = np.asarray(s.acceleration, dtype=np.float64)
        wn = np.array([md.wn for md in s.modes])
        a_mode = amax[[md.axis for md in s.modes]]
        # scales: the quasi-static deflection a_max / wn^2 and its rate a_max / wn
        self.mode_scales = np.stack([a_mode / wn**2, a_mode / wn])
        Y = self.Y = opti.variable(2 * m, K + 1)
        self.y0 = opti.parameter(2 * m, 1)
        self._constrain("initial mode state", Y[:, 0] - self.y0, 0.0, 0.0, np.zeros(2 * m, dtype=int))
        node_phase = np.minimum(np.arange(K + 1) // s.intervals, s.n_phases - 1)
        for k, md in enumerate(s.modes):
            Sd, Sr = self.mode_scales[:, k]
            dl, rt = Sd * Y[2 * k, :], Sr * Y[2 * k + 1, :]
            a0, j = a[md.axis, :-1], u[md.axis, :]
            d1, r1 = mode_flow(dl[:-1], rt[:-1], a0, j, h, md.wn, md.damping, ca)
            self._constrain(f"mode {k} dynamics delta", (dl[1:] - d1) / Sd, 0.0, 0.0, interval_phase)
            self._constrain(f"mode {k} dynamics rate", (rt[1:] - r1) / Sr, 0.0, 0.0, interval_phase)
            if s.deflection is not None:
                D = s.deflection
                self._constrain(f"mode {k} deflection", dl / D, -1.0, 1.0, node_phase)
                for i in range(1, s.checks + 1):
                    dc, _ = mode_flow(dl[:-1], rt[:-1], a0, j, h * (i / (s.checks + 1)), md.wn, md.damping, ca)
                    self._constrain(f"mode {k} deflection (check {i})", dc / D, -1.0, 1.0, interval_phase)
            if s.residual is not None and s.terminal:
                if s.residual[k] == 0:
                    self._constrain(f"mode {k} residual vibration", Y[2 * k : 2 * k + 2, K], 0.0, 0.0, np.full(2, s.n_phases - 1))
                else:
                    amp2 = residual_amplitude(dl[K], rt[K], md.wn, md.damping, ca) ** 2 / s.residual[k] ** 2
                    self._constrain(f"mode {k} residual vibration", amp2, -np.inf, 1.0, np.array([s.n_phases - 1]))

    # -- solving -----------------------------------------------------------------------------
    def solve(self, geometry: Geometry, initial_state: np.ndarray, guess: PhaseGrid,
              initial_modes: np.ndarray | None = None) -> tuple[PhaseGrid, SolveStats]:
        """Solve for one window.

        Args:
            geometry: the window's segments.
            initial_state: ``(3, d)`` state ``[p, v, a]`` at the start of the window.
            guess: initial guess on this window's grid (``guess.modes`` required with modes).
            initial_modes: ``(2, m)`` mode states at the start (default: at rest).

        Returns:
            ``(solution, stats)``.

        Raises:
            SolveFailure: IPOPT did not reach an acceptable point; carries the worst violation.
        """
        s, opti = self.spec, self.opti
        origin = geometry.start[0]
        scale = self.scales[:, None]
        opti.set_value(self.start, geometry.start.T)
        opti.set_value(self.end, geometry.end.T)
        opti.set_value(self.direction, geometry.direction.T)
        opti.set_value(self.length, geometry.length[None, :])
        opti.set_value(self.origin, origin)
        opti.set_value(self.min_tau, geometry.min_duration[None, :] / s.time_scale)
        opti.set_value(self.z0, self._scaled(initial_state[None], origin)[:, 0])
        opti.set_initial(self.Z, self._scaled(guess.states, origin))
        opti.set_initial(self.W, guess.jerks.T / float(np.max(s.jerk)))
        opti.set_initial(self.tau, guess.durations[None, :] / s.time_scale)
        if s.modes:
            y0 = np.zeros((2, len(s.modes))) if initial_modes is None else np.asarray(initial_modes, dtype=np.float64)
            opti.set_value(self.y0, (y0 / self.mode_scales).T.ravel())
            opti.set_initial(self.Y, (guess.modes / self.mode_scales).transpose(2, 1, 0).reshape(-1, guess.modes.shape[0]))
        t0 = time.perf_counter()
        try:
            sol = opti.solve()
            raw = sol.stats()
            value = sol.value
        except RuntimeError:
            raw = opti.stats()
            value = opti.debug.value
        iterations = int(raw.get("iter_count", 0))
        if not 0 <= iterations <= int(self.ipopt_options["max_iter"]):
            iterations = 0  # IPOPT stopped before its first iteration (e.g. too few degrees of freedom)
        stats = SolveStats(
            str(raw.get("return_status", "unknown")), iterations,
            time.perf_counter() - t0, str(raw.get("return_status")) in ACCEPTED,
        )
        if not stats.success:
            raise SolveFailure(stats, *self._worst_violation(opti.debug.value))
        Z = np.asarray(value(self.Z)).reshape(3 * s.dim, -1)
        states = (Z.T.reshape(-1, 3, s.dim) * scale) + np.stack([origin, 0 * origin, 0 * origin])
        jerks = np.asarray(value(self.W)).reshape(s.dim, -1).T * float(np.max(s.jerk))
        durations = np.atleast_1d(np.asarray(value(self.tau)).ravel()) * s.time_scale
        modes = None
        if s.modes:
            Y = np.asarray(value(self.Y)).reshape(2 * len(s.modes), -1)
            modes = Y.reshape(len(s.modes), 2, -1).transpose(2, 1, 0) * self.mode_scales
        return PhaseGrid(durations, states, jerks, modes), stats

    def _scaled(self, states: np.ndarray, origin: np.ndarray) -> np.ndarray:
        """``(m, 3, d)`` physical states -> ``(3 d, m)`` scaled decision values."""
        shifted = states - np.stack([origin, 0 * origin, 0 * origin])
        z = shifted / self.scales[:, None]
        return z.reshape(z.shape[0], -1).T

    def _worst_violation(self, value) -> tuple[str, int | None, float]:
        """Name, phase and size (in the constraint's scaled units) of the worst violated constraint
        at IPOPT's last iterate."""
        worst = ("none", None, 0.0)
        for name, expr, lb, ub, phase in self._records:
            g = np.asarray(value(expr), dtype=np.float64).reshape(expr.shape)
            viol = np.maximum(lb - g, g - ub)
            viol = np.where(np.isfinite(viol), viol, 0.0)
            i = np.unravel_index(int(np.argmax(viol)), viol.shape)
            if viol[i] > worst[2]:
                col = i[-1] if viol.ndim > 1 else i[0]
                ph = None if phase is None else int(phase[min(col, phase.size - 1)] if phase.ndim == 1 else phase[i])
                worst = (name, ph, float(viol[i]))
        return worst
