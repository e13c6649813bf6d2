"""5-axis tool paths as a B-spline in the tool pose ``(P, O)``, and the axis positions ``Q(s)`` and
their arc-length derivatives that feed-rate scheduling needs (Sencer 2009 thesis §3.3, eq 3.25-3.28).

A :class:`PoseSpline` holds one vector B-spline ``R(u) = [P(u), O(u)]`` (tool tip [mm] and tool axis,
6 components; the thesis fits its CL data with a C3 quintic B-spline, so the default degree is 5).
Its path parameter for feed scheduling is the arc length ``s`` of the tool tip (eq 3.25), computed by
Gauss-Legendre quadrature. :meth:`PoseSpline.axis_derivatives` maps poses to axis positions through
the inverse kinematics of a :class:`~research.paths.kinematics5.TableTiltingAC` machine (eq 3.21,
4.6) and returns ``Q, Q_s, Q_ss, Q_sss`` (eq 3.28) by Taylor-mode differentiation (``jax.jet``) of
the kinematics along the curve, with the chain rule from ``u`` to ``s``.

Bad geometry is refused: a cusp or a zero-length tip tangent (``|dP/du| -> 0``, where ``s`` stops
being a parameter) and a kinematic singularity (tool axis through ``a = 0``, where ``c`` is
undefined) raise :class:`~research.errors.PathError` with the parameter and tip position.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from scipy.interpolate import BSpline, make_interp_spline

from research.errors import PathError
from research.paths._arc_length import ArcLength
from research.paths.kinematics5 import FiveAxisPath, TableTiltingAC

_CHUNK = 2048  # rows per compiled kinematics call
CUSP_TURN = np.radians(30.0)  # largest tangent turn between neighbouring quadrature nodes


class AxisDerivatives(NamedTuple):
    """Axis positions and their derivatives with respect to tool-tip arc length (eq 3.28).

    Attributes:
        Q: ``(N, 5)`` ``[x, y, z, a, c]`` [mm, rad] (``c`` unwrapped along the path).
        Q_s, Q_ss, Q_sss: ``(N, 5)`` ``dQ/ds`` [mm/mm, rad/mm], ``d2Q/ds2`` [1/mm], ``d3Q/ds3`` [1/mm^2].
    """

    Q: np.ndarray
    Q_s: np.ndarray
    Q_ss: np.ndarray
    Q_sss: np.ndarray


@dataclass(frozen=True, eq=False)
class PoseSpline:
    """A B-spline ``R(u) = [P(u), O(u)]`` in tool tip ``P`` [mm] and tool axis ``O`` (eq 3.25).

    Args:
        spline: a ``scipy.interpolate.BSpline`` with 6 output components (tip xyz, axis ijk). ``O``
            need not be unit length: it is normalized before the inverse kinematics.
        name: path name.

    Raises:
        PathError: wrong shape, non-finite coefficients, a cusp / zero-length tip tangent, or a tool
            axis that vanishes.
    """

    spline: BSpline
    name: str = ""
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    def __post_init__(self):
        c = np.asarray(self.spline.c)
        if c.ndim != 2 or c.shape[1] != 6:
            raise PathError(f"PoseSpline {self.name!r}: the B-spline must have 6 components [P, O], got coefficients {c.shape}")
        if not np.all(np.isfinite(c)) or not np.all(np.isfinite(self.spline.t)):
            raise PathError(f"PoseSpline {self.name!r}: knots or control points contain NaN or inf")
        self._check_geometry()

    # -- construction -------------------------------------------------------------------------------
    @staticmethod
    def from_poses(tip, orientation, degree: int = 5, name: str = "") -> PoseSpline:
        """Interpolate poses with a B-spline of ``degree`` (default quintic, C4, as the thesis' C3
        fit), parametrized by the cumulative chord length of the tip so that ``u`` is close to ``s``.

        Args:
            tip: ``(N, 3)`` tool tips [mm]; orientation: ``(N, 3)`` tool axes (normalized here).
        Raises:
            PathError: fewer than ``degree + 1`` poses, NaN, zero-length tool axes, or two
                consecutive identical tips (a zero-length piece of tip path).
        """
        P = np.asarray(tip, dtype=np.float64)
        O = np.asarray(orientation, dtype=np.float64)
        if P.ndim != 2 or P.shape[1] != 3 or O.shape != P.shape or P.shape[0] < degree + 1:
            raise PathError(f"PoseSpline.from_poses {name!r}: need (N, 3) tips and orientations with N >= {degree + 1}, "
                            f"got {P.shape} and {O.shape}")
        if not (np.all(np.isfinite(P)) and np.all(np.isfinite(O))):
            raise PathError(f"PoseSpline.from_poses {name!r}: poses contain NaN or inf")
        norm = np.linalg.norm(O, axis=1)
        if np.any(norm < 1e-12):
            k = int(np.argmin(norm))
            raise PathError(f"PoseSpline.from_poses {name!r}: tool axis {k} has zero length")
        chord = np.linalg.norm(np.diff(P, axis=0), axis=1)
        if np.any(chord <= 1e-12 * max(chord.max(), 1.0)):
            k = int(np.argmin(chord))
            raise PathError(f"PoseSpline.from_poses {name!r}: tips {k} and {k + 1} coincide at {P[k].tolist()} mm "
                            "(zero-length tip tangent): feed is scheduled in tool-tip arc length, which must grow")
        u = np.concatenate([[0.0], np.cumsum(chord)])
        return PoseSpline(make_interp_spline(u, np.hstack([P, O / norm[:, None]]), k=degree), name)

    @staticmethod
    def from_five_axis_path(path: FiveAxisPath, degree: int = 5) -> PoseSpline:
        """Interpolate a sampled :class:`FiveAxisPath` (tip and rotary angles, eq 3.18 for ``O``)."""
        return PoseSpline.from_poses(np.asarray(path.tip), np.asarray(path.orientation), degree, path.name)

    # -- geometry -----------------------------------------------------------------------------------
    @property
    def domain(self) -> tuple[float, float]:
        k, t = self.spline.k, self.spline.t
        return float(t[k]), float(t[-k - 1])

    def _derivative(self, m: int) -> BSpline:
        if m not in self._cache:
            self._cache[m] = self.spline if m == 0 else self.spline.derivative(m)
        return self._cache[m]

    def pose(self, u, m: int = 0) -> np.ndarray:
        """``d^m R / du^m`` at parameters ``u``, ``(N, 6)``."""
        u0, u1 = self.domain
        return np.asarray(self._derivative(m)(np.clip(np.atleast_1d(np.asarray(u, dtype=np.float64)), u0, u1)))

    def _arc(self) -> ArcLength:
        """Tool-tip arc-length table: Gauss-Legendre, 8 nodes on 4 sub-intervals per knot span."""
        if "arc" not in self._cache:
            u0, u1 = self.domain
            t = self.spline.t
            self._cache["arc"] = ArcLength.build(t[(t >= u0) & (t <= u1)], self._tip_speed, order=8, subdivisions=4)
        return self._cache["arc"]

    def _tip_speed(self, u) -> np.ndarray:
        """``|dP/du|`` [mm per unit parameter]."""
        return np.linalg.norm(self.pose(u, 1)[:, :3], axis=1)

    @property
    def length(self) -> float:
        """Tool-tip arc length ``S_Sigma`` [mm] (Gauss-Legendre, 8 nodes on 4 sub-intervals per span)."""
        return self._arc().total

    def arc_length(self, u) -> np.ndarray:
        """Tip arc length ``s(u)`` [mm]."""
        return self._arc()(u)

    def parameter_at(self, s) -> np.ndarray:
        """Inverse of :meth:`arc_length`: ``u(s)`` for ``s`` in ``[0, length]`` [mm] (Newton on the
        quadrature, bracketed by the quadrature breaks; converges to ~1e-13 mm)."""
        return self._arc().inverse(s)

    def _check_geometry(self) -> None:
        """Cusp / zero-tangent check on the quadrature nodes: the tip speed ``|P_u|`` must stay
        away from zero and the tangent must not turn by more than 30 deg between neighbouring nodes
        (a spline through a cusp either stops there or turns back in a tiny loop)."""
        u = self._arc().nodes.ravel()
        d1 = self.pose(u, 1)
        speed = np.linalg.norm(d1[:, :3], axis=1)
        scale = float(np.median(speed))
        if not scale > 0:
            raise PathError(f"PoseSpline {self.name!r}: the tool tip does not move (|dP/du| = 0); feed is scheduled "
                            "in tool-tip arc length, so orientation-only motion is not supported")
        k = int(np.argmin(speed))
        if speed[k] < 1e-6 * scale:
            raise PathError(f"PoseSpline {self.name!r}: zero-length tip tangent |dP/du| = {speed[k]:.3g} at u = {u[k]:.6g} "
                            f"(tip {np.round(self.pose(u[k])[0, :3], 6).tolist()} mm): a cusp or a stop in the path; "
                            "split the path there")
        t = d1[:, :3] / speed[:, None]
        turn = np.arccos(np.clip(np.sum(t[1:] * t[:-1], axis=1), -1.0, 1.0))
        k = int(np.argmax(turn))
        if turn[k] > CUSP_TURN:
            raise PathError(f"PoseSpline {self.name!r}: the tip tangent turns by {np.degrees(turn[k]):.1f} deg between "
                            f"u = {u[k]:.6g} and {u[k + 1]:.6g} (tip {np.round(self.pose(u[k])[0, :3], 6).tolist()} mm): "
                            "a cusp or a sharp corner; split the path there or round the corner")
        o = np.linalg.norm(self.pose(u)[:, 3:], axis=1)
        if np.min(o) < 1e-9:
            raise PathError(f"PoseSpline {self.name!r}: the tool axis O(u) vanishes at u = {u[int(np.argmin(o))]:.6g}")

    # -- axis positions and derivatives -------------------------------------------------------------
    def axis_derivatives(self, machine: TableTiltingAC, s) -> AxisDerivatives:
        """``Q(s)`` and ``Q_s, Q_ss, Q_sss`` (eq 3.26, 3.28) at tip arc lengths ``s`` [mm].

        The pose derivatives in ``u`` come from the B-spline; those in ``s`` by the chain rule with
        ``u' = 1/sigma``, ``u'' = -sigma_u / sigma^3``, ``u''' = (3 sigma_u^2 - sigma sigma_uu) / sigma^5``
        (``sigma = |P_u|``); the inverse kinematics is differentiated along the curve in Taylor mode.

        Raises:
            PathError: the derivatives are not finite (the tool axis passes through ``a = 0``).
        """
        s = np.atleast_1d(np.asarray(s, dtype=np.float64))
        u = self.parameter_at(s)
        R0, R1, R2, R3 = (self.pose(u, m) for m in range(4))
        P1, P2, P3 = R1[:, :3], R2[:, :3], R3[:, :3]
        sig = np.linalg.norm(P1, axis=1)
        sig_u = np.sum(P1 * P2, axis=1) / sig
        sig_uu = (np.sum(P2 * P2, axis=1) + np.sum(P1 * P3, axis=1) - sig_u**2) / sig
        u1 = 1.0 / sig
        u2 = -sig_u / sig**3
        u3 = (3 * sig_u**2 - sig * sig_uu) / sig**5
        x1 = R1 * u1[:, None]
        x2 = R2 * (u1**2)[:, None] + R1 * u2[:, None]
        x3 = R3 * (u1**3)[:, None] + 3 * R2 * (u1 * u2)[:, None] + R1 * u3[:, None]
        out = [np.empty((s.size, 5)) for _ in range(4)]
        for i in range(0, s.size, _CHUNK):  # one compiled shape: pad every chunk to _CHUNK rows
            rows = slice(i, min(i + _CHUNK, s.size))
            n = rows.stop - rows.start
            pad = [np.pad(x[rows], ((0, _CHUNK - n), (0, 0)), mode="edge") for x in (R0, x1, x2, x3)]
            Q, (Qs, Qss, Qsss) = _kinematics_jet(machine, jnp.asarray(pad[0]), tuple(jnp.asarray(x) for x in pad[1:]))
            for dst, src in zip(out, (Q, Qs, Qss, Qsss)):
                dst[rows] = np.asarray(src)[:n]
        bad = ~np.all(np.isfinite(np.hstack(out)), axis=1)
        if bad.any():
            k = int(np.argmax(bad))
            raise PathError(f"PoseSpline {self.name!r}: axis derivatives are not finite at s = {s[k]:.6g} mm: the tool axis "
                            "passes through the kinematic singularity a = 0, where c is undefined (eq 3.21)")
        out[0][:, 4] = self._unwrap_c(s, out[0][:, 4])
        return AxisDerivatives(*out)

    def _unwrap_c(self, s: np.ndarray, c: np.ndarray) -> np.ndarray:
        """``c`` continuous along the path: a dense unwrapped reference table picks the branch."""
        if "c_ref" not in self._cache:
            grid = np.linspace(0.0, self.length, max(2001, int(self.length / 0.05)))
            R = self.pose(self.parameter_at(grid))
            c_raw = np.arctan2(R[:, 3], -R[:, 4])  # eq 3.21 (the same branch as rotary_angles)
            self._cache["c_ref"] = (grid, np.unwrap(c_raw))
        grid, ref = self._cache["c_ref"]
        guess = np.interp(s, grid, ref)
        return c + 2 * np.pi * np.round((guess - c) / (2 * np.pi))


@eqx.filter_jit
def _kinematics_jet(machine: TableTiltingAC, R0, series):
    """Inverse kinematics and its first three derivatives along the curve: nested forward-mode
    derivatives in ``t`` of ``IK(R0 + x1 t + x2 t^2/2 + x3 t^3/6)`` at ``t = 0`` (the cubic Taylor
    polynomial of the pose has the same first three derivatives as the pose itself)."""
    x1, x2, x3 = series

    def f(t):
        R = R0 + x1 * t + x2 * (t * t / 2) + x3 * (t * t * t / 6)
        return machine.inverse(R[:, :3], R[:, 3:])

    def d1(t):
        return jax.jvp(f, (t,), (jnp.ones_like(t),))[1]

    def d2(t):
        return jax.jvp(d1, (t,), (jnp.ones_like(t),))[1]

    def d3(t):
        return jax.jvp(d2, (t,), (jnp.ones_like(t),))[1]

    t0 = jnp.zeros(())
    return f(t0), (d1(t0), d2(t0), d3(t0))
