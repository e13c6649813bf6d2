"""One-pass sampling of a piecewise polynomial and its derivatives on a uniform grid.

The kernel behind :meth:`research.piecewise.PiecewisePolynomial.sample`: the grid's piece indices
from the breaks (:func:`first_samples`, no search), then one compiled walk over the samples that
evaluates every order of a sample together (``research._grid_sample_kernels``: the loop, its
operations and why it is written out per coefficient count).

Compiled with Numba: the loop carries the piece index from one sample to the next, which neither
NumPy nor XLA express without a per-sample gather of every coefficient (measured 270-1100 ns per
sample on this machine, benchmarks/bench_sampling.py) against the ~30 ns it costs to write the
``4 x 3`` doubles of a sample.
"""

from __future__ import annotations

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
    from research._grid_sample_kernels import kernel  # Numba: imported on first sampling

    kernel(coeffs.shape[1], int(orders))(breaks, first, coeffs, float(sample_period), out)
    return out
