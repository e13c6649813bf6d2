"""Overlap time ``T_k`` between consecutive G01 blocks from the cornering tolerance (Sencer 2015 §3).

Setting (one corner, both blocks long): the input velocity is ``F- u-`` until the block ends, zero
for the gap ``T_d - T_k``, then ``F+ u+``. The filter output is the input position averaged with
the chain's symmetric impulse response ``h``. Centring the averaging window on the gap gives the
point of the rounded corner on the bisector; its distance to the corner vertex is

    epsilon = |F+ u+ - F- u-| * H2(T_k / 2),      H2(r) = integral_0^r (r - tau) h(tau) d tau.

For equal feeds ``|F+ u+ - F- u-| = 2 F sin(beta / 2)`` with ``beta`` the turning angle, and this
reproduces eq 13 (one filter) and both branches of eq 14 (two filters) exactly; for three or more
filters ``H2`` is inverted numerically (optimistix bisection, differentiable by the implicit
function theorem).

Unequal feeds ``F- != F+`` (a feed schedule, the limits' factors, the look-ahead's window feeds):
the point at the centred window, ``|F+ u+ - F- u-| H2(T_k / 2)`` from the vertex, is on the rounded
corner, so the corner's distance to its vertex is at most that; but its tangential part
``cos(beta / 2) |F+ - F-| H2`` is a lag along the path, not an error, and on a collinear feed step
it would dwell where the output never leaves the line. A second bound: with ``t`` the bisector's
direction, ``n`` its normal, ``A(t)`` and ``B(t)`` the kernel's first moments of the input's
distance to the vertex before and after it (each ``H2(T_k / 2)`` at the centred window; ``A``
falls and ``B`` rises as the window moves on), the output is ``c (F+ B - F- A) t - s (F- A + F+
B) n`` (``s, c = sin, cos(beta / 2)``). Where its ``t`` part is 0 (``F- A = F+ B``, an instant
that exists since the part goes from ``-`` to ``+``) its distance to the vertex is ``2 s F- A =
2 s F+ B``, at most ``2 s max(F-, F+) H2`` (``A <= H2`` after the centre, ``B <= H2`` before it);
and its distance to the two lines at every instant is ``2 s c min(F- A, F+ B)``, at most the same.
:func:`corner_speed_change` takes the smaller of the two bounds' speeds, each equal to eq 13/14's
``2 F sin(beta / 2)`` at equal feeds. On bench_cam's 10^4-chord CAM file the mirror planner's
dwells at feed steps on 1-5 degree turns cost 0.53 s of 44.73 s with the first bound alone, none
with both (benchmarks/README.md).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import optimistix as optx
from jax import Array

from research.interpolators._fir_chain import kernel_second_integral


def cornering_error(overlap: Array, speed_change: Array, delays: Array) -> Array:
    """Corner error ``epsilon`` [mm] for overlap ``T_k`` [s] and ``|F+ u+ - F- u-|`` [mm/s].

    One filter (eq 13): ``sqrt(F^2 T_k^4 (1 - cos beta) / (32 T_1^2))``; in general
    ``|dF| H2(T_k / 2)`` (module docstring). Valid for ``0 <= T_k <= T_d``.
    """
    return jnp.asarray(speed_change) * kernel_second_integral(0.5 * jnp.asarray(overlap), delays)


def corner_speed_change(f_out: Array, f_in: Array, t_out: Array, t_in: Array, turn: bool) -> Array:
    """The speed change eq 13/14 rounds a corner for (module docstring: unequal feeds).

    Args:
        f_out, f_in: ``(K,)`` feeds [mm/s] leaving the block before each corner and entering the
            block after it.
        t_out, t_in: ``(K, d)`` unit tangents at those two ends.
        turn: False: the velocity step ``|f_in t_in - f_out t_out|`` (``plan_fir``'s
            ``corner_speed="step"``); True: the smaller of it and the turn at the larger feed,
            ``max(f_out, f_in) |t_in - t_out|`` (``corner_speed="turn"``).

    Returns:
        ``(K,)`` [mm/s]; ``2 F sin(beta / 2)`` at equal feeds either way; differentiable (finite
        gradients at 0).
    """
    f_out, f_in = jnp.asarray(f_out), jnp.asarray(f_in)
    change = _safe_norm(f_in[..., None] * t_in - f_out[..., None] * t_out)
    if not turn:
        return change
    return jnp.minimum(change, jnp.maximum(f_out, f_in) * _safe_norm(t_in - t_out))


def _safe_norm(x: Array) -> Array:
    """Euclidean norm along the last axis with a finite gradient at 0."""
    s = jnp.sum(x * x, axis=-1)
    positive = s > 0
    return jnp.where(positive, jnp.sqrt(jnp.where(positive, s, 1.0)), 0.0)


def overlap_time(tolerance: Array, speed_change: Array, delays: Array) -> Array:
    """Largest overlap ``T_k`` in ``[0, T_d]`` [s] whose corner error is at most ``tolerance`` [mm].

    Args:
        tolerance: cornering tolerance ``epsilon`` [mm], >= 0 (scalar or per corner).
        speed_change: ``|F+ u+ - F- u-|`` [mm/s] per corner (``2 F sin(beta/2)`` for equal feeds).
        delays: filter delays ``T_i`` [s].

    Returns:
        Overlap times [s], per corner. ``T_d`` (full overlap) where even full overlap stays within
        tolerance, e.g. collinear segments.

    Closed forms: one filter, eq 13 solved for ``T_k``: ``T_k = (32 T_1^2 eps^2 / (F^2 (1 - cos beta)))^(1/4)``;
    two filters, eq 14 (``T_1 >= T_2``)::

        T_k = (24 T_1 T_2 eps / (F sin(beta/2)))^(1/3)            for 0 <= T_k <= 2 T_2
        T_k = T_2 + sqrt(4 T_1 eps / (F sin(beta/2)) - T_2^2 / 3)  for 2 T_2 <= T_k <= T_1 + T_2

    Three or more filters: ``H2(T_k / 2) = eps / |dF|`` by bisection.
    """
    delays = jnp.sort(jnp.asarray(delays, dtype=jnp.float64))[::-1]  # T_1 >= T_2 >= ...
    n = delays.shape[0]
    Td = jnp.sum(delays)
    dF = jnp.asarray(speed_change, dtype=jnp.float64)
    tol = jnp.broadcast_to(jnp.asarray(tolerance, dtype=jnp.float64), dF.shape)
    turning = dF > 0
    # target H2(T_k / 2); capped at the full-overlap value so every branch stays in its domain
    h_full = kernel_second_integral(0.5 * Td, delays)
    h = jnp.minimum(tol / jnp.where(turning, dF, 1.0), h_full)
    if n == 1:
        Tk = jnp.sqrt(8.0 * delays[0] * h)  # eq 13: eps = |dF| T_k^2 / (8 T_1)
    elif n == 2:
        T1, T2 = delays[0], delays[1]
        first = jnp.cbrt(48.0 * T1 * T2 * h)  # eq 14, first branch
        in_first = h <= T2**2 / (6.0 * T1)
        radicand = jnp.where(in_first, 1.0, 8.0 * T1 * h - T2**2 / 3.0)  # no NaN gradient off-branch
        second = T2 + jnp.sqrt(radicand)  # eq 14, second branch
        Tk = jnp.where(in_first, first, second)
    else:
        # a zero target (zero tolerance) has its root on the bracket's end: T_k = 0 without a search
        safe = jnp.where(h > 0, h, 0.5 * h_full)
        Tk = 2.0 * jax.vmap(lambda target: _invert_h2(target, delays))(jnp.ravel(safe)).reshape(h.shape)
        Tk = jnp.where(h > 0, Tk, 0.0)
    return jnp.where(turning & (h < h_full), jnp.clip(Tk, 0.0, Td), Td)


def _invert_h2(target: Array, delays: Array) -> Array:
    """``r`` in ``[0, T_d / 2]`` with ``H2(r) = target`` (H2 is increasing: H2' = H1 >= 0)."""
    half = 0.5 * jnp.sum(delays)
    # keep the root inside the bracket up to rounding of H2(T_d / 2)
    target = jnp.clip(target, 0.0, kernel_second_integral(half, delays))

    def residual(r, args):
        return kernel_second_integral(r, delays) - target

    solver = optx.Bisection(rtol=1e-13, atol=1e-15, flip="detect", expand_if_necessary=False)
    sol = optx.root_find(residual, solver, half * 0.5, options=dict(lower=0.0, upper=half), throw=False, max_steps=256)
    return sol.value
