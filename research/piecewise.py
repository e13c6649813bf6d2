"""Piecewise polynomials in local coordinates: the exact form of FIR-filtered motion profiles.

A moving-average (FIR) filter maps a piecewise polynomial of degree d to one of degree d + 1
(Sencer 2015, eq 1-4), so a chain of n filters applied to rectangular velocity pulses gives an
exact piecewise-polynomial trajectory. This module holds that representation and the three
operations the interpolators need: antiderivative, moving average and evaluation. Everything is
written with ``jax.numpy`` so it can be jitted and differentiated with respect to the break points
(filter delays, overlap times).

Representation: breaks ``b[0] <= ... <= b[K]`` (zero-length pieces allowed) and coefficients
``c[i, m, :]`` in *ascending* powers of the local coordinate ``t - b[i]``::

    f(t) = sum_m c[i, m, :] * (t - b[i]) ** m      for b[i] <= t < b[i + 1]

Local coordinates keep every coefficient a local derivative, so nothing cancels catastrophically
on long time spans. Outside ``[b[0], b[K]]`` the function is held at its end values and all of its
derivatives are zero: motion profiles start and end at rest.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import partial

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from research._device import device_array
from research._grid_sample import GRID_SNAP, sample_grid  # noqa: F401 (GRID_SNAP: documented here, re-exported)



class PiecewisePolynomial(eqx.Module):
    """A vector-valued piecewise polynomial in local coordinates.

    Attributes:
        breaks: ``(K + 1,)`` non-decreasing break points [s].
        coeffs: ``(K, d + 1, A)`` ascending local coefficients for ``A`` output channels (axes).

    Example:
        >>> import jax.numpy as jnp
        >>> pp = PiecewisePolynomial.from_steps(jnp.array([0.0, 1.0]), jnp.array([[2.0]]))
        >>> float(pp.antiderivative()(jnp.array([0.5]))[0, 0])
        1.0
    """

    breaks: Array
    coeffs: Array

    @staticmethod
    def from_steps(breaks: Array, values: Array) -> "PiecewisePolynomial":
        """Piecewise-constant function: ``values[i]`` (shape ``(K, A)``) on ``[breaks[i], breaks[i+1])``."""
        values = jnp.asarray(values, dtype=jnp.float64)
        return PiecewisePolynomial(jnp.asarray(breaks, dtype=jnp.float64), values[:, None, :])

    @property
    def degree(self) -> int:
        return self.coeffs.shape[1] - 1

    @property
    def n_channels(self) -> int:
        return self.coeffs.shape[2]

    @property
    def start(self) -> Array:
        """First break [s] (a 0-d array)."""
        return _break(self.breaks, 0)

    @property
    def end(self) -> Array:
        """Last break [s] (a 0-d array)."""
        return _break(self.breaks, -1)

    def derivative(self, nu: int = 1) -> "PiecewisePolynomial":
        """The ``nu``-th derivative (degree drops by ``nu``; a constant if ``nu > degree``)."""
        c = self.coeffs
        for _ in range(nu):
            if c.shape[1] == 1:
                c = jnp.zeros_like(c)
                continue
            powers = jnp.arange(1, c.shape[1], dtype=c.dtype)[None, :, None]
            c = c[:, 1:, :] * powers
        return PiecewisePolynomial(self.breaks, c)

    def antiderivative(self, initial: Array | float = 0.0) -> "PiecewisePolynomial":
        """Integral from ``breaks[0]``, plus ``initial`` (scalar or ``(A,)``)."""
        c = self.coeffs
        d = c.shape[1]
        powers = jnp.arange(1, d + 1, dtype=c.dtype)[None, :, None]
        integrated = c / powers  # coefficient of (t - b)^(m + 1)
        h = jnp.diff(self.breaks)[:, None]
        hp = h[:, None, :] ** powers  # (K, d, 1)
        piece_integral = jnp.sum(integrated * hp, axis=1)  # (K, A)
        offsets = jnp.cumsum(piece_integral, axis=0) - piece_integral
        const = offsets + jnp.broadcast_to(jnp.asarray(initial, dtype=c.dtype), offsets.shape)
        return PiecewisePolynomial(self.breaks, jnp.concatenate([const[:, None, :], integrated], axis=1))

    def end_values(self) -> Array:
        """Value at ``breaks[-1]``, shape ``(A,)``."""
        h = self.breaks[-1] - self.breaks[-2]
        return _horner(self.coeffs[-1], h)

    def moving_average(self, delay: Array | float) -> "PiecewisePolynomial":
        """Output of the unity-gain FIR filter M(s) = (1 - exp(-s T)) / (s T) (Sencer 2015, eq 1).

        ``y(t) = (C(t) - C(t - T)) / T`` with ``C`` the antiderivative. Requires the function to be
        zero outside its breaks (a velocity-like signal); the result lives on
        ``[breaks[0], breaks[-1] + T]`` and has one degree more.
        """
        delay = jnp.asarray(delay, dtype=jnp.float64)
        C = self.antiderivative()
        b = C.breaks
        new_breaks, from_now = _merge_sorted(b, b + delay)
        left = new_breaks[:-1]
        # The merge says which old piece each new piece lies in: the number of breaks of C(t)
        # (of C(t - T)) at or before its start, less one. No search, no rounding ambiguity.
        piece_now = jnp.cumsum(from_now)[:-1] - 1
        piece_before = jnp.cumsum(1 - from_now)[:-1] - 1
        now = _recentred(C, piece_now, left)
        before = _recentred(C, piece_before, left - delay)
        return PiecewisePolynomial(new_breaks, (now - before) / delay)

    def __call__(self, t: Array, nu: int = 0) -> Array:
        """Evaluate the ``nu``-th derivative at times ``t`` (any shape ``S``); returns ``S + (A,)``."""
        return _evaluate(self, jnp.asarray(t, dtype=jnp.float64), (nu,))[0]

    def derivatives(self, t: Array, orders: int) -> tuple[Array, ...]:
        """Value and derivatives ``0 .. orders-1`` at times ``t``, sharing one piece search."""
        return _evaluate(self, jnp.asarray(t, dtype=jnp.float64), tuple(range(orders)))

    def sample(self, sample_period: float, n_samples: int, orders: int = 4) -> tuple[np.ndarray, ...]:
        """Values and derivatives ``0 .. orders-1`` on the grid ``breaks[0] + i * sample_period``.

        Samples are right-hand limits, and a break within :data:`GRID_SNAP` ``* sample_period`` after
        a sample counts as on it: a profile whose switching instants sit on the grid up to rounding
        (``k Ts + 1e-16``) gives the new phase's acceleration/jerk at ``t_k``, not the old phase's
        for a whole period. One O(n_samples + K) pass for all orders (the piece index walks with the
        grid, no search; :func:`research._grid_sample.sample_grid`). Returns ``orders`` NumPy arrays
        of shape ``(n_samples, A)`` (views of one ``(orders, n_samples, A)`` block).
        """
        return tuple(sample_grid(np.asarray(self.breaks), np.asarray(self.coeffs), sample_period, n_samples, orders))

    def evaluate_numpy(self, t, nu: int = 0, snap: float = 0.0) -> np.ndarray:
        """:meth:`__call__` in NumPy, for concrete arrays: no JAX compilation or dispatch, which
        is cheaper for small or one-off evaluations. ``t`` of any shape ``S``; returns ``S + (A,)``.
        A break less than ``snap`` [s] after a time counts as at it (that time takes the next piece).
        For many calls on one polynomial, build :meth:`numpy_evaluator` once."""
        return self.numpy_evaluator()(t, nu, snap)

    def numpy_evaluator(self) -> "NumpyPiecewise":
        """The same function on NumPy copies of the breaks and coefficients (see :class:`NumpyPiecewise`)."""
        return NumpyPiecewise(np.asarray(self.breaks, dtype=np.float64), np.asarray(self.coeffs, dtype=np.float64))


def _break(breaks, i: int) -> Array:
    """``breaks[i]``: indexed by JAX where traced; read in NumPy and transferred where concrete
    (a JAX index of a concrete array compiles a slice per array size: ``research._device``)."""
    if isinstance(breaks, jax.core.Tracer):
        return breaks[i]
    return device_array(np.asarray(breaks)[i])


@dataclass(frozen=True)
class NumpyPiecewise:
    """A :class:`PiecewisePolynomial` held as NumPy arrays, evaluated without JAX: for loops that
    evaluate one profile many times (golden-section refinements in :mod:`research.metrics`), where
    the per-call cost of a JAX module's attribute access dominates.

    Attributes:
        breaks: ``(K + 1,)`` [s]; coeffs: ``(K, d + 1, A)`` ascending local coefficients.
    """

    breaks: np.ndarray
    coeffs: np.ndarray

    def __call__(self, t, nu: int = 0, snap: float = 0.0) -> np.ndarray:
        """Value (``nu = 0``) or ``nu``-th derivative at ``t`` of any shape ``S``; returns ``S + (A,)``
        (arguments as :meth:`PiecewisePolynomial.evaluate_numpy`). One compiled pass over the times
        (``research._piecewise_eval``)."""
        from research._piecewise_eval import evaluate  # Numba: imported on first use

        t = np.asarray(t, dtype=np.float64)
        flat = np.ascontiguousarray(t.reshape(-1))
        K, D, A = self.coeffs.shape
        value = np.zeros((flat.size, A))
        if nu < D:
            scale = np.array([float(math.perm(m, nu)) if m >= nu else 0.0 for m in range(D)])
            evaluate(np.ascontiguousarray(self.breaks, dtype=np.float64), np.ascontiguousarray(self.coeffs, dtype=np.float64),
                     flat, int(nu), float(snap), scale, value)
        return value.reshape(t.shape + (A,))

    def realized(self) -> "NumpyPiecewise":
        """The same profile without its pieces shorter than :data:`DEGENERATE_PIECE`: each is
        dropped and the next piece starts at its start (the previous one runs on, for the last),
        a shift of at most that much time. Their continuous derivatives are the neighbours' end
        values; only the discontinuous highest one differs, for a time no motion realizes.

        Example:
            >>> import numpy as np
            >>> p = NumpyPiecewise(np.array([0.0, 1.0, 1.0 + 2e-16, 2.0]), np.array([[[0.0]], [[1e9]], [[0.0]]]))
            >>> float(np.abs(p.realized()(np.linspace(0.0, 2.0, 5))).max())
            0.0
        """
        short = np.diff(self.breaks) < DEGENERATE_PIECE
        if not short.any() or short.all():
            return self
        K = short.size
        drop_break = np.flatnonzero(short) + 1  # the next piece starts at the dropped one's start
        drop_break[drop_break == K] = K - 1  # the last piece: the previous one runs on to the end
        return NumpyPiecewise(np.delete(self.breaks, drop_break), self.coeffs[~short])


#: pieces shorter than this [s] are rounding, not motion: two breaks that coincide up to rounding
#: leave a piece of ~1e-16 s whose highest (discontinuous) derivative carries both neighbours'
#: jumps, which no motion realizes (``_fir_piece_peaks``, :meth:`NumpyPiecewise.realized`)
DEGENERATE_PIECE = 1e-12


def bucket_size(n: int, minimum: int = 4) -> int:
    """``n`` rounded up to one of 16 sizes per octave (at most 6.25 % padding), so that arrays of
    similar length share one compiled JAX function."""
    n = max(int(n), minimum)
    step = 1 << max((n - 1).bit_length() - 4, 0)
    return -(-n // step) * step


@partial(jax.jit, static_argnums=2)
def _evaluate(pp: PiecewisePolynomial, t: Array, orders: tuple[int, ...]) -> tuple[Array, ...]:
    flat = t.reshape(-1)
    K = pp.coeffs.shape[0]
    i = jnp.clip(jnp.searchsorted(pp.breaks, flat, side="right") - 1, 0, K - 1)
    tau = jnp.clip(flat, pp.breaks[0], pp.breaks[-1]) - pp.breaks[i]
    c = pp.coeffs[i]
    outside = ((flat < pp.breaks[0]) | (flat > pp.breaks[-1]))[:, None]
    out = []
    for nu in orders:
        value = _horner(PiecewisePolynomial(pp.breaks, c).derivative(nu).coeffs, tau) if nu else _horner(c, tau)
        if nu:
            value = jnp.where(outside, 0.0, value)
        out.append(value.reshape(t.shape + (pp.coeffs.shape[2],)))
    return tuple(out)


def _merge_sorted(a: Array, b: Array) -> tuple[Array, Array]:
    """Merge two sorted 1-D arrays (ties: ``a`` first). Returns the merged array and a 0/1 mask
    of the entries that came from ``a``. Two searches, cheaper than sorting the concatenation."""
    at = jnp.arange(a.shape[0]) + jnp.searchsorted(b, a, side="left")
    bt = jnp.arange(b.shape[0]) + jnp.searchsorted(a, b, side="right")
    n = a.shape[0] + b.shape[0]
    merged = jnp.zeros(n, a.dtype).at[at].set(a).at[bt].set(b)
    return merged, jnp.zeros(n, jnp.int32).at[at].set(1)


def _horner(coeffs: Array, tau: Array) -> Array:
    """Evaluate ascending coefficients ``(..., d + 1, A)`` at ``tau`` (shape ``(...)``)."""
    out = coeffs[..., -1, :]
    for m in range(coeffs.shape[-2] - 2, -1, -1):
        out = out * tau[..., None] + coeffs[..., m, :]
    return out


def taylor_shift(coeffs: Array, delta: Array) -> Array:
    """Re-centre ascending coefficients ``(N, d + 1, A)`` by ``delta`` ``(N,)``: those of ``p(delta + x)``
    from those of ``p(x)`` (repeated synthetic division, O(d^2); a zero shift returns the same
    values). NumPy arrays in, a NumPy array out; JAX otherwise (traceable)."""
    c = [coeffs[:, m, :] for m in range(coeffs.shape[1])]
    d = len(c) - 1
    dl = delta[:, None]
    for i in range(d):
        for m in range(d - 1, i - 1, -1):
            c[m] = c[m] + dl * c[m + 1]
    stack = np.stack if isinstance(coeffs, np.ndarray) and isinstance(delta, np.ndarray) else jnp.stack
    return stack(c, axis=1)


def _recentred(C: PiecewisePolynomial, piece: Array, origin: Array) -> Array:
    """Coefficients of piece ``piece`` of ``C`` re-centred at ``origin``.

    ``piece`` runs from -1 (before ``breaks[0]``, where C is zero) to K (after ``breaks[-1]``, where
    C holds its end value).
    """
    K = C.coeffs.shape[0]
    zero = jnp.zeros_like(C.coeffs[:1])
    hold = jnp.zeros_like(C.coeffs[:1]).at[0, 0, :].set(C.end_values())
    table = jnp.concatenate([zero, C.coeffs, hold], axis=0)
    table_origin = jnp.concatenate([C.breaks[:1], C.breaks[:K], C.breaks[-1:]])
    j = jnp.clip(piece + 1, 0, K + 1)
    return taylor_shift(table[j], origin - table_origin[j])
