"""FIR delays from measured modes (Sencer 2015 eq 10) and their robustness to a frequency error.

Eq 10 puts a zero of the chain's spectrum (eq 9, ``prod_i |sin(w T_i / 2) / (w T_i / 2)|``) on each mode:
``T_i = k / f_r,i`` (k = 1: the first zero, the shortest delay; k = 2: the second zero, twice the
delay and cycle-time cost). One filter per mode, the longest delay first (the paper's order: T1 = 148
ms for the 6.8 Hz Y beam, T2 = 89 ms for the 11.4 Hz X beam); delegates to
:func:`research.interpolators.delays_for_modes`.

Residual vibration. A velocity step ``dv`` through the chain leaves a mode ``(wn, zeta)`` ringing with
envelope ``|dv| / w_d`` times the ratio (the ``filt`` factor of :mod:`research.experiments.fir_model`)

    R(f, zeta; T) = | prod_i (exp(lam T_i) - 1) / (lam T_i) |,   lam = -zeta wn + j wn sqrt(1 - zeta^2),

which is eq 9 at ``w = wn`` when ``zeta -> 0`` (and vanishes at eq 10's delays). ``R`` is the fraction
of the unfiltered step's vibration that the filters let through, on any path (each corner is a sum of
such steps), so :func:`robustness_table` reports it against a frequency error of the estimate: the true
mode at ``f (1 + e)`` for the delays tuned to ``f``. A path-level residual [mm] can be passed in as
``residual_fn`` (the CLI passes :func:`research.experiments.fir_model.fir_metrics`).
"""

from __future__ import annotations

import dataclasses
from typing import Callable, Sequence

import numpy as np

from research.errors import ParameterError
from research.interpolators import delays_for_modes, magnitude_response

#: frequency errors of the robustness table (issue 20): +-5, +-10, +-20 %
FREQUENCY_ERRORS = (-0.20, -0.10, -0.05, 0.0, 0.05, 0.10, 0.20)
#: residual-vibration tolerance of the robustness margin: 5 %, the "insensitivity" level of the input-shaping
#: literature (Singer and Seering 1990, J. Dyn. Sys. Meas. Control 112: the width of the frequency band
#: over which the residual stays below 5 % of the unshaped one)
MARGIN_TOLERANCE = 0.05


@dataclasses.dataclass(frozen=True)
class TunedDelays:
    """Delays for a set of modes.

    Attributes:
        delays_s: ``(n,)`` FIR delays ``T_i`` [s], longest first.
        frequencies_hz, dampings: the modes each delay was placed on (same order).
        axes: the axis of each mode.
        k: eq 10 ripple index of each delay.
    """

    delays_s: tuple[float, ...]
    frequencies_hz: tuple[float, ...]
    dampings: tuple[float, ...]
    axes: tuple[str, ...]
    k: tuple[int, ...]

    @property
    def total_delay_s(self) -> float:
        """``T_d = sum T_i`` [s] (eq 6): what the chain adds to every move."""
        return float(sum(self.delays_s))


def tune_delays(modes: Sequence, k: int | Sequence[int] = 1) -> TunedDelays:
    """Eq 10 delays for ``modes`` (objects with ``axis``, ``frequency_hz``, ``damping``), longest first.

    Raises:
        ParameterError: no modes, a non-positive frequency, a bad ``k`` (from ``delays_for_modes``).
    """
    modes = list(modes)
    if not modes:
        raise ParameterError("tune_delays needs at least one mode")
    kk = np.broadcast_to(np.asarray(k), (len(modes),))
    d = delays_for_modes([m.frequency_hz for m in modes], kk)
    order = np.argsort(-d, kind="stable")
    return TunedDelays(delays_s=tuple(float(d[i]) for i in order),
                       frequencies_hz=tuple(float(modes[i].frequency_hz) for i in order),
                       dampings=tuple(float(modes[i].damping) for i in order),
                       axes=tuple(modes[i].axis for i in order), k=tuple(int(kk[i]) for i in order))


def residual_ratio(frequency_hz, damping, delays_s) -> np.ndarray:
    """``R(f, zeta; T)`` of the module docstring [-]: vibration left per velocity step, relative to no filter."""
    f = np.atleast_1d(np.asarray(frequency_hz, dtype=np.float64))
    z = np.broadcast_to(np.asarray(damping, dtype=np.float64), f.shape)
    T = np.asarray(delays_s, dtype=np.float64)
    if not (np.all(f > 0) and np.all((z >= 0) & (z < 1)) and T.ndim == 1 and T.size and np.all(T > 0)):
        raise ParameterError(f"residual_ratio needs f > 0 Hz, 0 <= zeta < 1 and delays > 0 s; got {f}, {z}, {T}")
    wn = 2 * np.pi * f
    lam = (-z * wn + 1j * wn * np.sqrt(1 - z**2))[:, None]
    return np.abs(np.prod(np.expm1(lam * T[None, :]) / (lam * T[None, :]), axis=1))


