"""CEC mirror compensation (Prévost, Lavernhe, Lartigue, HSM 2012, §3, eq 3-4).

Each setpoint sample is moved against the total execution error measured at the same time:
``R'_i = R_i - e_T(t_i)`` (eq 4), where ``e_T(t_i) = P_i - foot(P_i)`` runs from the closest point
of the CAM path to the simulated actual position ``P_i``. The setpoint keeps its N samples and hence
its execution time ``N Ts`` (§3).

Unknown: the correction ``D`` ``(N, A)`` added to the interpolator's setpoint. The corrected setpoint
is ``q + D`` with ``v + D'``, ``a + D''``, ``j + D'''``, where the derivatives of the (small, smooth)
correction are central finite differences at ``Ts``: what a CNC would feed forward from corrected
position samples. The exact derivatives of the interpolator's profile are kept.

Prévost's method is one mirror pass: the corrected setpoint is computed once from the
uncompensated simulation and then checked ("Once the new setpoint is calculated using the CEC
method, the new simulated tool positions are evaluated", §3; "The CEC algorithm is directly
applied", §4.2): :func:`mirror_single_pass`, the result to compare with the paper.

Extensions beyond the paper (it iterates nothing), both with optimistix and the JAX drive model:

- iterated mirror (``method="fixed_point"``, ``optimistix.FixedPointIteration``):
  ``D <- D - e_T(D)`` repeated until ``max |e_T| <= tolerance``; one simulation per iteration
  (:func:`mirror_passes` repeats it a fixed number of times);
- model inversion (``method="newton"``, ``optimistix.Newton``) on
  ``r(D) = P(D) - stop_gradient(foot(P(D)))``: the JAX Jacobian of ``r`` is the drive's
  input-output map ``dP/dD``, so each Newton step is ``D <- D - (dP/dD)^-1 e_T``. The roots of
  ``r`` are the fixed points of the mirror rule.

Inside the loop the CAM path is a dense polyline (vertices ``spacing`` apart) and each sample is
projected onto a fixed window of pieces around the foot of its uncompensated actual position, which
keeps the loop in pure JAX; reported errors always come from the exact projection of
:func:`research.contour.contour_error`, and the two are compared.
"""

from __future__ import annotations

import dataclasses
import functools
import time
from dataclasses import dataclass
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import lineax as lx
import numpy as np
import optimistix as optx
from jax import Array

from research.contour._exact import ContourError, contour_error
from research.contour._geometry import as_reference, dense_polyline
from research.contour._limits import LimitCheck, check_setpoint
from research.drives import DriveResponse, simulate
from research.errors import ConvergenceError, InfeasibleProblem, ParameterError
from research.limits import AxisLimits
from research.paths.polyline import Polyline
from research.trajectory import Trajectory

METHODS = ("fixed_point", "newton")
#: what each ``method`` of :func:`mirror_compensation` is; neither is in Prévost 2012
EXTENSIONS = {
    "fixed_point": "iterated mirror: Prévost's eq 4 repeated to a tolerance (extension)",
    "newton": "model inversion: Newton root find with the drive Jacobian (extension)",
}
#: ``CompensationResult.method`` of the paper's method, :func:`mirror_single_pass`
PAPER_METHOD = "single_pass"
#: largest accepted difference [mm] between the in-loop and the exact |e_T| (0.1 um)
LOOP_DISCREPANCY = 1e-4


class CECProblem(eqx.Module):
    """A CEC compensation problem: setpoint, drive model and the CAM target in loop form.

    Build with :func:`cec_problem`.

    Attributes:
        setpoint: the interpolator's setpoint (absolute coordinates) [s, mm, mm/s, ...].
        drive: one drive model for all axes or a tuple with one per axis.
        target: ``(M + 1, d)`` dense polyline vertices of the CAM path [mm].
        window_start: ``(N,)`` first target piece of each sample's projection window.
        window: number of target pieces in every window.
        friction: friction mode passed to :func:`research.drives.simulate`.
        cam_path: the CAM path as a Polyline or BSplinePath (for exact errors), not traced.
    """

    setpoint: Trajectory
    drive: Any
    target: Array
    window_start: Array
    window: int = eqx.field(static=True)
    friction: str = eqx.field(static=True)
    cam_path: Any = eqx.field(static=True)

    @property
    def n_samples(self) -> int:
        return self.setpoint.n_samples


