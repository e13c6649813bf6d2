"""The bounded problem of thesis §6.4 solved with optimistix: smooth bounds plus variable projection.

Same objective as the PSO (eq 6.18 with eq 6.21 inside, :class:`ProjectedProblem`), but solved by a
Gauss-Newton-type method on the reduced residual ``z_b - R11 theta1(sigma(u))``:

* bounds by reparametrization, smooth and never violated: ``wn = wn_min (wn_max/wn_min)^sig(u1)``,
  ``p = p_min (p_max/p_min)^sig(u3)`` (log scale: frequencies span three decades) and
  ``zeta = zeta_min + (zeta_max - zeta_min) sig(u2)`` with the logistic ``sig``; every ``u`` is a stable model
  inside eq 6.14;
* variable projection: the zeros and friction are eliminated by eq 6.21, so only 3 unknowns remain;
* starts: the unconstrained LS optimum (from the same QR) when it lies inside the bounds -- it is then the
  global minimum of the bounded problem and LM only polishes it -- otherwise the best points of a coarse
  grid over the region (cheap: the reduced objective costs a 3 x 3 product per point), solved at once
  (``jax.vmap``); the lowest loss wins. Coordinates that end within 1e-4 of a bound are put on it when
  that lowers the loss (the logistic map only approaches a bound).
"""

from __future__ import annotations

import functools
import time

import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx

from research.errors import ParameterError
from research.identification._log import DriveLog
from research.identification._projection import (
    THESIS_BOUNDS,
    PoleBounds,
    ProjectedProblem,
    theta1_from_poles,
)
from research.identification._regression import (
    DEFAULT_OPTIONS,
    Regression,
    RegressionOptions,
    build_regression,
)
from research.identification._result import IdentifiedDrive

SOLVERS = ("levenberg_marquardt", "gauss_newton")
_EDGE = 1e-6  # starts are kept this far (in logistic coordinates) inside the bounds


def sigma_from_u(u, lower, upper, xp=jnp):
    """Smooth bounded map ``u (..., 3) -> sigma = [wn, zeta, p]`` (module docstring); ``lower``/``upper`` from
    :class:`PoleBounds`."""
    s = 1.0 / (1.0 + xp.exp(-u))
    wn = lower[0] * (upper[0] / lower[0]) ** s[..., 0]
    z = lower[1] + (upper[1] - lower[1]) * s[..., 1]
    p = lower[2] * (upper[2] / lower[2]) ** s[..., 2]
    return xp.stack([wn, z, p], axis=-1)


def u_from_sigma(sigma, lower, upper) -> np.ndarray:
    """Inverse of :func:`sigma_from_u` (points on a bound are moved ``_EDGE`` inside)."""
    sigma = np.asarray(sigma, dtype=np.float64)
    f = np.stack([
        np.log(sigma[..., 0] / lower[0]) / np.log(upper[0] / lower[0]),
        (sigma[..., 1] - lower[1]) / (upper[1] - lower[1]),
        np.log(sigma[..., 2] / lower[2]) / np.log(upper[2] / lower[2]),
    ], axis=-1)
    f = np.clip(f, _EDGE, 1 - _EDGE)
    return np.log(f / (1 - f))


def _residual(u, args):
    R11, z_b, scale1, lower, upper = args
    t1 = theta1_from_poles(sigma_from_u(u, lower, upper), xp=jnp)
    return z_b - (t1 * scale1) @ R11.T


@functools.partial(jax.jit, static_argnames=("solver", "max_steps"))
def _solve_starts(u0, args, *, solver, max_steps):
    if solver == "levenberg_marquardt":
        opt = optx.LevenbergMarquardt(rtol=1e-12, atol=1e-16)
    else:
        opt = optx.GaussNewton(rtol=1e-12, atol=1e-16)

    def one(u):
        sol = optx.least_squares(_residual, opt, u, args, max_steps=max_steps, throw=False)
        r = _residual(sol.value, args)
        return sol.value, 0.5 * jnp.sum(r * r), sol.stats["num_steps"]

    return jax.vmap(one)(u0)


def grid_starts(prob: ProjectedProblem, bounds: PoleBounds, count: int = 3, shape=(12, 6, 12)) -> np.ndarray:
    """The ``count`` lowest-loss points ``sigma`` of a grid over the bounded region (log-spaced in ``wn``, ``p``)."""
    lo, hi = bounds.lower, bounds.upper
    g = np.meshgrid(
        np.geomspace(lo[0], hi[0], shape[0]), np.linspace(lo[1], hi[1], shape[1]), np.geomspace(lo[2], hi[2], shape[2]),
        indexing="ij",
    )
    pts = np.stack([a.ravel() for a in g], axis=-1)
    f = prob.loss(pts)
    return pts[np.argsort(f)[:count]]