def robustness_table(tuned: TunedDelays, errors: Sequence[float] = FREQUENCY_ERRORS,
                     residual_fn: Callable[[int, float], float] | None = None) -> list[dict]:
    """Residual vibration when each mode's true frequency is ``f (1 + e)`` for the delays tuned to ``f``.

    Args:
        tuned: the delays and the modes they were tuned to.
        errors: relative frequency errors ``e`` (> -1).
        residual_fn: optional ``(mode index, true frequency [Hz]) -> residual`` (e.g. a path's residual
            vibration [mm]), reported as ``"path_residual"``.
    Returns:
        One row per (mode, error): ``axis``, ``frequency_hz`` (estimate), ``error``, ``true_hz``,
        ``ratio`` (``R`` with damping), ``eq9`` (``|M(j 2 pi f_true)|``, undamped) and optionally
        ``path_residual``.
    """
    rows = []
    for i, (ax, f, z) in enumerate(zip(tuned.axes, tuned.frequencies_hz, tuned.dampings)):
        for e in errors:
            if not e > -1:
                raise ParameterError(f"frequency errors must be > -1 (relative), got {e!r}")
            ft = f * (1 + e)
            row = {"axis": ax, "frequency_hz": f, "error": float(e), "true_hz": ft,
                   "ratio": float(residual_ratio(ft, z, tuned.delays_s)[0]),
                   "eq9": float(magnitude_response(np.array([2 * np.pi * ft]), np.asarray(tuned.delays_s))[0])}
            if residual_fn is not None:
                row["path_residual"] = float(residual_fn(i, ft))
            rows.append(row)
    return rows


def format_robustness(rows: list[dict]) -> str:
    """The robustness table as text (one line per mode and error)."""
    path = "path_residual" in rows[0] if rows else False
    head = f"{'axis':>4} {'f est [Hz]':>10} {'error':>6} {'f true [Hz]':>11} {'R (damped)':>11} {'|eq 9|':>9}"
    head += f" {'residual [um]':>13}" if path else ""
    lines = [head]
    for r in rows:
        line = (f"{r['axis']:>4} {r['frequency_hz']:10.3f} {r['error'] * 100:+5.0f}% {r['true_hz']:11.3f} "
                f"{r['ratio']:11.2e} {r['eq9']:9.2e}")
        if path:
            line += f" {r['path_residual'] * 1e3:13.3f}"
        lines.append(line)
    return "\n".join(lines)


def robustness_margin(tuned: TunedDelays, tolerance: float = MARGIN_TOLERANCE, span: float = 0.5,
                      points: int = 2001) -> list[dict]:
    """The frequency-error interval around 0 in which each mode's ratio ``R`` stays <= ``tolerance``.

    Scans ``e`` on ``points`` values over ``[-span, span]`` (resolution ``2 span / (points - 1)``) and
    returns, per mode, ``{"axis", "frequency_hz", "low", "high", "ratio_at_estimate"}``: ``low < 0 < high``
    bound the contiguous run containing ``e = 0`` (``None`` where it reaches the scan's end, so the margin
    is wider than ``span``; both ``None`` and ``ratio_at_estimate > tolerance`` when even the estimate is
    above the tolerance).
    """
    if not (0 < tolerance < 1 and 0 < span < 1 and points >= 3):
        raise ParameterError(f"robustness_margin needs 0 < tolerance < 1, 0 < span < 1, points >= 3; got "
                             f"{tolerance!r}, {span!r}, {points!r}")
    e = np.linspace(-span, span, points)
    i0 = int(np.argmin(np.abs(e)))
    out = []
    for ax, f, z in zip(tuned.axes, tuned.frequencies_hz, tuned.dampings):
        r = residual_ratio(f * (1 + e), z, tuned.delays_s)
        row = {"axis": ax, "frequency_hz": f, "ratio_at_estimate": float(residual_ratio(f, z, tuned.delays_s)[0]),
               "low": None, "high": None}
        if r[i0] <= tolerance:
            above = np.flatnonzero(r > tolerance)
            lo, hi = above[above < i0], above[above > i0]
            row["low"] = float(e[lo[-1] + 1]) if lo.size else None
            row["high"] = float(e[hi[0] - 1]) if hi.size else None
        out.append(row)
    return out