def cec_problem(cam_path, setpoint: Trajectory, drive, *, friction: str = "exact", spacing: float = 0.02,
                window_margin: float | None = None) -> CECProblem:
    """Set up the mirror loop for ``setpoint`` run through ``drive`` against ``cam_path``.

    Args:
        cam_path: the CAM path (Polyline, BSplinePath, Trajectory curve or (M, d) points) [mm].
        setpoint: interpolator output on the NC sample period [s, mm].
        drive: drive model(s) for :func:`research.drives.simulate`.
        friction: ``"exact"`` or ``"smooth"`` Coulomb sign.
        spacing: largest piece of the in-loop target polyline [mm]; its chord error on a curve of
            curvature ``kappa`` is ``spacing^2 kappa / 8`` (2.5e-6 mm at 0.02 mm and 20 mm radius).
        window_margin: half-length [mm] of the arc-length window each sample is projected on; default
            ``max(0.5, 10 max e_T)`` of the uncompensated motion.
    Returns:
        :class:`CECProblem`.
    Raises:
        ParameterError: not a Trajectory, a dimension mismatch, or a bad spacing/margin.
    """
    if not isinstance(setpoint, Trajectory):
        raise ParameterError(f"setpoint must be a Trajectory, got {type(setpoint).__name__}")
    pts, arc = dense_polyline(cam_path, spacing)
    if pts.shape[1] != setpoint.n_axes:
        raise ParameterError(f"the CAM path has {pts.shape[1]} coordinates but the setpoint has {setpoint.n_axes} axes")
    actual = simulate_setpoint(setpoint, drive, friction)
    P0 = np.asarray(actual.position)
    ref = Polyline.from_points(pts, merge_duplicates=True, tol=1e-9)
    pts = ref.points
    arc = np.concatenate([[0.0], np.cumsum(ref.lengths)])
    d0, seg, u = ref.project(P0)
    if window_margin is None:
        window_margin = max(0.5, 10.0 * float(d0.max()))
    if not (np.isfinite(window_margin) and window_margin > 0):
        raise ParameterError(f"window_margin must be a finite length > 0 mm, got {window_margin!r}")
    s = arc[seg] + u * ref.lengths[seg]
    lo = np.clip(np.searchsorted(arc, s - window_margin, side="right") - 1, 0, ref.n_segments - 1)
    hi = np.clip(np.searchsorted(arc, s + window_margin, side="left"), 1, ref.n_segments)
    window = int(np.max(hi - lo))
    lo = np.clip(lo, 0, max(0, ref.n_segments - window))
    return CECProblem(setpoint, drive, jnp.asarray(pts), jnp.asarray(lo), window, friction, as_reference(cam_path))


# -- the model in the loop ------------------------------------------------------------------------
def _derivative(x: Array, Ts: float) -> Array:
    return jnp.gradient(x, Ts, axis=0)


@functools.partial(jax.jit, static_argnames="Ts")
def _corrected(q, v, a, j, D, Ts: float):
    """``(q + D, v + D', a + D'', j + D''')`` in one compiled call: run eagerly, each of its seven array
    operations was a compilation of its own, repeated in every process (each is below the compile time
    JAX's persistent cache keeps)."""
    D = jnp.asarray(D, dtype=jnp.float64)
    d1 = _derivative(D, Ts)
    d2 = _derivative(d1, Ts)
    d3 = _derivative(d2, Ts)
    return q + D, v + d1, a + d2, j + d3