def bounded_fit(
    data: DriveLog | Regression | ProjectedProblem,
    *,
    bounds: PoleBounds = THESIS_BOUNDS,
    solver: str = "levenberg_marquardt",
    starts: int = 3,
    max_steps: int = 100,
    initial: np.ndarray | None = None,
    options: RegressionOptions = DEFAULT_OPTIONS,
) -> IdentifiedDrive:
    """Minimize eq 6.18 subject to eq 6.14 with optimistix (module docstring).

    Args:
        data: log, regression or :class:`ProjectedProblem`.
        bounds: :class:`PoleBounds` (default thesis §6.5).
        solver: ``"levenberg_marquardt"`` or ``"gauss_newton"`` (``optx.LevenbergMarquardt`` / ``optx.GaussNewton``).
        starts: number of grid starts, used when the LS optimum is outside the bounds or unstable.
        max_steps: solver steps per start.
        initial: optional extra start ``sigma = [wn, zeta, p]`` [rad/s, -, rad/s].
        options: regression processing when ``data`` is a log.
    Returns:
        :class:`IdentifiedDrive` ``method="optimistix"``, ``info["sigma"]`` inside ``bounds``.
    """
    if solver not in SOLVERS:
        raise ParameterError(f"bounded_fit: solver must be one of {SOLVERS}, got {solver!r}")
    if isinstance(data, ProjectedProblem):
        prob = data
    else:
        reg = data if isinstance(data, Regression) else build_regression(data, options)
        prob = ProjectedProblem.from_regression(reg)
    t0 = time.perf_counter()
    ls = _ls_sigma(prob)
    if ls is not None and bounds.contains(ls):
        # the unconstrained optimum satisfies eq 6.14, so it is the bounded problem's global minimum:
        # one start suffices (LM only polishes it)
        cand = [ls[None]]
    else:
        cand = [grid_starts(prob, bounds, starts)]
    if initial is not None:
        cand.append(np.clip(np.asarray(initial, dtype=np.float64), bounds.lower, bounds.upper)[None])
    sig0 = np.concatenate(cand)
    lo, hi = jnp.asarray(bounds.lower), jnp.asarray(bounds.upper)
    args = (jnp.asarray(prob.R11), jnp.asarray(prob.z_b), jnp.asarray(prob.scale1), lo, hi)
    u, f, steps = _solve_starts(jnp.asarray(u_from_sigma(sig0, bounds.lower, bounds.upper)), args, solver=solver, max_steps=max_steps)
    u, f, steps = np.asarray(u), np.asarray(f), np.asarray(steps)
    k = int(np.nanargmin(f))
    sigma = _snap_to_bounds(prob, np.asarray(sigma_from_u(u[k], bounds.lower, bounds.upper, xp=np)), bounds)
    wall = time.perf_counter() - t0
    theta = prob.theta(sigma)
    return IdentifiedDrive.from_theta(
        theta, method="optimistix", loss=float(prob.loss(sigma)), loss_kind="equation error, eq 6.10",
        wall_time_s=wall, iterations=int(steps.sum()), source=prob.regression.source,
        info={"sigma": sigma.tolist(), "solver": solver, "starts": sig0.tolist(), "bounds": bounds.to_dict()},
    )


def _snap_to_bounds(prob: ProjectedProblem, sigma: np.ndarray, bounds: PoleBounds) -> np.ndarray:
    """The logistic map reaches a bound only asymptotically: put coordinates within 1e-4 (relative to the
    range) of a bound on it when that lowers the loss."""
    lo, hi = bounds.lower, bounds.upper
    tol = 1e-4 * (hi - lo)
    snapped = np.where(sigma - lo < tol, lo, np.where(hi - sigma < tol, hi, sigma))
    return snapped if prob.loss(snapped) <= prob.loss(sigma) else sigma


def _ls_sigma(prob: ProjectedProblem) -> np.ndarray | None:
    """``[wn, zeta, p]`` of the unconstrained LS optimum (from the QR blocks: ``R11 theta1 = z_b``), or None when
    its poles are not of the eq 6.13 form with positive ``wn``, ``zeta``, ``p``."""
    try:
        alpha1, alpha2, alpha3 = np.linalg.solve(prob.R11, prob.z_b) / prob.scale1
    except np.linalg.LinAlgError:
        return None
    a2 = 1 / alpha1
    r = np.roots([1.0, alpha2 * a2, a2, alpha3 * a2])
    if np.any(r.real >= 0):
        return None
    cplx = r[np.abs(r.imag) > 1e-9 * np.abs(r)]
    if cplx.size:
        wn = abs(cplx[0])
        return np.array([wn, -cplx[0].real / wn, -r[np.abs(r.imag) <= 1e-9 * np.abs(r)].real[0]])
    r = np.sort(r.real)[::-1]
    wn = np.sqrt(r[1] * r[2])
    return np.array([wn, -(r[1] + r[2]) / (2 * wn), -r[0]])
