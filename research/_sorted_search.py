"""Searches in sorted arrays, compiled: ``np.searchsorted``'s counts inside compiled loops.

Shared by the planner's kernels (``research.interpolators._fir_kernels``, ``_fir_verify_kernels``,
``_fir_candidate_kernels``) and the piecewise evaluator (``research._piecewise_eval``), which sit on
both sides of the package's layers. Each returns the same index as ``np.searchsorted`` on a
non-decreasing array (no NaN; callers that meet one handle it before).
"""

from __future__ import annotations

import numba


@numba.njit(cache=True, nogil=True, error_model="numpy")
def left_in(a, v, lo, hi):
    """``np.searchsorted(a, v, side="left")`` where the answer is known to lie in ``[lo, hi]``."""
    while lo < hi:
        mid = (lo + hi) >> 1
        if a[mid] < v:
            lo = mid + 1
        else:
            hi = mid
    return lo


@numba.njit(cache=True, nogil=True, error_model="numpy")
def right_in(a, v, lo, hi):
    """``np.searchsorted(a, v, side="right")`` where the answer is known to lie in ``[lo, hi]``."""
    while lo < hi:
        mid = (lo + hi) >> 1
        if a[mid] <= v:
            lo = mid + 1
        else:
            hi = mid
    return lo


@numba.njit(cache=True, nogil=True, error_model="numpy")
def left(a, v):
    """``np.searchsorted(a, v, side="left")``."""
    return left_in(a, v, 0, a.size)


@numba.njit(cache=True, nogil=True, error_model="numpy")
def right(a, v):
    """``np.searchsorted(a, v, side="right")``."""
    return right_in(a, v, 0, a.size)


@numba.njit(inline="always", cache=True, nogil=True, error_model="numpy")
def _past(x, v, right):
    """The search goes on past an entry ``x``: ``x <= v`` for the right side, ``x < v`` for the left."""
    return x <= v if right else x < v


@numba.njit(inline="always", cache=True, nogil=True, error_model="numpy")
def _from(a, v, hint, right):
    """:func:`right_from` (``right``) or :func:`left_from`, inlined into each with its side a
    constant: steps of 1, 2, 4, ... away from ``hint`` until the answer is bracketed, then a binary
    search in the bracket."""
    n = a.size
    i = min(max(hint, 0), n)
    if i > 0 and not _past(a[i - 1], v, right):  # the answer is below i
        hi, step = i, 1
        lo = hi - step
        while lo > 0 and not _past(a[lo - 1], v, right):
            hi = lo
            step *= 2
            lo = max(hi - step, 0)
        lo = max(lo, 0)
    else:  # the answer is at or above i
        lo, step = i, 1
        hi = lo + step
        while hi <= n and _past(a[hi - 1], v, right):
            lo = hi
            step *= 2
            hi = lo + step
        hi = min(hi, n)
    return right_in(a, v, lo, hi) if right else left_in(a, v, lo, hi)  # binary search inside the bracket


@numba.njit(cache=True, nogil=True, error_model="numpy")
def right_from(a, v, hint):
    """``np.searchsorted(a, v, side="right")`` (the count of entries ``<= v``, unique on a sorted
    array) found from a nearby index ``hint`` by a galloping search: steps of 1, 2, 4, ... away from
    ``hint`` until the answer is bracketed, then a binary search in the bracket. ``O(log distance)``
    for queries that move little along ``a``."""
    return _from(a, v, hint, True)


@numba.njit(cache=True, nogil=True, error_model="numpy")
def left_from(a, v, hint):
    """``np.searchsorted(a, v, side="left")`` (the count of entries ``< v``) found from a nearby
    index ``hint`` by the galloping search of :func:`right_from`."""
    return _from(a, v, hint, False)