def corrected_setpoint(problem: CECProblem, correction) -> Trajectory:
    """The setpoint ``q + D`` with ``v + D'``, ``a + D''``, ``j + D'''`` (central differences at
    ``Ts``); absolute coordinates [mm]."""
    sp = problem.setpoint
    Ts = sp.sample_period
    q, v, a, j = _corrected(sp.q, sp.v, sp.a, sp.j, correction, Ts=float(Ts))
    return Trajectory(sp.t, q, v, a, j, sp.duration, None, sp.axes, Ts)


def simulate_setpoint(setpoint: Trajectory, drive, friction: str = "exact") -> DriveResponse:
    """:func:`research.drives.simulate` of ``setpoint`` (one drive, or one per axis), starting from
    the loop's rest state at the first sample. Positions in absolute coordinates [mm, rad]."""
    return simulate(drive, setpoint, friction=friction)


def simulate_correction(problem: CECProblem, correction) -> DriveResponse:
    """Drive response to the corrected setpoint (absolute coordinates)."""
    return simulate_setpoint(corrected_setpoint(problem, correction), problem.drive, problem.friction)


def cubic_hold(setpoint: Trajectory, factor: int) -> Trajectory:
    """The setpoint's cubic hold (the reference the drive sees between samples, see
    :mod:`research.drives`) sampled ``factor`` times finer: ``q_k + v_k tau + a_k tau^2/2 + j_k tau^3/6``
    and its derivatives. Simulating it at ``Ts / factor`` gives the exact actual motion between the
    NC samples, for contour errors that do not depend on where the samples fall."""
    if not isinstance(factor, (int, np.integer)) or factor < 1:
        raise ParameterError(f"factor must be an integer >= 1, got {factor!r}")
    Ts = setpoint.sample_period
    tau = (np.arange(factor) * Ts / factor)[None, :, None]
    q, v, a, j = (np.asarray(x)[:-1, None, :] for x in (setpoint.q, setpoint.v, setpoint.a, setpoint.j))
    fine = [q + v * tau + a * tau**2 / 2 + j * tau**3 / 6, v + a * tau + j * tau**2 / 2, a + j * tau, j + 0 * tau]
    last = [np.asarray(x)[-1:] for x in (setpoint.q, setpoint.v, setpoint.a, setpoint.j)]
    A = setpoint.n_axes
    q, v, a, j = (np.concatenate([f.reshape(-1, A), l]) for f, l in zip(fine, last))
    t = np.asarray(setpoint.t)[0] + np.arange(q.shape[0]) * Ts / factor
    return Trajectory(t, q, v, a, j, setpoint.duration, None, setpoint.axes, Ts / factor)


def intersample_response(problem: CECProblem, correction, factor: int = 6) -> DriveResponse:
    """Actual motion for the corrected setpoint on a grid ``factor`` times finer than ``Ts``
    (exact for the cubic hold, :func:`cubic_hold`)."""
    sp = cubic_hold(corrected_setpoint(problem, correction), factor)
    return simulate_setpoint(sp, problem.drive, problem.friction)


def _foot(problem: CECProblem, P: Array) -> Array:
    """Closest point of the in-loop target polyline, searched in each sample's window."""
    return _window_foot(problem.target, problem.window_start, P, window=problem.window)


@functools.partial(jax.jit, static_argnames="window")
def _window_foot(target: Array, window_start: Array, P: Array, window: int) -> Array:
    """:func:`_foot` on arrays in one compiled call (run eagerly, its ~25 array operations compiled one by one)."""
    M = target.shape[0] - 1
    idx = jnp.clip(window_start[:, None] + jnp.arange(window)[None, :], 0, M - 1)
    a = target[idx]
    ab = target[idx + 1] - a
    u = jnp.clip(jnp.sum((P[:, None, :] - a) * ab, -1) / jnp.sum(ab * ab, -1), 0.0, 1.0)
    cand = a + u[..., None] * ab
    best = jnp.argmin(jnp.sum((P[:, None, :] - cand) ** 2, -1), axis=1)
    return jnp.take_along_axis(cand, best[:, None, None], axis=1)[:, 0]


