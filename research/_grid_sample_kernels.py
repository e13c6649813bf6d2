"""The compiled loop of :func:`research._grid_sample.sample_grid`, one form per coefficient count.

On the grid ``t_i = b_0 + i Ts`` the piece index is non-decreasing in ``i``, so one walk over the
samples locates every sample's piece (no search), scales that piece's coefficients once into the
derivatives' ``m! / (m - nu)! c_m`` (a few doubles of scratch, no table over the pieces: that was
4x the profile, 190 MB for a 77k-chord program) and evaluates the value and all four orders from
them, writing the ``4 x A`` outputs of a sample together. Each order is Horner's rule on those
coefficients (the same operations, in the same order, as the per-order evaluation in
:class:`research.piecewise.NumpyPiecewise`), so the results agree to rounding.

The coefficient count ``D`` and the order count are constants in the source of each form
(:data:`FORMS`, ``D = 1 .. 12``: FIR lines under 1-10 filters, arcs under 1-5, S-curves, the OCP's
cubics): the loops over them unroll and each sample is straight-line code (a loop over a runtime
``D`` costs ~3x more per sample, :func:`_rows_any`, for any other count). Written out, not
generated: Numba caches a compiled function on disk by its source file, which a generated one has
not, and the first sampling of every process compiled for ~1 s (a quarter of the main job).
Imported on first sampling (``import numba`` costs ~0.2 s that a run served from the store never needs).
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(inline="always", nogil=True)
def _sample(breaks, first, coeffs, sample_period, out, D, orders):
    """The loop (:func:`research._grid_sample.sample_grid`'s arguments; ``out`` ``(orders, N, A)``
    written): piece ``p`` covers samples ``first[p - 1] .. first[p] - 1``; its scaled coefficients
    ``tab[nu, m] = c_m m! / (m - nu)!`` (the factor multiplied in even where it is 1: ``x * 1.0`` is
    ``x``), then per sample the local time ``tau`` (the time clipped to ``[b_0, b_K]``) and Horner's
    rule per order; after ``b_K`` the derivatives are zero."""
    K = coeffs.shape[0]
    n = out.shape[1]
    A = out.shape[2]
    b0, bK = breaks[0], breaks[K]
    tab = np.zeros((orders, D, A))
    start = 0
    for p in range(K):
        stop = first[p] if p < K - 1 else n
        if stop <= start:
            continue
        bp = breaks[p]
        for a in range(A):
            for nu in range(min(orders, D)):
                for m in range(nu, D):
                    scale = 1.0
                    for r in range(m - nu + 1, m + 1):
                        scale *= r
                    tab[nu, m, a] = coeffs[p, m, a] * scale
        for i in range(start, stop):
            t = b0 + i * sample_period
            tau = min(max(t, b0), bK) - bp
            moving = t <= bK
            for a in range(A):
                for nu in range(orders):
                    if nu >= D:
                        out[nu, i, a] = 0.0
                        continue
                    v = tab[nu, D - 1, a]
                    for m in range(D - 2, nu - 1, -1):
                        v = v * tau + tab[nu, m, a]
                    out[nu, i, a] = v if (nu == 0 or moving) else 0.0
        start = max(start, stop)


@numba.njit(cache=True, nogil=True)
def _rows_any(breaks, first, coeffs, sample_period, out):
    _sample(breaks, first, coeffs, sample_period, out, coeffs.shape[1], out.shape[0])


# one function per coefficient count, written out (see the module docstring)
@numba.njit(cache=True, nogil=True)
def _rows1(breaks, first, coeffs, sample_period, out):
    _sample(breaks, first, coeffs, sample_period, out, 1, 4)

@numba.njit(cache=True, nogil=True)
def _rows2(breaks, first, coeffs, sample_period, out):
    _sample(breaks, first, coeffs, sample_period, out, 2, 4)

@numba.njit(cache=True, nogil=True)
def _rows3(breaks, first, coeffs, sample_period, out):
    _sample(breaks, first, coeffs, sample_period, out, 3, 4)

@numba.njit(cache=True, nogil=True)
def _rows4(breaks, first, coeffs, sample_period, out):
    _sample(breaks, first, coeffs, sample_period, out, 4, 4)

@numba.njit(cache=True, nogil=True)
def _rows5(breaks, first, coeffs, sample_period, out):
    _sample(breaks, first, coeffs, sample_period, out, 5, 4)

@numba.njit(cache=True, nogil=True)
def _rows6(breaks, first, coeffs, sample_period, out):
    _sample(breaks, first, coeffs, sample_period, out, 6, 4)

@numba.njit(cache=True, nogil=True)
def _rows7(breaks, first, coeffs, sample_period, out):
    _sample(breaks, first, coeffs, sample_period, out, 7, 4)

@numba.njit(cache=True, nogil=True)
def _rows8(breaks, first, coeffs, sample_period, out):
    _sample(breaks, first, coeffs, sample_period, out, 8, 4)

@numba.njit(cache=True, nogil=True)
def _rows9(breaks, first, coeffs, sample_period, out):
    _sample(breaks, first, coeffs, sample_period, out, 9, 4)

@numba.njit(cache=True, nogil=True)
def _rows10(breaks, first, coeffs, sample_period, out):
    _sample(breaks, first, coeffs, sample_period, out, 10, 4)

@numba.njit(cache=True, nogil=True)
def _rows11(breaks, first, coeffs, sample_period, out):
    _sample(breaks, first, coeffs, sample_period, out, 11, 4)

@numba.njit(cache=True, nogil=True)
def _rows12(breaks, first, coeffs, sample_period, out):
    _sample(breaks, first, coeffs, sample_period, out, 12, 4)


#: the written-out form of each coefficient count, for four orders (:func:`kernel`)
FORMS = {D: globals()[f"_rows{D}"] for D in range(1, 13)}


def kernel(n_coeffs: int, orders: int):
    """The compiled loop for ``n_coeffs`` coefficients and ``orders`` orders: a written-out form, or
    :func:`_rows_any`. Chosen here, not in compiled code: each is compiled (or loaded) on first use only."""
    return FORMS.get(n_coeffs, _rows_any) if orders == 4 else _rows_any
