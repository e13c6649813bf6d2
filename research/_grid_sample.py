"""One-pass sampling of a piecewise polynomial and its derivatives on a uniform grid.

The kernel behind :meth:`research.piecewise.PiecewisePolynomial.sample`. On the grid
``t_i = b_0 + i Ts`` the piece index is non-decreasing in ``i``, so one walk over the samples
locates every sample's piece (no search), scales that piece's coefficients once into the derivatives'
``m! / (m - nu)! c_m`` (a few doubles of scratch, no table over the pieces: that was 4x the
profile, 190 MB for a 77k-chord program) and evaluates the value and all requested derivatives from
them, writing the ``orders x A`` outputs of a sample together. Each order is Horner's rule on those
coefficients (the same operations, in the same order, as the per-order evaluation in
:class:`research.piecewise.NumpyPiecewise`), so the results agree to rounding.

Compiled with Numba: the loop carries the piece index from one sample to the next, which neither
NumPy nor XLA express without a per-sample gather of every coefficient (measured 270-1100 ns per
sample on this machine, benchmarks/bench_sampling.py) against the ~30 ns it costs to write the
``4 x 3`` doubles of a sample.
"""

from __future__ import annotations

import functools
import math

import numpy as np

#: breaks closer than this many sample periods after a grid instant are sampled as on it
#: (DESIGN.md: grid sampling takes right-hand limits with a 1e-9 Ts snap)
GRID_SNAP = 1e-9


def first_samples(breaks: np.ndarray, sample_period: float, n_samples: int) -> np.ndarray:
    """Index of the first grid sample at or after each interior break, less :data:`GRID_SNAP` periods.

    Args:
        breaks: ``(K + 1,)`` non-decreasing break points [s]; the grid starts at ``breaks[0]``.
        sample_period: grid period ``Ts`` [s].
        n_samples: grid length ``N``.

    Returns:
        ``(K - 1,)`` int64 indices in ``[0, N]``, non-decreasing: sample ``i`` lies in piece
        ``#{k : first[k] <= i}`` (its right-hand limit, with the snap).
    """
    rel = (breaks[1:-1] - breaks[0]) / sample_period - GRID_SNAP
    return np.clip(np.ceil(rel), 0, n_samples).astype(np.int64)


@functools.lru_cache(maxsize=None)
def _kernel(n_coeffs: int, orders: int):
    """The sampling loop for ``n_coeffs = d + 1`` coefficients and ``orders`` orders, compiled once.

    Generated with every Horner step written out, so that each sample is straight-line code (a
    generic loop over ``m`` costs about 3x more per sample, measured in bench_sampling.py)."""
    import numba  # here, not at module level: importing numba costs ~0.3 s that only sampling needs

    D = n_coeffs
    lines = [
        "def kernel(breaks, first, coeffs, sample_period, out):",
        "    K = coeffs.shape[0]",
        "    n = out.shape[1]",
        "    b0, bK = breaks[0], breaks[K]",
        f"    tab = np.zeros(({orders}, {D}, out.shape[2]))",
        "    start = 0",
        "    for p in range(K):",
        "        stop = first[p] if p < K - 1 else n",
        "        if stop <= start:",
        "            continue",
        "        bp = breaks[p]",
        "        for a in range(out.shape[2]):",
    ]
    # the piece's derivative coefficients m! / (m - nu)! c_m, once per piece (a few doubles, not a
    # (K, orders, d + 1, A) table: that was 4x the profile's size at once)
    for nu in range(min(orders, D)):
        for m in range(nu, D):
            scale = math.perm(m, nu)
            lines.append(f"            tab[{nu}, {m}, a] = coeffs[p, {m}, a]" + ("" if scale == 1 else f" * {float(scale)!r}"))
    lines += [
        "        for i in range(start, stop):",
        "            t = b0 + i * sample_period",
        "            tau = min(max(t, b0), bK) - bp",
        "            moving = t <= bK",
        "            for a in range(out.shape[2]):",
    ]
    for nu in range(orders):
        if nu >= n_coeffs:
            lines.append(f"                out[{nu}, i, a] = 0.0")
            continue
        expr = f"tab[{nu}, {n_coeffs - 1}, a]"
        for m in range(n_coeffs - 2, nu - 1, -1):
            expr = f"({expr}) * tau + tab[{nu}, {m}, a]"
        lines.append(f"                out[{nu}, i, a] = {expr}" + ("" if nu == 0 else " if moving else 0.0"))
    lines.append("        start = max(start, stop)")
    namespace: dict = {"np": np}
    exec("\n".join(lines), namespace)  # noqa: S102 - source built above from two integers
    return numba.njit(nogil=True)(namespace["kernel"])


def sample_grid(breaks, coeffs, sample_period: float, n_samples: int, orders: int = 4) -> np.ndarray:
    """Value and derivatives ``0 .. orders - 1`` on the grid ``breaks[0] + i * sample_period``.

    Samples are right-hand limits, a break within :data:`GRID_SNAP` ``* sample_period`` after a
    sample counting as on it; before ``breaks[0]`` no sample exists, after ``breaks[-1]`` the value
    is held and the derivatives are zero. O(N + K).

    Args:
        breaks: ``(K + 1,)`` non-decreasing break points [s], ``K >= 1``.
        coeffs: ``(K, d + 1, A)`` ascending local coefficients (see :mod:`research.piecewise`).
        sample_period: ``Ts`` [s], > 0.
        n_samples: grid length ``N``.
        orders: number of orders.

    Returns:
        ``(orders, N, A)`` float64 array; ``out[nu]`` is the ``nu``-th derivative.
    """
    breaks = np.ascontiguousarray(breaks, dtype=np.float64)
    coeffs = np.ascontiguousarray(coeffs, dtype=np.float64)
    out = np.empty((orders, int(n_samples), coeffs.shape[2]))
    first = first_samples(breaks, float(sample_period), int(n_samples))
    _kernel(coeffs.shape[1], int(orders))(breaks, first, coeffs, float(sample_period), out)
    return out