def execution_error_vector(problem: CECProblem, correction) -> Array:
    """``e_T(t_i) = P_i - foot(P_i)`` ``(N, d)`` [mm] for the corrected setpoint (in-loop projection)."""
    P = simulate_correction(problem, correction).position
    return P - _foot(problem, P)


def q_filter(correction: Array, window: int) -> Array:
    """Zero-phase moving average of ``window`` samples along time (edges padded with their value);
    ``window = 1`` returns the input."""
    if window == 1:
        return correction
    k = jnp.ones(window) / window
    x = jnp.pad(correction, ((window // 2, window - 1 - window // 2), (0, 0)), mode="edge")
    return jax.vmap(lambda col: jnp.convolve(col, k, mode="valid"), in_axes=1, out_axes=1)(x)


def mirror_step(problem: CECProblem, correction, smoothing: int = 1) -> Array:
    """One application of Prévost's rule, eq 4: ``D <- D - e_T(D)``.

    With ``smoothing = m > 1`` the new correction is passed through a zero-phase ``m``-sample moving
    average (the Q-filter of iterative learning control; not in Prévost): the plain rule amplifies
    the components where the drive lags by more than 90 deg (``|1 - G| > 1``), which a sharp target
    excites, and the filter also bounds the jerk the correction adds."""
    D = jnp.asarray(correction, dtype=jnp.float64)
    return q_filter(D - execution_error_vector(problem, D), smoothing)


def _newton_residual(problem: CECProblem, correction) -> Array:
    P = simulate_correction(problem, correction).position
    return P - jax.lax.stop_gradient(_foot(problem, P))


def _sample_norm(x) -> Array:
    """Largest Euclidean norm over samples of an ``(N, d)`` array (the max contour error)."""
    return jnp.max(jnp.sqrt(jnp.sum(x * x, axis=-1)))


# -- results ----------------------------------------------------------------------------------------
@dataclass(frozen=True)
class CompensationResult:
    """Outcome of a CEC compensation.

    Attributes:
        method: ``"single_pass"`` (Prévost's method), or the extensions ``"fixed_point"`` (iterated
            mirror), ``"newton"`` (model inversion), ``"passes"`` (a fixed number of mirror passes).
        correction: ``(N, A)`` setpoint correction ``D`` [mm].
        setpoint: the compensated setpoint (derivatives as in the module docstring).
        response: its simulated drive response.
        before, after: exact total error ``e_T`` of the uncompensated and compensated motion.
        steps: solver iterations.
        simulations: primal drive simulations, including the uncompensated one and the final check.
        jacobians: Jacobian evaluations (Newton: each is ``N A`` tangent simulations, batched).
        tangent_simulations: tangent (JVP) simulations in those Jacobians.
        converged: ``after.max <= tolerance``.
        tolerance: requested max ``|e_T|`` [mm].
        loop_discrepancy: max difference [mm] between the in-loop and the exact ``|e_T|``.
        history: max exact ``|e_T|`` [mm] after each pass (``"passes"`` only; else empty).
        wall_time: seconds spent in the solve (compilation included).
        limits: the limit check of the compensated setpoint, when limits were given.
    """

    method: str
    correction: np.ndarray
    setpoint: Trajectory
    response: DriveResponse
    before: ContourError
    after: ContourError
    steps: int
    simulations: int
    jacobians: int
    tangent_simulations: int
    converged: bool
    tolerance: float
    loop_discrepancy: float
    history: tuple[float, ...]
    wall_time: float
    limits: LimitCheck | None


def _finish(problem, method, D, steps, sims, jacs, tolerance, history, t0, limits, control_limit,
            on_violation, throw, before):
    D = np.asarray(D)
    sp = corrected_setpoint(problem, D)
    resp = simulate_correction(problem, D)
    after = contour_error(problem.cam_path, np.asarray(resp.position))
    loop = np.linalg.norm(np.asarray(resp.position) - np.asarray(_foot(problem, resp.position)), axis=1)
    discrepancy = float(np.max(np.abs(loop - after.distance)))
    check = None
    if limits is not None:
        check = check_setpoint(sp, resp, limits, control_limit=control_limit)
    result = CompensationResult(
        method, D, sp, resp, before, after, int(steps), int(sims) + 1, int(jacs),
        int(jacs) * problem.n_samples * problem.setpoint.n_axes, bool(after.max <= tolerance), float(tolerance),
        discrepancy, tuple(history), time.perf_counter() - t0, check,
    )
    if throw and not result.converged:
        raise ConvergenceError(
            f"CEC ({method}) did not converge: max |e_T| = {after.max * 1e3:.4g} um after {steps} steps "
            f"(tolerance {tolerance * 1e3:.4g} um, {result.simulations} simulations)",
            residual=after.max, steps=int(steps), result=result,
        )
    if result.converged and discrepancy > LOOP_DISCREPANCY:
        raise ConvergenceError(
            f"CEC ({method}): the in-loop projection differs from the exact contour error by {discrepancy * 1e3:.3g} um "
            f"(more than {LOOP_DISCREPANCY * 1e3:.3g} um), so convergence cannot be trusted; widen window_margin or "
            "refine spacing",
            residual=after.max, steps=int(steps), result=result,
        )
    if check is not None and not check.ok and on_violation == "refuse":
        raise InfeasibleProblem(f"CEC ({method}): the compensated setpoint violates the limits: {check.summary()}")
    return result


def _check_common(tolerance, max_steps, on_violation, limits):
    if not (np.isfinite(tolerance) and tolerance > 0):
        raise ParameterError(f"tolerance must be a finite length > 0 mm, got {tolerance!r}")
    if not isinstance(max_steps, (int, np.integer)) or max_steps < 1:
        raise ParameterError(f"max_steps must be an integer >= 1, got {max_steps!r}")
    if on_violation not in ("flag", "refuse"):
        raise ParameterError(f"on_violation must be 'flag' or 'refuse', got {on_violation!r}")
    if limits is not None and not isinstance(limits, AxisLimits):
        raise ParameterError(f"limits must be an AxisLimits, got {type(limits).__name__}")


def mirror_compensation(problem: CECProblem, *, method: str = "newton", tolerance: float = 2e-3,
                        max_steps: int = 100, limits: AxisLimits | None = None, control_limit=None,
                        on_violation: str = "flag", throw: bool = True) -> CompensationResult:
    """Compensate the setpoint until the simulated actual motion is within ``tolerance`` of the CAM
    path. An extension of Prévost's single pass (:func:`mirror_single_pass`): see :data:`EXTENSIONS`.

    Args:
        problem: from :func:`cec_problem`.
        method: ``"fixed_point"`` (optimistix ``FixedPointIteration`` on eq 4) or ``"newton"``
            (optimistix ``Newton`` root find with the JAX Jacobian, i.e. model inversion).
        tolerance: target max ``|e_T|`` [mm] (Prévost Application 1 reaches 2 um = 2e-3 mm in one pass).
        max_steps: iteration cap.
        limits: axis v/a/j limits the compensated setpoint must respect (Prévost §3: "must be checked").
        control_limit: per-axis bound on the control signal (drive models with a control output) [V].
        on_violation: ``"flag"`` (report in ``result.limits``) or ``"refuse"`` (raise).
        throw: raise :class:`ConvergenceError` when ``tolerance`` is not reached.
    Returns:
        :class:`CompensationResult`.
    Raises:
        ConvergenceError: not converged (with ``throw``), carrying the residual [mm], the step count and the
            result; also when the in-loop projection disagrees with the exact contour error.
        InfeasibleProblem: limits violated with ``on_violation="refuse"``.
        ParameterError: bad arguments.
    """
    if method not in METHODS:
        raise ParameterError(f"method must be one of {METHODS}, got {method!r}")
    _check_common(tolerance, max_steps, on_violation, limits)
    t0 = time.perf_counter()
    before = contour_error(problem.cam_path, np.asarray(simulate_correction(problem, jnp.zeros_like(problem.setpoint.q)).position))
    y0 = jnp.zeros_like(problem.setpoint.q)
    if method == "fixed_point":
        solver = optx.FixedPointIteration(rtol=0.0, atol=tolerance, norm=_sample_norm)
        sol = optx.fixed_point(lambda D, p: mirror_step(p, D), solver, y0, args=problem, max_steps=max_steps,
                               throw=False)
        steps = int(sol.stats["num_steps"])
        sims, jacs = 1 + steps, 0
    else:
        solver = optx.Newton(rtol=0.0, atol=tolerance, norm=_sample_norm, linear_solver=lx.SVD())
        sol = optx.root_find(lambda D, p: _newton_residual(p, D), solver, y0, args=problem, max_steps=max_steps,
                             throw=False)
        steps = int(sol.stats["num_steps"])
        sims, jacs = 1 + steps, steps
    return _finish(problem, method, sol.value, steps, sims, jacs, tolerance, (), t0, limits, control_limit,
                   on_violation, throw, before)


def mirror_passes(problem: CECProblem, passes: int, *, smoothing: int = 1, limits: AxisLimits | None = None,
                  control_limit=None, on_violation: str = "flag") -> CompensationResult:
    """Apply Prévost's rule (eq 4) a fixed number of times, recording the exact max ``|e_T|`` after
    every pass in ``history``. ``passes = 1`` is the paper's method (:func:`mirror_single_pass`);
    more passes are the iterated-mirror extension.

    Never raises for non-convergence (there is no tolerance): ``converged`` is False and ``history``
    shows what each pass achieved. ``smoothing``: Q-filter window in samples (:func:`mirror_step`,
    an extension as well).
    """
    if not isinstance(passes, (int, np.integer)) or passes < 1:
        raise ParameterError(f"passes must be an integer >= 1, got {passes!r}")
    if not isinstance(smoothing, (int, np.integer)) or smoothing < 1:
        raise ParameterError(f"smoothing must be a window of >= 1 samples, got {smoothing!r}")
    _check_common(1.0, 1, on_violation, limits)
    t0 = time.perf_counter()
    D = np.zeros(np.shape(problem.setpoint.q))  # NumPy: no eager JAX operation to compile
    before = contour_error(problem.cam_path, np.asarray(simulate_correction(problem, D).position))
    history = []
    for _ in range(passes):
        D = mirror_step(problem, D, int(smoothing))  # its parts compiled: the drive scan once, not again inside it
        history.append(contour_error(problem.cam_path, np.asarray(simulate_correction(problem, D).position)).max)
    return _finish(problem, "passes", D, passes, 1 + 2 * passes, 0, 0.0, history, t0, limits, control_limit,
                   on_violation, False, before)


def mirror_single_pass(problem: CECProblem, *, limits: AxisLimits | None = None, control_limit=None,
                       on_violation: str = "flag") -> CompensationResult:
    """Prévost's CEC method: one mirror pass, eq 4, ``R'_i = R_i - e_T(t_i)`` from the uncompensated
    simulation, then the compensated motion simulated and checked (§3).

    Args:
        problem: from :func:`cec_problem`.
        limits, control_limit, on_violation: the check of the compensated setpoint, as in
            :func:`mirror_compensation` (Prévost §3: "the trajectory execution has to be checked").
    Returns:
        :class:`CompensationResult` with ``method = "single_pass"``, ``history = (after.max,)``;
        ``converged`` is False (no tolerance is asked for).
    Raises:
        InfeasibleProblem: limits violated with ``on_violation="refuse"``; ParameterError: bad arguments.
    """
    r = mirror_passes(problem, 1, limits=limits, control_limit=control_limit, on_violation=on_violation)
    return dataclasses.replace(r, method=PAPER_METHOD)
