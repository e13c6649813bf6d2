"""The linear-in-parameters form of the closed-loop axis model: thesis eq 6.7-6.9.

Eq 6.3 divided by ``a2`` gives, at every sample ``k`` (eq 6.7),

    x_k = alpha3 e_k - alpha1 x''_k - alpha2 x'_k + beta0 x_r''_k + beta1 x_r'_k + beta2 x_r,k - delta sign(x'_k)

with the normalized parameters of eq 6.8: ``alpha1 = 1/a2``, ``alpha2 = a1/a2``, ``alpha3 = a3/a2``,
``beta_i = b_i/a2``, ``delta = d_c/a2``, and the integrated tracking error ``e_k = int_0^t (x_r - x)``.
Stacking all samples gives ``Y = Phi theta`` (eq 6.9), ``theta = [alpha3 alpha1 alpha2 beta0 beta1 beta2 delta]``
in the column order of :data:`COLUMNS`.

Two variants of the signal processing (:class:`RegressionOptions`):

* ``RegressionOptions.thesis()``: as printed in eq 6.9 -- rectangle-rule integration
  ``e_k = Ts sum_{m<=k} (x_r,m - x_m)``, second-order central differences, ``sign`` of the raw velocity.
* the default ("improved"): trapezoidal integration, fourth-order central differences, and the same
  zero-phase low-pass prefilter applied to every signal of eq 6.7 before differentiating. Eq 6.7 is
  linear and time invariant in its signals (``sign(x')`` enters as a signal), so filtering every term
  by one filter keeps it exact while it removes the encoder noise that ``d^2/dt^2`` would amplify; and
  the friction switching signal is taken half a sample late, ``(s_k + s_{k-1})/2``, which is where a
  friction force held over each control period (zero-order hold, as in the simulator and in sampled
  controllers) is centred.

Why the thesis' LS is biased (Table 6.1: p 11.4 Hz instead of 10.8 Hz): the rectangle rule adds
``Ts/2 (x_r,k - x_k)`` to ``e_k`` relative to the trapezoid, i.e. ``alpha3 Ts/2 (x_r - x)`` to eq 6.7, a scale error
of ``a3/a2 Ts/2`` (2.6 % for Table 6.1) that moves the real pole; tested in ``tests/identification``.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

import numpy as np
from scipy.integrate import cumulative_trapezoid
from scipy.signal import butter, sosfiltfilt

from research.errors import DriveLogError, ParameterError
from research.identification._log import DriveLog

if TYPE_CHECKING:
    from research.drives import ClosedLoopModel

#: names of the columns of Phi (eq 6.9), in order; the parameter of each is in :data:`PARAMETERS`
COLUMNS = ("e", "-x''", "-x'", "x_r''", "x_r'", "x_r", "-sign(x')")
#: eq 6.8 normalized parameters, column order of Phi
PARAMETERS = ("alpha3", "alpha1", "alpha2", "beta0", "beta1", "beta2", "delta")
#: indices of theta1 = [alpha1, alpha2, alpha3] (eq 6.19, pole part) and theta2 = [beta0, beta1, beta2, delta]
POLE_COLUMNS = (1, 2, 0)
ZERO_COLUMNS = (3, 4, 5, 6)
#: largest acceptable condition number of the column-normalized regressor
MAX_CONDITION = 1e8


@dataclasses.dataclass(frozen=True)
class RegressionOptions:
    """Signal processing that builds eq 6.9 from a log.

    Attributes:
        integration: ``"trapezoid"`` or ``"rectangle"`` (eq 6.9 as printed) for ``e_k`` [mm s].
        derivative_order: accuracy order of the central differences, 2 (``numpy.gradient`` twice) or 4.
        prefilter_hz: cutoff [Hz] of the zero-phase Butterworth prefilter applied to every signal, or None.
        prefilter_order: order of that Butterworth filter (applied forward and backward).
        sign_filter_hz: cutoff [Hz] of the zero-phase low-pass on ``x`` used only to find ``sign(x')`` (robust
            to encoder noise at rest), or None for the raw velocity.
        half_sample_sign: use ``(s_k + s_{k-1})/2`` for the friction column (module docstring).
        trim: samples dropped at each end (filter and difference edge effects).
    """

    integration: str = "trapezoid"
    derivative_order: int = 4
    prefilter_hz: float | None = 60.0
    prefilter_order: int = 4
    sign_filter_hz: float | None = 20.0
    half_sample_sign: bool = True
    trim: int = 100

    def __post_init__(self):
        if self.integration not in ("trapezoid", "rectangle"):
            raise ParameterError(f"RegressionOptions.integration must be 'trapezoid' or 'rectangle', got {self.integration!r}")
        if self.derivative_order not in (2, 4):
            raise ParameterError(f"RegressionOptions.derivative_order must be 2 or 4, got {self.derivative_order!r}")
        for name in ("prefilter_hz", "sign_filter_hz"):
            v = getattr(self, name)
            if v is not None and not (np.isfinite(v) and v > 0):
                raise ParameterError(f"RegressionOptions.{name} must be None or > 0 Hz, got {v!r}")
        if self.trim < 0:
            raise ParameterError(f"RegressionOptions.trim must be >= 0, got {self.trim}")

    @staticmethod
    def thesis() -> RegressionOptions:
        """Eq 6.9 as printed: rectangle-rule ``e``, 2nd-order differences, raw ``sign``, no prefilter."""
        return RegressionOptions("rectangle", 2, None, 4, None, False, 2)


#: the default (improved) processing
DEFAULT_OPTIONS = RegressionOptions()


@dataclasses.dataclass(frozen=True, eq=False)
class Regression:
    """``Y = Phi theta`` of eq 6.9 built from a log.

    Attributes:
        Phi: ``(N', 7)`` regressor, columns :data:`COLUMNS` [mm s, mm/s^2, mm/s, mm/s^2, mm/s, mm, -].
        Y: ``(N',)`` measured (prefiltered) positions [mm].
        options: the :class:`RegressionOptions` used.
        source: the log's source.
        sample_period: ``Ts`` [s].
        column_scale: ``(7,)`` 2-norms of the columns of ``Phi``.
        condition: condition number of the column-normalized ``Phi``.
    """

    Phi: np.ndarray
    Y: np.ndarray
    options: RegressionOptions
    source: str
    sample_period: float
    column_scale: np.ndarray
    condition: float

    def loss(self, theta) -> float:
        """Eq 6.10: ``0.5 ||Y - Phi theta||^2`` [mm^2]."""
        r = self.Y - self.Phi @ np.asarray(theta, dtype=np.float64)
        return 0.5 * float(r @ r)


def _d1(y, Ts, order):
    if order == 2:
        return np.gradient(y, Ts)
    yp = np.pad(y, 2, mode="reflect", reflect_type="odd")
    return (yp[:-4] - 8 * yp[1:-3] + 8 * yp[3:-1] - yp[4:]) / (12 * Ts)


def _d2(y, Ts, order):
    if order == 2:
        return np.gradient(np.gradient(y, Ts), Ts)
    yp = np.pad(y, 2, mode="reflect", reflect_type="odd")
    return (-yp[:-4] + 16 * yp[1:-3] - 30 * yp[2:-2] + 16 * yp[3:-1] - yp[4:]) / (12 * Ts**2)


def _lowpass(y, cutoff_hz, order, Ts):
    sos = butter(order, cutoff_hz, fs=1.0 / Ts, output="sos")
    return sosfiltfilt(sos, y)


def build_regression(log: DriveLog, options: RegressionOptions = DEFAULT_OPTIONS) -> Regression:
    """Eq 6.7-6.9 from a log: numeric derivatives plus integrated tracking error.

    Args:
        log: validated :class:`DriveLog` [s, mm].
        options: :class:`RegressionOptions` (default: the improved processing, module docstring).
    Returns:
        :class:`Regression`.
    Raises:
        DriveLogError: the log is too short for the trim and the 7 parameters, or the regressor is
            rank deficient / not exciting enough (condition number above :data:`MAX_CONDITION`, the value
            and the weakest column are named).
    """
    Ts = log.sample_period
    need = 2 * options.trim + 10 * len(COLUMNS)
    if log.n_samples < need:
        raise DriveLogError(
            f"{log.source}: {log.n_samples} samples are too few to identify the 7 parameters of eq 6.3 "
            f"(need at least {need} = 2 x trim {options.trim} + 70)"
        )
    xr, x = log.reference, log.actual
    if options.integration == "trapezoid":
        e = cumulative_trapezoid(xr - x, dx=Ts, initial=0.0)
    else:
        e = Ts * np.cumsum(xr - x)
    xs = x if options.sign_filter_hz is None else _lowpass(x, options.sign_filter_hz, 4, Ts)
    s = np.sign(_d1(xs, Ts, options.derivative_order))
    if options.half_sample_sign:
        s = np.concatenate([s[:1], 0.5 * (s[1:] + s[:-1])])
    if options.prefilter_hz is not None:
        if options.prefilter_hz >= 0.5 / Ts:
            raise ParameterError(f"prefilter_hz {options.prefilter_hz} must be below the Nyquist frequency {0.5 / Ts} Hz")
        x, xr, e, s = (_lowpass(y, options.prefilter_hz, options.prefilter_order, Ts) for y in (x, xr, e, s))
    o = options.derivative_order
    Phi = np.column_stack([e, -_d2(x, Ts, o), -_d1(x, Ts, o), _d2(xr, Ts, o), _d1(xr, Ts, o), xr, -s])
    sl = slice(options.trim, log.n_samples - options.trim)
    Phi, Y = np.ascontiguousarray(Phi[sl]), np.ascontiguousarray(x[sl])
    scale = np.linalg.norm(Phi, axis=0)
    zero = np.flatnonzero(scale == 0)
    if zero.size:
        raise DriveLogError(
            f"{log.source}: the log does not excite eq 6.7: regressor column {COLUMNS[zero[0]]!r} is identically "
            "zero (condition number inf); log a motion with acceleration, velocity reversals and tracking error"
        )
    sv = np.linalg.svd(Phi / scale, compute_uv=False)
    cond = float(sv[0] / sv[-1]) if sv[-1] > 0 else float("inf")
    if not cond <= MAX_CONDITION:
        _, _, vt = np.linalg.svd(Phi / scale, full_matrices=False)
        weak = COLUMNS[int(np.argmax(np.abs(vt[-1])))]
        raise DriveLogError(
            f"{log.source}: the regressor of eq 6.9 is rank deficient (condition number {cond:.3g} > {MAX_CONDITION:.0e}; "
            f"weakest direction dominated by column {weak!r}); the log does not excite the drive enough "
            "(use the §6.5 program: random moves with trapezoidal velocity and reversals)"
        )
    return Regression(Phi, Y, options, log.source, Ts, scale, cond)


# -- parameter maps ---------------------------------------------------------------------------------
def theta_from_coefficients(a1, a2, a3, b0, b1, b2, dc) -> np.ndarray:
    """Eq 6.8: eq 6.3 coefficients -> ``theta`` in the column order :data:`PARAMETERS`."""
    return np.array([a3 / a2, 1.0 / a2, a1 / a2, b0 / a2, b1 / a2, b2 / a2, dc / a2], dtype=np.float64)


def coefficients_from_theta(theta) -> dict:
    """Inverse of eq 6.8: ``{a1, a2, a3, b0, b1, b2, dc}`` [1/s, 1/s^2, 1/s^3, -, 1/s, 1/s^2, mm/s^2]."""
    alpha3, alpha1, alpha2, beta0, beta1, beta2, delta = (float(v) for v in theta)
    a2 = 1.0 / alpha1
    return {"a1": alpha2 * a2, "a2": a2, "a3": alpha3 * a2, "b0": beta0 * a2, "b1": beta1 * a2, "b2": beta2 * a2, "dc": delta * a2}


def theta_from_model(model: ClosedLoopModel) -> np.ndarray:
    """Eq 6.8 for a :class:`ClosedLoopModel`."""
    m = model.closed_loop_model()
    return theta_from_coefficients(*(float(getattr(m, k)) for k in ("a1", "a2", "a3", "b0", "b1", "b2", "dc")))
