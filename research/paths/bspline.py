"""B-spline tool paths [mm]: evaluation, derivatives, arc length, exact point projection, and the
planar cubic B-spline of Prévost et al. (HSM 2012, Application 1, Fig 4).

A :class:`BSplinePath` wraps ``scipy.interpolate.BSpline`` (control points ``(n, d)``, degree ``p``,
knot vector of ``n + p + 1`` values). Arc length is integrated with Gauss-Legendre quadrature over
sub-intervals of every knot span, so it is exact to ~1e-12 mm for these polynomial pieces; the
inverse map ``s -> u`` is Newton on that integral. :meth:`BSplinePath.to_polyline` gives a dense
polyline for the G01 interpolators, with a stated chord error bound; :meth:`BSplinePath.project`
gives the exact closest point (a KD-tree over a dense polyline picks the basin, Newton on
``C'(u) . (C(u) - p) = 0`` finds the foot on the curve itself).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.interpolate import BSpline

from research.errors import PathError
from research.paths._arc_length import ArcLength
from research.paths.polyline import DEFAULT_AXES, Polyline



@dataclass(frozen=True, eq=False)
class BSplinePath:
    """A (clamped or unclamped) B-spline curve ``C(u) = sum_i N_{i,p}(u) P_i`` on ``[U_p, U_{n}]``.

    Args:
        control_points: ``(n, d)`` control points ``P_i`` [mm], ``d`` in 1..3, ``n >= p + 1``.
        knots: knot vector ``U``, ``n + p + 1`` non-decreasing values.
        degree: ``p >= 1``.
        axes: axis names (default ``x, y, z`` cut to ``d``).

    Raises:
        PathError: wrong shapes, non-finite values, decreasing knots, an empty parameter domain.

    Example:
        >>> c = prevost2012_bspline()
        >>> c(0.0).round(6).tolist(), c(1.0).round(6).tolist()
        ([[-100.0, 0.0]], [[-100.0, -50.0]])
    """

    control_points: np.ndarray
    knots: np.ndarray
    degree: int = 3
    axes: tuple[str, ...] = ()
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    def __post_init__(self):
        cp = np.array(self.control_points, dtype=np.float64)
        U = np.array(self.knots, dtype=np.float64).ravel()
        p = self.degree
        if not isinstance(p, (int, np.integer)) or p < 1:
            raise PathError(f"BSplinePath.degree must be an integer >= 1, got {p!r}")
        if cp.ndim != 2 or not 1 <= cp.shape[1] <= 3 or cp.shape[0] < p + 1:
            raise PathError(
                f"BSplinePath.control_points must have shape (n, d) with n >= degree + 1 = {p + 1} and d in 1..3, "
                f"got {cp.shape}"
            )
        if U.size != cp.shape[0] + p + 1:
            raise PathError(
                f"BSplinePath.knots needs n + p + 1 = {cp.shape[0] + p + 1} values for {cp.shape[0]} control points "
                f"of degree {p}, got {U.size}"
            )
        for name, arr in (("control_points", cp), ("knots", U)):
            if not np.all(np.isfinite(arr)):
                raise PathError(f"BSplinePath.{name} contains NaN or inf")
        if np.any(np.diff(U) < 0):
            k = int(np.argmax(np.diff(U) < 0))
            raise PathError(f"BSplinePath.knots must be non-decreasing; knot {k + 1} = {U[k + 1]} < knot {k} = {U[k]}")
        if not U[-p - 1] > U[p]:
            raise PathError(f"BSplinePath.knots give an empty parameter domain [{U[p]}, {U[-p - 1]}]")
        axes = tuple(self.axes) or DEFAULT_AXES[: cp.shape[1]]
        if len(axes) != cp.shape[1]:
            raise PathError(f"BSplinePath has {cp.shape[1]} coordinates per control point but axes {axes}")
        cp.setflags(write=False)
        U.setflags(write=False)
        object.__setattr__(self, "control_points", cp)
        object.__setattr__(self, "knots", U)
        object.__setattr__(self, "degree", int(p))
        object.__setattr__(self, "axes", axes)

    # -- evaluation --------------------------------------------------------------------------------
    @property
    def dim(self) -> int:
        return self.control_points.shape[1]

    @property
    def domain(self) -> tuple[float, float]:
        """Parameter interval ``[U_p, U_n]``."""
        p = self.degree
        return float(self.knots[p]), float(self.knots[-p - 1])

    @property
    def spline(self) -> BSpline:
        """The underlying ``scipy.interpolate.BSpline``."""
        if "spline" not in self._cache:
            self._cache["spline"] = BSpline(self.knots, self.control_points, self.degree, extrapolate=False)
        return self._cache["spline"]

    def __call__(self, u, nu: int = 0) -> np.ndarray:
        """``d^nu C / du^nu`` at parameters ``u`` (clipped to the domain), shape ``(len(u), d)`` [mm]."""
        if not isinstance(nu, (int, np.integer)) or nu < 0:
            raise PathError(f"derivative order nu must be an integer >= 0, got {nu!r}")
        u0, u1 = self.domain
        u = np.clip(np.atleast_1d(np.asarray(u, dtype=np.float64)), u0, u1)
        if nu > self.degree:
            return np.zeros((u.size, self.dim))
        if nu not in self._cache:
            self._cache[nu] = self.spline if nu == 0 else self.spline.derivative(nu)
        return np.asarray(self._cache[nu](u)).reshape(u.size, self.dim)

    def speed(self, u) -> np.ndarray:
        """``|C'(u)|`` [mm per unit parameter], shape ``(len(u),)``."""
        return np.linalg.norm(self(u, 1), axis=1)

    def curvature(self, u) -> np.ndarray:
        """Curvature ``kappa(u) = |C' x C''| / |C'|^3`` [1/mm] (``d`` = 2 or 3), shape ``(len(u),)``."""
        d1, d2 = self(u, 1), self(u, 2)
        if self.dim == 1:
            return np.zeros(d1.shape[0])
        if self.dim == 2:
            cross = np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])
        else:
            cross = np.linalg.norm(np.cross(d1, d2), axis=1)
        return cross / np.maximum(np.linalg.norm(d1, axis=1), 1e-300) ** 3

    # -- arc length --------------------------------------------------------------------------------
    def _arc(self) -> ArcLength:
        """Gauss-Legendre table: 12 nodes on 8 sub-intervals of every knot span."""
        if "arc" not in self._cache:
            u0, u1 = self.domain
            self._cache["arc"] = ArcLength.build(self.knots[(self.knots >= u0) & (self.knots <= u1)], self.speed,
                                                 order=12, subdivisions=8)
        return self._cache["arc"]

    @property
    def length(self) -> float:
        """Total arc length [mm] (Gauss-Legendre, 12 nodes on 8 sub-intervals of every knot span)."""
        return self._arc().total

    def arc_length(self, u) -> np.ndarray:
        """Arc length ``s(u) = int_{U_p}^{u} |C'|`` [mm] at parameters ``u``, shape ``(len(u),)``."""
        return self._arc()(u)

    def parameter_at(self, s) -> np.ndarray:
        """Inverse of :meth:`arc_length`: the parameter ``u`` at arc length ``s`` [mm] (clipped to
        ``[0, length]``); Newton on ``s(u) - s``, safeguarded by the quadrature brackets."""
        return self._arc().inverse(s)

    # -- discretization and projection --------------------------------------------------------------
    def sample(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        """``n >= 2`` points equally spaced in arc length: ``(u, C(u))``, shapes ``(n,)``, ``(n, d)``."""
        if not isinstance(n, (int, np.integer)) or n < 2:
            raise PathError(f"BSplinePath.sample needs an integer n >= 2, got {n!r}")
        u = self.parameter_at(np.linspace(0.0, self.length, int(n)))
        return u, self(u)

    def to_polyline(self, chord_error: float = 1e-4) -> Polyline:
        """A polyline through points of the curve equally spaced in arc length whose chord error
        (sagitta ``h^2 kappa_max / 8``) is below ``chord_error`` [mm].

        Raises:
            PathError: ``chord_error`` not > 0.
        """
        return Polyline(self.sample(self._count_for(chord_error))[1], self.axes)

    def _count_for(self, chord_error: float) -> int:
        if not (np.isfinite(chord_error) and chord_error > 0):
            raise PathError(f"chord_error must be a finite length > 0 mm, got {chord_error!r}")
        u0, u1 = self.domain
        kmax = float(np.max(self.curvature(np.linspace(u0, u1, 4001)))) * 1.05 + 1e-12
        h = np.sqrt(8.0 * chord_error / kmax)
        return max(2, int(np.ceil(self.length / h)) + 1)

    def project(self, query) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Closest point of the curve to each query point.

        A dense polyline (chord error 1e-3 mm) with its KD-tree gives the basin; Newton on
        ``g(u) = C'(u) . (C(u) - q) = 0`` inside the neighbouring polyline intervals gives the foot.
        Exact (to ~1e-12 mm) unless two distant branches of the curve are within the chord error of
        each other, where the answer is still within 1e-3 mm of the exact distance.

        Args:
            query: ``(N, d)`` points [mm].
        Returns:
            ``(distance [mm] (N,), parameter u (N,), foot point (N, d) [mm])``.
        """
        q = np.asarray(query, dtype=np.float64).reshape(-1, self.dim)
        if not np.all(np.isfinite(q)):
            raise PathError("BSplinePath.project: query points contain NaN or inf")
        if "dense" not in self._cache:
            uu, pts = self.sample(self._count_for(1e-3))
            self._cache["dense"] = (uu, Polyline(pts, self.axes))
        uu, poly = self._cache["dense"]
        _, seg, frac = poly.project(q)
        lo = uu[np.maximum(seg - 1, 0)]
        hi = uu[np.minimum(seg + 2, uu.size - 1)]
        u = uu[seg] + frac * (uu[seg + 1] - uu[seg])
        for _ in range(12):
            c, d1, d2 = self(u), self(u, 1), self(u, 2)
            e = c - q
            g = np.sum(d1 * e, axis=1)
            dg = np.sum(d1 * d1, axis=1) + np.sum(d2 * e, axis=1)
            step = np.where(dg > 0, g / np.where(dg > 0, dg, 1.0), 0.0)
            u = np.clip(u - step, lo, hi)
            if np.max(np.abs(step)) < 1e-14:
                break
        foot = self(u)
        return np.linalg.norm(q - foot, axis=1), u, foot

    def distance(self, query) -> np.ndarray:
        """Exact distance [mm] from each query point ``(N, d)`` to the curve, shape ``(N,)``."""
        return self.project(query)[0]


def prevost2012_bspline() -> BSplinePath:
    """Prévost, Lavernhe, Lartigue (HSM 2012) Application 1, Fig 4: the planar cubic B-spline with
    control points (-100, 0), (-50, 0), (-50, 50), (0, 50), (50, 0), (50, -50), (-100, -50) [mm],
    degree p = 3 and knot vector U = [0, 0, 0, 0, 1/3, 1/2, 2/3, 1, 1, 1, 1]. The paper machines it at
    a programmed feed of 10 m/min."""
    cp = [[-100.0, 0.0], [-50.0, 0.0], [-50.0, 50.0], [0.0, 50.0], [50.0, 0.0], [50.0, -50.0], [-100.0, -50.0]]
    U = [0.0, 0.0, 0.0, 0.0, 1 / 3, 1 / 2, 2 / 3, 1.0, 1.0, 1.0, 1.0]
    return BSplinePath(np.array(cp), np.array(U), 3, ("x", "y"))
