"""The bounded identification problem of thesis §6.4: pole bounds (eq 6.13/6.14), the pole map eq 6.20 and
the variable-projection objective eq 6.18-6.21 that both the PSO and the optimistix fits minimize.

Given the pole part ``sigma = [wn, zeta, p]`` (eq 6.17), ``theta1 = [alpha1, alpha2, alpha3]`` follows from
eq 6.20 and the zero/friction part ``theta2 = [beta0, beta1, beta2, delta]`` from the inner least squares
eq 6.21, so the objective ``f(sigma) = 0.5 ||Y - Phi1 theta1 - Phi2 theta2||^2`` (eq 6.18) depends on three
numbers only. It is evaluated exactly from a QR factorization of the column-scaled ``[Phi2 Phi1]``
(computed once): with ``Q^T Y = [z_a; z_b]`` and ``R = [[R22, R21], [0, R11]]``, eq 6.21 zeroes the first
block and ``f = 0.5 (||z_b - R11 theta1||^2 + r_0^2)`` where ``r_0`` is the part of ``Y`` outside the span
of ``Phi`` -- the same number as the N-sample residual, at the cost of a 3 x 3 product per particle.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from research.errors import ParameterError
from research.identification._regression import POLE_COLUMNS, ZERO_COLUMNS, Regression

HZ = 2 * np.pi


@dataclasses.dataclass(frozen=True)
class PoleBounds:
    """Search region of eq 6.14 (Fig 6.4/6.5) for ``sigma = [wn, zeta, p]``.

    Attributes:
        wn_min, wn_max: bounds on the natural frequency of the complex pair [rad/s] (> 0).
        zeta_min, zeta_max: bounds on its damping [-] (``0 < zeta_min < zeta_max``).
        p_min, p_max: bounds on the real pole frequency [rad/s] (> 0).

    Every point of the region gives three poles in the open left half plane (eq 6.13), which is the
    thesis' stability guarantee.
    """

    wn_min: float
    wn_max: float
    zeta_min: float
    zeta_max: float
    p_min: float
    p_max: float

    def __post_init__(self):
        for lo, hi in (("wn_min", "wn_max"), ("zeta_min", "zeta_max"), ("p_min", "p_max")):
            a, b = getattr(self, lo), getattr(self, hi)
            if not (np.isfinite(a) and np.isfinite(b) and 0 < a < b):
                raise ParameterError(f"PoleBounds: need 0 < {lo} < {hi} (eq 6.14), got {a!r}, {b!r}")

    @staticmethod
    def thesis() -> PoleBounds:
        """Thesis §6.5: ``wn, p`` in [0.2, 500] Hz, ``zeta`` in [0.2, 2.0]."""
        return PoleBounds(0.2 * HZ, 500 * HZ, 0.2, 2.0, 0.2 * HZ, 500 * HZ)

    @property
    def lower(self) -> np.ndarray:
        """``sigma_min = [wn_min, zeta_min, p_min]`` (PSO step 1)."""
        return np.array([self.wn_min, self.zeta_min, self.p_min])

    @property
    def upper(self) -> np.ndarray:
        """``sigma_max = [wn_max, zeta_max, p_max]``."""
        return np.array([self.wn_max, self.zeta_max, self.p_max])

    def contains(self, sigma) -> bool:
        s = np.asarray(sigma, dtype=np.float64)
        return bool(np.all(s >= self.lower) and np.all(s <= self.upper))

    def to_dict(self) -> dict:
        return {"wn_hz": [self.wn_min / HZ, self.wn_max / HZ], "zeta": [self.zeta_min, self.zeta_max],
                "p_hz": [self.p_min / HZ, self.p_max / HZ]}


#: the thesis §6.5 search region (module-level default for function arguments)
THESIS_BOUNDS = PoleBounds.thesis()


def theta1_from_poles(sigma, xp=np):
    """Eq 6.20: ``sigma = [wn, zeta, p]`` (``(..., 3)``, rad/s, -, rad/s) -> ``[alpha1, alpha2, alpha3]``.

    ``alpha1 = 1/(wn^2 + 2 zeta wn p)``, ``alpha2 = (p + 2 zeta wn) alpha1``, ``alpha3 = p wn^2 alpha1``.
    ``xp`` is ``numpy`` or ``jax.numpy``.
    """
    wn, z, p = sigma[..., 0], sigma[..., 1], sigma[..., 2]
    a2 = wn**2 + 2 * z * wn * p
    return xp.stack([1.0 / a2, (p + 2 * z * wn) / a2, p * wn**2 / a2], axis=-1)


@dataclasses.dataclass(frozen=True, eq=False)
class ProjectedProblem:
    """The eq 6.18-6.21 objective over ``sigma``, built once from a :class:`Regression`.

    Attributes:
        regression: the eq 6.9 regression.
        R11 ``(3, 3)``, R21 ``(4, 3)``, R22 ``(4, 4)``, z_a ``(4,)``, z_b ``(3,)``: QR blocks (module docstring)
            of the column-scaled regressor ``[Phi2 Phi1] / scale``.
        scale1 ``(3,)``, scale2 ``(4,)``: column norms of ``Phi1`` and ``Phi2``.
        r0_squared: ``||Y - proj_Phi Y||^2`` [mm^2], the loss floor.
    """

    regression: Regression
    R11: np.ndarray
    R21: np.ndarray
    R22: np.ndarray
    z_a: np.ndarray
    z_b: np.ndarray
    scale1: np.ndarray
    scale2: np.ndarray
    r0_squared: float

    @staticmethod
    def from_regression(reg: Regression) -> ProjectedProblem:
        """QR-factorize the scaled ``[Phi2 Phi1]`` of ``reg`` (eq 6.19 split)."""
        s1 = reg.column_scale[list(POLE_COLUMNS)]
        s2 = reg.column_scale[list(ZERO_COLUMNS)]
        A = np.column_stack([reg.Phi[:, list(ZERO_COLUMNS)] / s2, reg.Phi[:, list(POLE_COLUMNS)] / s1])
        Q, R = np.linalg.qr(A)
        z = Q.T @ reg.Y
        r0 = reg.Y - Q @ z
        return ProjectedProblem(reg, R[4:, 4:], R[:4, 4:], R[:4, :4], z[:4], z[4:], s1, s2, float(r0 @ r0))

    # -- objective -------------------------------------------------------------------------------
    def residual(self, theta1, xp=np):
        """Reduced residual ``z_b - R11 (scale1 theta1)`` ``(..., 3)`` [mm] for ``theta1`` ``(..., 3)``."""
        R11 = xp.asarray(self.R11)
        return xp.asarray(self.z_b) - (theta1 * xp.asarray(self.scale1)) @ R11.T

    def loss_theta1(self, theta1) -> np.ndarray:
        """Eq 6.18 with eq 6.21 inside, for ``theta1`` ``(..., 3)``: ``0.5 (||residual||^2 + r_0^2)`` [mm^2]."""
        r = self.residual(np.asarray(theta1, dtype=np.float64))
        return 0.5 * (np.sum(r * r, axis=-1) + self.r0_squared)

    def loss(self, sigma) -> np.ndarray:
        """Eq 6.18 as a function of the particles ``sigma = [wn, zeta, p]`` ``(..., 3)`` (eq 6.17, 6.20, 6.21)."""
        return self.loss_theta1(theta1_from_poles(np.asarray(sigma, dtype=np.float64)))

    def theta2(self, theta1) -> np.ndarray:
        """Eq 6.21: ``theta2 = [beta0, beta1, beta2, delta]`` minimizing eq 6.18 for given ``theta1`` ``(3,)``."""
        t1 = np.asarray(theta1, dtype=np.float64) * self.scale1
        return np.linalg.solve(self.R22, self.z_a - self.R21 @ t1) / self.scale2

    def theta(self, sigma) -> np.ndarray:
        """Full eq 6.8 ``theta`` (column order of :data:`research.identification.PARAMETERS`) for ``sigma``."""
        t1 = theta1_from_poles(np.asarray(sigma, dtype=np.float64))
        t2 = self.theta2(t1)
        out = np.empty(7)
        out[list(POLE_COLUMNS)] = t1
        out[list(ZERO_COLUMNS)] = t2
        return out

    def loss_full(self, sigma) -> np.ndarray:
        """The same objective evaluated the thesis' way on all N samples (eq 6.21 per particle, then eq 6.18);
        ``sigma`` ``(..., 3)``. O(N P) work; used to check :meth:`loss` and in the benchmark."""
        reg = self.regression
        sigma = np.asarray(sigma, dtype=np.float64)
        shape = sigma.shape[:-1]
        Phi1, Phi2 = reg.Phi[:, list(POLE_COLUMNS)], reg.Phi[:, list(ZERO_COLUMNS)]
        t1 = theta1_from_poles(sigma.reshape(-1, 3))  # (P, 3)
        rest = reg.Y[:, None] - Phi1 @ t1.T  # (N, P)
        t2, *_ = np.linalg.lstsq(Phi2, rest, rcond=None)  # eq 6.21 for every particle
        r = rest - Phi2 @ t2
        return (0.5 * np.sum(r * r, axis=0)).reshape(shape)

