"""Closed-form, differentiable FIR-cornering model for sweeps (the ``jax.vmap`` fast path).

For a polyline run at one feed ``F`` through a chain of FIR filters with overlap from the cornering
tolerance (Sencer 2015 §3), three figures of merit are closed-form in ``(T_i, eps, F)`` and in the
structural mode's ``(f, zeta)``:

* cycle time ``sum_k T_v,k + T_d + sum_k (T_d - T_k)`` with ``T_v,k = L_k / F`` (eq 5, 11) and
  ``T_k`` from eq 13/14 (:func:`~research.interpolators.overlap_time`);
* corner error ``|dF| H2(T_k / 2)`` (eq 13/14, :func:`~research.interpolators.cornering_error`):
  ``eps`` itself unless even full overlap stays inside the tolerance;
* residual vibration of a base-excited mode ``d'' + 2 zeta wn d' + wn^2 d = -x''`` (the beams of §4;
  the closed form is :func:`research.drives.fir_pulse_residual`)
  once the motion has stopped. The filtered acceleration is ``a(t) = sum_m dv_m h(t - t_m)`` (pulse
  edges ``t_m``, velocity jumps ``dv_m``, chain impulse response ``h``), so the free vibration left
  at the end ``t_e = t_last + T_d`` has the complex amplitude

      B = sum_m dv_m exp(lam (t_last - t_m)) prod_i (exp(lam T_i) - 1) / (lam T_i),
      lam = -zeta wn + j wn sqrt(1 - zeta^2),

  and envelope ``|B| / w_d`` [mm]. With ``zeta -> 0`` the product is eq 8 at ``w = wn``: it vanishes
  when ``T_i = k / f`` (eq 10), which is why the paper's delays leave the beams still.

The formulas hold exactly when every block is at least as long as the filter (``T_v,k >= T_d``, the
paper's setting); :func:`fir_metrics` returns that flag as ``exact`` so a sweep can send the other
points to :func:`~research.interpolators.plan_fir` (verified overlap) instead.

Example:
    >>> import jax.numpy as jnp
    >>> from research.paths import named_path
    >>> m = fir_metrics(jnp.asarray(named_path("diamond").points), 250.0, jnp.array([0.148, 0.089]), 0.5,
    ...                 jnp.array([11.4, 6.8]), jnp.array([0.02, 0.02]), axes=(0, 1))
    >>> from research.interpolators import plan_fir
    >>> plan = plan_fir(named_path("diamond"), 250.0, [0.148, 0.089], 0.5)  # the verified planner
    >>> abs(float(m["cycle_time"]) - float(plan.cycle_time)) < 1e-9, abs(float(m["max_corner_error"]) - 0.5) < 1e-9
    (True, True)
    >>> bool(m["exact"])
    True
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from jax import Array

from research.drives import fir_pulse_residual
from research.interpolators import cornering_error, overlap_time

#: differentiable inputs of :func:`fir_metrics`, in the order of :func:`sensitivities`' columns
INPUTS = ("feed", "delays", "tolerance", "mode_hz", "mode_damping")
#: outputs that are scalars per point (units: s, mm, mm, mm)
SCALARS = ("cycle_time", "max_corner_error", "residual_vibration")


def fir_metrics(points: Array, feed, delays: Array, tolerance, mode_hz: Array, mode_damping: Array,
                *, axes: tuple[int, ...]) -> dict[str, Array]:
    """Cycle time, corner errors and residual vibration of FIR overlap on a polyline.

    Args:
        points: ``(M + 1, d)`` polyline vertices [mm] (no zero-length segments).
        feed: ``F`` [mm/s], one for all blocks.
        delays: ``(n,)`` FIR delays ``T_i`` [s].
        tolerance: cornering tolerance ``eps`` [mm].
        mode_hz, mode_damping: ``(K,)`` structural modes [Hz, -] (``K`` may be 0).
        axes: static, the axis index (into ``d``) that excites each mode.

    Returns:
        ``cycle_time`` [s], ``corner_errors`` ``(M - 1,)`` [mm], ``max_corner_error`` [mm],
        ``overlaps`` ``(M - 1,)`` [s], ``residual`` ``(K,)`` [mm] (vibration envelope at the end
        of motion, per mode), ``residual_vibration`` [mm] (their max; 0 without modes) and
        ``exact`` (every block at least ``T_d`` long: the closed forms are the exact profile's).
    """
    points = jnp.asarray(points, dtype=jnp.float64)
    delays = jnp.asarray(delays, dtype=jnp.float64)
    seg = points[1:] - points[:-1]
    lengths = jnp.sqrt(jnp.sum(seg * seg, axis=1))
    u = seg / lengths[:, None]
    Td = jnp.sum(delays)
    pulse = lengths / feed  # T_v,k (eq 5)
    dF = feed * jnp.sqrt(jnp.sum((u[1:] - u[:-1]) ** 2, axis=1))  # |F u+ - F u-| = 2 F sin(beta / 2)
    overlaps = overlap_time(tolerance, dF, delays)
    corners = cornering_error(overlaps, dF, delays)
    gaps = Td - overlaps
    starts = jnp.concatenate([jnp.zeros(1), jnp.cumsum(pulse[:-1] + gaps)])
    ends = starts + pulse
    last = ends[-1]
    out = {
        "cycle_time": last + Td,
        "corner_errors": corners,
        "max_corner_error": jnp.max(corners, initial=0.0),
        "overlaps": overlaps,
        "exact": jnp.all(pulse >= Td),
    }
    hz = jnp.asarray(mode_hz, dtype=jnp.float64)
    steps = feed * u[:, jnp.asarray(axes, dtype=int)].T if hz.shape[0] else jnp.zeros((0, u.shape[0]))
    residual = fir_pulse_residual(steps, starts, ends, last, delays, hz, jnp.asarray(mode_damping, dtype=jnp.float64))
    out["residual"] = residual
    out["residual_vibration"] = jnp.max(residual, initial=0.0)
    return out


def sensitivities(points: Array, feed, delays, tolerance, mode_hz, mode_damping, *, axes) -> dict[str, Array]:
    """Forward-mode derivatives of :data:`SCALARS` with respect to feed, each delay and tolerance.

    Returns:
        ``{"d_<metric>/d_<input>": value}`` with inputs ``F`` [mm/s], ``T1`` .. ``Tn`` [s] and
        ``eps`` [mm], e.g. ``"d_cycle_time/d_T1"`` [s/s]. Example: at the paper's point on the
        diamond ``d_max_corner_error/d_eps = 1`` (the error sits on the tolerance).
    """
    delays = jnp.asarray(delays, dtype=jnp.float64)
    x = jnp.concatenate([jnp.atleast_1d(jnp.asarray(feed, dtype=jnp.float64)), delays,
                         jnp.atleast_1d(jnp.asarray(tolerance, dtype=jnp.float64))])
    n = delays.shape[0]

    def f(x):
        m = fir_metrics(points, x[0], x[1:1 + n], x[1 + n], mode_hz, mode_damping, axes=axes)
        return jnp.stack([m[k] for k in SCALARS])

    jac = jax.jacfwd(f)(x)  # (3, 2 + n)
    names = ["F"] + [f"T{i + 1}" for i in range(n)] + ["eps"]
    return {f"d_{m}/d_{p}": jac[i, j] for i, m in enumerate(SCALARS) for j, p in enumerate(names)}
