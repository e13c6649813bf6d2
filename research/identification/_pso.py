"""Constrained identification by Particle Swarm Optimization, thesis §6.4 (eq 6.16-6.23), written out by hand.

The swarm searches the pole part ``sigma = [wn, zeta, p]`` (eq 6.17) inside the bounds of eq 6.14; each
particle's zeros and friction come from the inner least squares eq 6.21 (see
:class:`~research.identification.ProjectedProblem`). All particles move together (numpy arrays
``(M, 3)``); randomness comes only from ``numpy.random.default_rng(seed)``.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from research.errors import ParameterError
from research.identification._log import DriveLog
from research.identification._projection import (
    THESIS_BOUNDS,
    PoleBounds,
    ProjectedProblem,
)
from research.identification._regression import (
    DEFAULT_OPTIONS,
    Regression,
    RegressionOptions,
    build_regression,
)
from research.identification._result import IdentifiedDrive


@dataclasses.dataclass(frozen=True)
class PSOSettings:
    """PSO parameters, thesis §6.5 values by default.

    Attributes:
        eta1, eta2: learning gains toward the particle's and the swarm's best (eq 6.16; thesis 0.103, 2.897,
            ``eta1 + eta2 = 3`` inside the convergent range of §6.4.3).
        inertia: inertia weight ``w`` (thesis 0.6).
        particles: swarm size ``M`` (thesis 200).
        iterations: iterations (thesis 100).
        velocity_fraction: ``v_max = (sigma_max - sigma_min) * velocity_fraction`` (eq 6.22: 10-20 %).
        swarms: independent swarms run side by side (restarts); the best final ``gbest`` wins. The thesis
            runs one. With its strongly social gains (``eta2 / eta1 = 28``) a single swarm collapses early,
            and on the Table 6.2 drive it settles in a local minimum with three real poles (``zeta > 1``)
            in about 3 of 4 seeds; independent swarms make finding the global minimum likely (tests use 16).
    """

    eta1: float = 0.103
    eta2: float = 2.897
    inertia: float = 0.6
    particles: int = 200
    iterations: int = 100
    velocity_fraction: float = 0.15
    swarms: int = 1

    def __post_init__(self):
        if not (self.particles >= 2 and self.iterations >= 1):
            raise ParameterError(f"PSOSettings: need particles >= 2 and iterations >= 1, got {self.particles}, {self.iterations}")
        if not (0 < self.inertia < 1):
            raise ParameterError(f"PSOSettings.inertia must lie in (0, 1) for convergence (§6.4.3), got {self.inertia}")
        if not (self.eta1 >= 0 and self.eta2 >= 0 and 0 < self.eta1 + self.eta2 < 4):
            raise ParameterError(f"PSOSettings: eta1, eta2 >= 0 with eta1 + eta2 < 4 (§6.4.3), got {self.eta1}, {self.eta2}")
        if self.swarms < 1:
            raise ParameterError(f"PSOSettings.swarms must be >= 1, got {self.swarms}")
        if not (0 < self.velocity_fraction <= 1):
            raise ParameterError(f"PSOSettings.velocity_fraction must lie in (0, 1], got {self.velocity_fraction}")


def particle_swarm(
    data: DriveLog | Regression | ProjectedProblem,
    *,
    seed: int,
    bounds: PoleBounds = THESIS_BOUNDS,
    settings: PSOSettings = PSOSettings(),
    options: RegressionOptions = DEFAULT_OPTIONS,
) -> IdentifiedDrive:
    """Thesis §6.4.2 steps 1-7.

    1. ``sigma^0`` uniform in the box, ``v^0`` uniform in ``[-v_max, v_max]`` (eq 6.22);
    2. evaluate ``f`` for every particle (eq 6.18, 6.20, 6.21);
    3-4. update each particle's best and the swarm's best;
    5-6. move (eq 6.16, with uniform random factors ``r1, r2`` per particle and coordinate -- the
       "stochastic acceleration terms" of §6.4.1) and put coordinates outside the region back on the
       closest bound (eq 6.23);
    7. after the last iteration return the swarm's best, with eq 6.20/6.21/6.8 de-normalization.

    Args:
        data: log, regression or ready :class:`ProjectedProblem`.
        seed: seed of the swarm's random numbers (required: the result depends on it).
        bounds: :class:`PoleBounds` (eq 6.14; default thesis §6.5).
        settings: :class:`PSOSettings` (default thesis §6.5).
        options: regression processing when ``data`` is a log.
    Returns:
        :class:`IdentifiedDrive` ``method="pso"``; ``history`` holds the gbest trajectory (Fig 6.8) and
        ``info["sigma"]`` the final ``[wn, zeta, p]`` (inside ``bounds`` by construction).
    """
    if not isinstance(seed, (int, np.integer)) or isinstance(seed, bool):
        raise ParameterError(f"particle_swarm: seed must be an int, got {seed!r}")
    prob = _problem(data, options)
    t0 = time.perf_counter()
    sigma, f, history = _swarm(prob.loss, bounds, settings, int(seed))
    wall = time.perf_counter() - t0
    theta = prob.theta(sigma)
    return IdentifiedDrive.from_theta(
        theta, method="pso", loss=float(f), loss_kind="equation error, eq 6.10", wall_time_s=wall,
        iterations=settings.iterations * settings.swarms, source=prob.regression.source, history=history,
        info={"sigma": sigma.tolist(), "seed": int(seed), "bounds": bounds.to_dict(), "settings": dataclasses.asdict(settings)},
    )


def _problem(data, options) -> ProjectedProblem:
    if isinstance(data, ProjectedProblem):
        return data
    reg = data if isinstance(data, Regression) else build_regression(data, options)
    return ProjectedProblem.from_regression(reg)


def _swarm(objective, bounds: PoleBounds, s: PSOSettings, seed: int):
    """The vectorized swarms ``(S, M, 3)``; ``objective`` maps ``(..., 3)`` particles to ``(...)`` losses.
    Returns the best ``gbest`` over the swarms, its loss and the history of that swarm."""
    rng = np.random.default_rng(seed)
    lo, hi = bounds.lower, bounds.upper
    S, M = s.swarms, s.particles
    vmax = (hi - lo) * s.velocity_fraction
    v = -vmax + 2.0 * rng.random((S, M, 3)) * vmax  # eq 6.22
    x = lo + rng.random((S, M, 3)) * (hi - lo)
    pbest, fbest = x.copy(), np.full((S, M), np.inf)
    g, fg = x[:, 0].copy(), np.full(S, np.inf)
    history = np.empty((s.iterations, S, 4))
    rows = np.arange(S)
    for it in range(s.iterations):
        f = objective(x)  # step 2
        f = np.where(np.isfinite(f), f, np.inf)
        better = f <= fbest  # step 3
        pbest[better], fbest[better] = x[better], f[better]
        k = np.argmin(fbest, axis=1)  # step 4
        improve = fbest[rows, k] <= fg
        g[improve], fg[improve] = pbest[rows, k][improve], fbest[rows, k][improve]
        history[it, :, 0], history[it, :, 1:] = fg, g
        r1, r2 = rng.random((S, M, 3)), rng.random((S, M, 3))
        v = s.inertia * v + s.eta1 * r1 * (pbest - x) + s.eta2 * r2 * (g[:, None, :] - x)  # eq 6.16
        x = np.clip(x + v, lo, hi)  # step 5, eq 6.23
    best = int(np.argmin(fg))
    return g[best].copy(), float(fg[best]), history[:, best, :].copy()
