"""Evaluation of a piecewise polynomial at arbitrary times, compiled: the kernel behind
:meth:`research.piecewise.NumpyPiecewise.__call__`.

The golden-section refinements and break scans of :mod:`research.metrics` evaluate one profile at
millions of scattered times (a 76,461-chord program: 858,073 samples, 710,032 pieces). In NumPy each
evaluation gathers its piece's whole coefficient rows into temporaries and runs Horner's rule over
them array by array; here one loop per time finds the piece (``np.searchsorted(side="right")``'s
count, searched from the previous time's: ``research._sorted_search.right_from``) and runs Horner's
rule in registers. The same operations in the same order as the NumPy form it replaced (clip,
search, local time, ``c_m m! / (m - nu)!`` by Horner), so the same values bit for bit
(tests/test_piecewise.py compares the two).

Imported on first evaluation (Numba's import costs ~0.3 s that a run served from the store never
needs); compiled once and cached on disk.
"""

from __future__ import annotations

import numba

from research._sorted_search import right_from


@numba.njit(cache=True, nogil=True)
def evaluate(breaks, coeffs, times, nu, snap, scale, out):
    """``out[i] =`` the ``nu``-th derivative at ``times[i]`` of the piecewise polynomial ``(breaks,
    coeffs)`` (:class:`~research.piecewise.NumpyPiecewise`): the time clipped to ``[b_0, b_K]``, its
    piece the last whose break is at or before it plus ``snap``, Horner's rule on ``coeffs[piece, m]
    * scale[m]`` (``scale[m] = m! / (m - nu)!``); for ``nu >= 1`` zero outside ``[b_0, b_K]``
    (the motion at rest). ``nu`` is at most the degree (the caller returns zeros above it).

    Args:
        breaks: ``(K + 1,)`` [s]; coeffs: ``(K, D, A)`` ascending local coefficients; times: ``(n,)``
            [s]; nu: derivative order; snap: [s]; scale: ``(D,)``; out: ``(n, A)``, written.
    """
    K, D, A = coeffs.shape
    b0, bK = breaks[0], breaks[K]
    g = 0  # the last time's count: the search starts there
    for i in range(times.size):
        t = times[i]
        c = t
        if t < b0:
            c = b0
        elif t > bK:
            c = bK
        x = c + snap
        g = K + 1 if x != x else right_from(breaks, x, g)  # NaN sorts last, as in NumPy
        p = min(max(g - 1, 0), K - 1)
        tau = c - breaks[p]
        for a in range(A):
            v = coeffs[p, D - 1, a] * scale[D - 1]
            for m in range(D - 2, nu - 1, -1):
                v = v * tau + coeffs[p, m, a] * scale[m]
            out[i, a] = v
        if nu > 0 and not (b0 <= t <= bK):
            for a in range(A):
                out[i, a] = 0.0
