"""`Trajectory`: the one type every interpolator returns and every consumer takes.

Sampled axis positions and their first three time derivatives on a uniform grid with the
interpolation period ``Ts``, plus the exact duration of the motion and, where the producer has one,
the exact (analytic) position profile. Arrays follow the package convention: time along axis 0,
axes along axis 1, shape ``(N, n_axes)``. Units: s, mm, mm/s, mm/s^2, mm/s^3.

A ``Trajectory`` is an immutable ``equinox.Module`` (a JAX pytree), so drive simulations can take it
through ``jit``/``vmap``/``grad``. Input checks run only on concrete arrays.
"""

from __future__ import annotations

import contextvars
from pathlib import Path

import equinox as eqx
import jax
import numpy as np
from jax import Array
from scipy.interpolate import CubicHermiteSpline

from research._device import device_array
from research.errors import ParameterError
from research.piecewise import PiecewisePolynomial

# set while from_piecewise wraps its own samples: their checks cannot fail (see from_piecewise)
_SAMPLED_FROM_PROFILE = contextvars.ContextVar("trajectory_sampled_from_profile", default=False)


class Trajectory(eqx.Module):
    """Sampled multi-axis motion.

    Attributes:
        t: ``(N,)`` strictly increasing sample times [s], ``t[0] = 0`` for interpolator output.
        q, v, a, j: ``(N, A)`` position [mm], velocity [mm/s], acceleration [mm/s^2], jerk [mm/s^3].
        duration: exact motion time [s] (the cycle time); may end between two samples.
        exact: analytic position profile when the producer has one (``None`` otherwise).
        axes: axis names, e.g. ``("x", "y")``.
        sample_period: interpolation period ``Ts`` [s].

    Example:
        >>> import numpy as np
        >>> tr = Trajectory.from_positions(np.arange(5) * 1e-3, np.arange(5.0)[:, None], axes=("x",))
        >>> tr.n_axes, float(tr.v[2, 0])
        (1, 1000.0)
    """

    t: Array
    q: Array
    v: Array
    a: Array
    j: Array
    duration: Array
    exact: PiecewisePolynomial | None = None
    axes: tuple[str, ...] = eqx.field(static=True, default=("x", "y"))
    sample_period: float = eqx.field(static=True, default=1e-3)

    def __check_init__(self):
        if _SAMPLED_FROM_PROFILE.get():
            return
        if any(isinstance(x, jax.core.Tracer) for x in (self.t, self.q)):
            return
        t = np.asarray(self.t)
        if t.ndim != 1 or t.size < 1:
            raise ParameterError(f"Trajectory.t must be a non-empty 1-D array, got shape {t.shape}")
        if t.size > 1 and not np.all(np.diff(t) > 0):
            k = int(np.argmin(np.diff(t) > 0))
            raise ParameterError(f"Trajectory.t must be strictly increasing; t[{k + 1}] <= t[{k}]")
        for name in ("q", "v", "a", "j"):
            x = np.asarray(getattr(self, name))
            if x.shape != (t.size, len(self.axes)):
                raise ParameterError(
                    f"Trajectory.{name} has shape {x.shape}; expected (N, A) = {(t.size, len(self.axes))} "
                    f"for axes {self.axes}"
                )
            bad = ~np.isfinite(x)
            if bad.any():
                i, k = map(int, np.argwhere(bad)[0])
                raise ParameterError(f"Trajectory.{name} is not finite at sample {i}, axis {self.axes[k]!r}")
        if not self.sample_period > 0:
            raise ParameterError(f"Trajectory.sample_period must be > 0 s, got {self.sample_period}")

    # -- construction ------------------------------------------------------------------------
    @staticmethod
    def from_piecewise(
        position: PiecewisePolynomial, sample_period: float, axes: tuple[str, ...]
    ) -> "Trajectory":
        """Sample an exact position profile at ``Ts`` from its start until it has ended.

        The grid is ``0, Ts, 2 Ts, ...`` up to the first sample at or after the end of the motion,
        so the last sample is at rest on the end point; ``duration`` keeps the exact end time.
        """
        if not (np.isfinite(sample_period) and sample_period > 0):
            raise ParameterError(f"Trajectory.from_piecewise: sample_period must be finite and > 0 s, got {sample_period!r}")
        breaks, coeffs = np.asarray(position.breaks), np.asarray(position.coeffs)
        if coeffs.shape[2] != len(axes):
            raise ParameterError(f"Trajectory.from_piecewise: profile has {coeffs.shape[2]} channels, axes {tuple(axes)}")
        # O(K) checks on the profile instead of O(N) checks on its samples: finite breaks and
        # coefficients give finite samples, and the grid i * Ts is increasing by construction
        for name, x in (("breaks", breaks), ("coeffs", coeffs)):
            bad = ~np.isfinite(x)
            if bad.any():
                raise ParameterError(f"Trajectory.from_piecewise: profile {name} not finite at index {tuple(map(int, np.argwhere(bad)[0]))}")
        duration = position.end - position.start
        n = int(np.ceil(float(breaks[-1] - breaks[0]) / sample_period - 1e-9)) + 1
        q, v, a, j = position.sample(sample_period, n, orders=4)
        # in NumPy and handed over by transfer (research._device): JAX ops on the profile's arrays
        # compiled once per profile size (1.6 MB kept and 37 ms per sampled plan of a sweep)
        shifted = PiecewisePolynomial(device_array(breaks - breaks[0]), device_array(coeffs))
        t = np.arange(n) * sample_period
        token = _SAMPLED_FROM_PROFILE.set(True)
        try:
            return Trajectory(t, q, v, a, j, duration, shifted, tuple(axes), float(sample_period))
        finally:
            _SAMPLED_FROM_PROFILE.reset(token)

    @staticmethod
    def from_positions(t, q, axes: tuple[str, ...], duration: float | None = None) -> "Trajectory":
        """Wrap sampled positions (e.g. a log); derivatives by second-order finite differences
        (``numpy.gradient``), so they are approximate. ``t`` must be uniformly sampled."""
        t = np.asarray(t, dtype=np.float64)
        q = np.asarray(q, dtype=np.float64)
        if q.ndim == 1:
            q = q[:, None]
        if t.size < 3:
            raise ParameterError(f"Trajectory.from_positions needs at least 3 samples, got {t.size}")
        dt = np.diff(t)
        if not np.all(dt > 0):
            raise ParameterError(f"Trajectory.from_positions: t must be strictly increasing (index {int(np.argmin(dt > 0)) + 1})")
        Ts = float(np.median(dt))
        if np.max(np.abs(dt - Ts)) > 1e-6 * Ts:
            raise ParameterError("Trajectory.from_positions: t must be uniformly sampled; resample the data first")
        v = np.gradient(q, Ts, axis=0)
        a = np.gradient(v, Ts, axis=0)
        j = np.gradient(a, Ts, axis=0)
        dur = float(t[-1] - t[0]) if duration is None else float(duration)
        return Trajectory(t, q, v, a, j, np.float64(dur), None, tuple(axes), Ts)

    # -- views -------------------------------------------------------------------------------
    @property
    def n_samples(self) -> int:
        return int(self.t.shape[0])

    @property
    def n_axes(self) -> int:
        return len(self.axes)

    @property
    def feed(self) -> Array:
        """Path speed ``||v||`` [mm/s], shape ``(N,)``."""
        return np.linalg.norm(np.asarray(self.v), axis=1)

    def axis(self, name: str) -> int:
        """Column index of axis ``name``."""
        try:
            return self.axes.index(name)
        except ValueError:
            raise ParameterError(f"no axis {name!r} in trajectory with axes {self.axes}") from None

    # -- exact evaluation and resampling --------------------------------------------------------
    def evaluate(self, t, nu: int = 0) -> np.ndarray:
        """Position (``nu = 0``) or its ``nu``-th derivative at arbitrary times ``t`` [s].

        Exact when the producer stored an analytic profile; otherwise a cubic Hermite interpolant of
        the sampled ``(x, x')`` pair for the requested order (accurate to O(Ts^4) for smooth motion).
        """
        return self.evaluator()(t, nu)

    def evaluator(self):
        """``f(t, nu=0)`` equal to :meth:`evaluate`, with its set-up done once: for callers that
        evaluate the same trajectory many times (e.g. :mod:`research.metrics`)."""
        if self.exact is not None:
            return self.exact.numpy_evaluator()
        return self._sampled

    def _sampled(self, t, nu: int = 0) -> np.ndarray:
        """Cubic Hermite interpolation of the samples (no exact profile)."""
        t = np.asarray(t, dtype=np.float64)
        if nu > 2:
            raise ParameterError("without an exact profile, derivatives above 2 (jerk) are not interpolated")
        pairs = (self.q, self.v, self.a, self.j)
        spline = CubicHermiteSpline(np.asarray(self.t), np.asarray(pairs[nu]), np.asarray(pairs[nu + 1]), axis=0)
        return spline(np.clip(t, self.t[0], self.t[-1]))

    def resample(self, sample_period: float) -> "Trajectory":
        """The same motion on a new grid with period ``sample_period`` [s] (see :meth:`evaluate`)."""
        if not sample_period > 0:
            raise ParameterError(f"sample_period must be > 0 s, got {sample_period}")
        t0, t1 = float(self.t[0]), float(self.t[-1])
        t = t0 + np.arange(int(np.floor((t1 - t0) / sample_period + 1e-9)) + 1) * sample_period
        if self.exact is not None:
            q, v, a, j = (self.evaluate(t, nu) for nu in range(4))
        else:
            q, v, a = (self.evaluate(t, nu) for nu in range(3))
            j = np.gradient(a, sample_period, axis=0)
        return Trajectory(t, q, v, a, j, self.duration, self.exact, self.axes, float(sample_period))

    # -- storage -----------------------------------------------------------------------------
    def save(self, path: str | Path) -> None:
        """Write the samples (and the exact profile, if any) to an ``.npz`` file."""
        extra = {} if self.exact is None else {"breaks": self.exact.breaks, "coeffs": self.exact.coeffs}
        np.savez(
            path, t=self.t, q=self.q, v=self.v, a=self.a, j=self.j, duration=self.duration,
            axes=np.array(self.axes), sample_period=self.sample_period, **extra,
        )

    @staticmethod
    def load(path: str | Path) -> "Trajectory":
        """Read a file written by :meth:`save`."""
        with np.load(path) as z:
            exact = PiecewisePolynomial(z["breaks"], z["coeffs"]) if "breaks" in z else None
            return Trajectory(
                z["t"], z["q"], z["v"], z["a"], z["j"], z["duration"][()], exact,
                tuple(str(a) for a in z["axes"]), float(z["sample_period"]),
            )
