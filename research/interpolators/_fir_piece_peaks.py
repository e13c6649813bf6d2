"""Exact per-axis peaks of a piecewise-polynomial FIR profile, piece by piece, for the windows the
limit-holding planner checks (``_fir_limits``).

A profile's velocity, acceleration and jerk peak at its break points or where the next derivative
vanishes; :class:`PiecePeaks` finds every piece's largest ``peak / limit`` (one compiled pass
over the pieces: the real roots of the next derivative in closed form to degree 2, isolated by its
own derivatives' roots above) and answers the largest over any set of time windows
(:meth:`PiecePeaks.over`); :func:`corner_peak_ratios` is one such call. Above cubic degree (arcs,
three filters) the windows seek roots only in the pieces whose coefficient bound exceeds the
window's largest end value (:func:`window_maxima`, the same floats): on random G-code programs
with arcs under limits well below the envelope the root isolation took 28-38 % of planning.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from research.interpolators._illinois import narrowed, secant_point
from research.limits import AxisLimits
from research.piecewise import DEGENERATE_PIECE


def corner_peak_ratios(position, lo: np.ndarray, hi: np.ndarray, limits: AxisLimits) -> np.ndarray:
    """Largest ``peak / limit`` over axes and over velocity, acceleration, jerk, in each window
    ``[lo_c, hi_c]`` [s]; exact (roots of the next derivative) for pieces of any degree.

    ``position``: a :class:`PiecewisePolynomial` or its NumPy evaluator. Pieces shorter than
    :data:`DEGENERATE_PIECE` are skipped (their continuous derivatives are the neighbours' end values).
    Several window sets on one profile: :class:`PiecePeaks` once, then :meth:`PiecePeaks.over`."""
    return PiecePeaks(position, limits).over(lo, hi)


class PiecePeaks:
    """Largest ``peak / limit`` of every piece of a profile (over axes and over velocity,
    acceleration, jerk), computed once, for the windows of :meth:`over`.

    Each derivative of order 1-3 peaks, on a piece, at one of its ends or where the next
    derivative vanishes (its real roots in ``[0, h]``: closed form up to degree 2, isolated by the
    roots of its own derivatives above, :func:`_isolated_roots`); each axis is evaluated at its own roots.

    Args:
        position: a :class:`PiecewisePolynomial` or its NumPy evaluator (``breaks``, ``coeffs``
            ``(K, d + 1, A)`` ascending local).
        limits: the per-axis limits.

    Example (``q = 2 t`` on one axis for 1 s: speed 2 against a limit of 4)::

        >>> import numpy as np
        >>> from research.limits import AxisLimits
        >>> from research.piecewise import NumpyPiecewise
        >>> q = NumpyPiecewise(np.array([0.0, 1.0]), np.array([[[0.0], [2.0], [0.0], [0.0]]]))
        >>> peaks = PiecePeaks(q, AxisLimits.uniform(1, 4.0, 1.0, 1.0))
        >>> peaks.over(np.array([0.0]), np.array([1.0]))  # one window set of many on one profile
        array([0.5])
    """

    def __init__(self, position, limits: AxisLimits):
        self.breaks = np.asarray(position.breaks, dtype=np.float64)
        self._coeffs = np.ascontiguousarray(position.coeffs, dtype=np.float64)
        self._h = np.diff(self.breaks)
        self._limit = np.ascontiguousarray(np.stack([limits.velocity, limits.acceleration, limits.jerk]),
                                           dtype=np.float64)  # (3, A)
        self._per_piece = None

    @property
    def per_piece(self) -> np.ndarray:
        """``(K,)`` largest ``peak / limit`` of every piece (0 on pieces of rounding length)."""
        if self._per_piece is None:
            ratio = piece_ratios_at(self._coeffs, self._h, self._limit, np.arange(self._coeffs.shape[0]))
            self._per_piece = np.where(self._h > DEGENERATE_PIECE, ratio, 0.0)
        return self._per_piece

    def over(self, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        """``(C,)`` largest piece ratio in each window ``[lo_c, hi_c]`` [s] (the pieces it meets):
        from the piece holding ``lo_c`` (``searchsorted`` right, less one) to the last piece
        starting before ``hi_c`` (left), at least one. Windows in time order (``lo`` and ``hi``
        nondecreasing: the corner windows, the own spans) find their pieces by one merge with the
        breaks (:func:`_merged_windows`), others by binary search. Above cubic degree the roots
        are sought only in the pieces that may hold a window's largest value
        (:func:`window_maxima`: the same floats)."""
        lo, hi = window_interiors(lo, hi)
        if np.all(lo[1:] >= lo[:-1]) and np.all(hi[1:] >= hi[:-1]):
            first, last = _merged_windows(self.breaks, lo, hi)
        else:
            K = self._h.size
            first = np.clip(np.searchsorted(self.breaks, lo, side="right") - 1, 0, K - 1)
            last = np.clip(np.searchsorted(self.breaks, hi, side="left"), first + 1, K)
        if self._per_piece is None and self._coeffs.shape[1] != 4:
            return window_maxima(self._coeffs, self._h, self._limit, first, last)
        return range_max(self.per_piece, first, last)


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _cubic_ratios_at(coeffs, h, limit, pieces):
    """:func:`general_ratios_at` of a cubic profile (lines under two filters), its loops written
    out: the same operations in the same order (derivative rows ``c[o - 1, m + 1] * (m + 1)``,
    Horner at 0 and ``h``, the acceleration's root ``-a0 / a1`` for the velocity), so the same
    floats, without the small arrays of the general degree."""
    A = coeffs.shape[2]
    out = np.zeros(pieces.size)
    for i in range(pieces.size):
        k = pieces[i]
        hk = h[k]
        best = 0.0
        for a in range(A):
            c10, c11, c12 = coeffs[k, 1, a] * 1, coeffs[k, 2, a] * 2, coeffs[k, 3, a] * 3
            c20, c21 = c11 * 1, c12 * 2
            c30 = c21 * 1
            # velocity: ends, then where the acceleration vanishes
            v0 = (c12 * 0.0 + c11) * 0.0 + c10
            vh = (c12 * hk + c11) * hk + c10
            peak = max(abs(v0), abs(vh))
            t = -c20 / c21 if c21 != 0 else 0.0
            if t != t:
                t = 0.0
            t = min(max(t, 0.0), hk)
            peak = max(peak, abs((c12 * t + c11) * t + c10))
            best = max(best, peak / limit[0, a])
            # acceleration (linear): its ends; jerk (constant)
            best = max(best, max(abs(c21 * 0.0 + c20), abs(c21 * hk + c20)) / limit[1, a])
            best = max(best, max(abs(c30), abs(c30)) / limit[2, a])
        out[i] = best
    return out


#: a window ``[lo, hi]`` reads the pieces that overlap it by more than this many spacings of its
#: end times (``np.spacing``): a window's ends and the profile's breaks at the same instants come from
#: different sums (a block's end, ``start + T_d``; the filters' ``b + T_i``) and differ by rounding,
#: so a piece that ends an ulp past a window's start belongs to the window before it
WINDOW_ULPS = 8


def window_interiors(lo, hi) -> tuple[np.ndarray, np.ndarray]:
    """``(lo, hi)`` moved inwards by :data:`WINDOW_ULPS` spacings of the larger end where the window
    is wider than twice that (narrower ones as given): what :meth:`PiecePeaks.over` searches. Every
    piece of more than ``2 WINDOW_ULPS`` spacings still lies more than that inside one of any
    windows that tile the time (the corner windows and own spans do); shorter ones are below
    :data:`DEGENERATE_PIECE` on plans of up to ~10^3 s, and rounding beyond."""
    lo, hi = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
    d = WINDOW_ULPS * np.spacing(np.maximum(np.abs(lo), np.abs(hi)))
    wide = hi - lo > 2.0 * d
    return np.where(wide, lo + d, lo), np.where(wide, hi - d, hi)


@numba.njit(cache=True, nogil=True)
def _merged_windows(breaks, lo, hi):
    """``(first, last)`` pieces of :meth:`PiecePeaks.over` for nondecreasing ``lo`` and ``hi``: the
    counts of breaks ``<= lo_c`` and ``< hi_c`` (``searchsorted`` right and left) by one merge."""
    K, C = breaks.size - 1, lo.size
    first, last = np.empty(C, np.int64), np.empty(C, np.int64)
    right, left = 0, 0
    for i in range(C):
        while right <= K and breaks[right] <= lo[i]:
            right += 1
        while left <= K and breaks[left] < hi[i]:
            left += 1
        first[i] = min(max(right - 1, 0), K - 1)
        last[i] = min(max(left, first[i] + 1), K)
    return first, last


def piece_ratios_at(coeffs: np.ndarray, h: np.ndarray, limit: np.ndarray, pieces: np.ndarray) -> np.ndarray:
    """``(N,)`` largest ``peak / limit`` of the pieces ``pieces`` of a profile (``coeffs`` ``(K, D, A)``
    ascending local, ``h`` ``(K,)`` piece lengths [s], ``limit`` ``(3, A)``), over axes and over
    velocity, acceleration and jerk: each peaks at a piece end or a real root of the next
    derivative. One compiled pass: :func:`_cubic_ratios_at` for cubic profiles (lines under two
    filters), :func:`general_ratios_at` for any other degree (``tests/interpolators/_peaks_reference.py``
    holds the whole-array NumPy form: both reproduce it bit for bit to degree 4, up to the
    rounding of the roots above)."""
    coeffs = np.ascontiguousarray(coeffs, dtype=np.float64)
    pieces = np.ascontiguousarray(pieces, dtype=np.int64)
    if coeffs.shape[1] == 4:
        return _cubic_ratios_at(coeffs, h, limit, pieces)
    return general_ratios_at(coeffs, h, limit, pieces)


@numba.njit(inline="always", cache=True, nogil=True, error_model="numpy")
def _derivative_rows(coeffs, k, a, c, n):
    """Rows ``c[o, :n[o]]`` of the derivatives of order ``o = 0 .. 4`` of piece ``k``'s axis ``a``
    (ascending; ``c[o - 1, m + 1] * (m + 1)``, a constant's derivative: one 0)."""
    D = coeffs.shape[1]
    n[0] = D
    for m in range(D):
        c[0, m] = coeffs[k, m, a]
    for o in range(1, 5):
        if n[o - 1] > 1:
            n[o] = n[o - 1] - 1
            for m in range(n[o]):
                c[o, m] = c[o - 1, m + 1] * (m + 1)
        else:
            n[o] = 1
            c[o, 0] = 0.0


@numba.njit(cache=True, nogil=True)
def range_max(values, first, last):
    """``max(values[first_i:last_i])`` for every ``i`` (``first_i < last_i``) by a sparse table of
    the maxima of ``2^l`` consecutive values, ``l`` up to the longest range (O(K log L + C)): each
    range the union of two such runs, so the maximum of the same values."""
    K, C = values.size, first.size
    longest = 1
    for i in range(C):
        longest = max(longest, last[i] - first[i])
    levels = 1
    while (1 << levels) <= longest:
        levels += 1
    table = np.empty((levels, K))
    table[0] = values
    for lv in range(1, levels):
        half = 1 << (lv - 1)
        for k in range(K - (1 << lv) + 1):
            a, b = table[lv - 1, k], table[lv - 1, k + half]
            table[lv, k] = a if a >= b else b
    out = np.empty(C)
    for i in range(C):
        n, lv = last[i] - first[i], 0
        while (2 << lv) <= n:
            lv += 1
        a, b = table[lv, first[i]], table[lv, last[i] - (1 << lv)]
        out[i] = a if a >= b else b
    return out


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _isolated_roots(p, n, hk, d, lev, nlev):
    """Real roots in ``(0, hk)`` of ``p[0 .. n]`` (ascending) and of each of its derivatives: those of
    derivative ``j`` into ``lev[j, :nlev[j]]`` (increasing), ``j = 0 .. n - 1``.

    Root isolation by the derivatives: the roots of the ``(n - 1)``-th derivative (linear) in closed
    form; then, for each lower derivative down to the polynomial itself, the roots of the next one
    cut ``[0, hk]`` into intervals where it is monotone, so each interval holds at most one root,
    bracketed by a sign change and found by false position with the Illinois modification (Dowell
    & Jarratt 1971) to the float resolution of ``hk``. A root of even multiplicity (no sign change)
    is not an extremum of the polynomial's antiderivative, so the peaks do not need it. (The
    companion-matrix eigenvalues this replaces took 35 of 44 s of a limit-holding plan of 1,632
    adaptive-clearing blocks, whose arcs give pieces of degree 8.) ``d`` ``(n + 1, n + 1)``: scratch;
    ``lev`` ``(n, n + 1)`` and ``nlev`` ``(n,)``: the output."""
    for m in range(n + 1):
        d[0, m] = p[m]
    for j in range(1, n):
        for m in range(n + 1 - j):
            d[j, m] = d[j - 1, m + 1] * (m + 1)
    nlev[n - 1] = 0
    if d[n - 1, 1] != 0.0:  # the (n - 1)-th derivative: d[n-1, 0] + d[n-1, 1] t
        t = -d[n - 1, 0] / d[n - 1, 1]
        if 0.0 < t < hk:
            lev[n - 1, 0] = t
            nlev[n - 1] = 1
    for j in range(n - 2, -1, -1):  # roots of derivative j between those of j + 1 (and the ends)
        deg = n - j
        nr = 0
        for i in range(nlev[j + 1] + 1):
            x0 = lev[j + 1, i - 1] if i > 0 else 0.0
            x1 = lev[j + 1, i] if i < nlev[j + 1] else hk
            f0 = _horner(d, j, deg, x0)
            f1 = _horner(d, j, deg, x1)
            if f0 == 0.0:
                if x0 > 0.0 and (nr == 0 or lev[j, nr - 1] != x0):
                    lev[j, nr] = x0
                    nr += 1
                continue
            if f1 == 0.0 or (f0 < 0.0) == (f1 < 0.0):
                continue  # no sign change inside (a zero at x1 is the next interval's start)
            side = 0
            for _ in range(200):
                x = secant_point(x0, f0, x1, f1)
                if x <= x0 or x >= x1:
                    break
                fx = _horner(d, j, deg, x)
                if fx == 0.0:
                    x0 = x1 = x
                    break
                x0, f0, x1, f1, side = narrowed(x0, f0, x1, f1, side, x, fx)
            lev[j, nr] = 0.5 * (x0 + x1)
            nr += 1
        nlev[j] = nr


@numba.njit(inline="always", cache=True, nogil=True, error_model="numpy")
def _horner(d, j, deg, x):
    """Polynomial ``d[j, 0 .. deg]`` at ``x`` by Horner's rule."""
    v = d[j, deg]
    for m in range(deg - 1, -1, -1):
        v = v * x + d[j, m]
    return v


@numba.njit(inline="always", cache=True, nogil=True, error_model="numpy")
def _piece_ratio(coeffs, k, hk, limit, degree, c, n, tau, d, lev, nlev):
    """Largest ``peak / limit`` of piece ``k`` over its axes and over velocity, acceleration and
    jerk (:func:`general_ratios_at`; ``c n tau d lev nlev``: scratch arrays)."""
    A = coeffs.shape[2]
    best = 0.0
    for a in range(A):
        _derivative_rows(coeffs, k, a, c, n)
        for order in range(1, 4):
            tau[0], tau[1] = 0.0, hk
            nt = 2
            if order < degree:
                r = n[order + 1] - 1  # degree of the next derivative
                if r == 1:
                    a1, a0 = c[order + 1, 1], c[order + 1, 0]
                    tau[2] = -a0 / a1 if a1 != 0 else 0.0
                    nt = 3
                elif r == 2:
                    a2, a1, a0 = c[order + 1, 2], c[order + 1, 1], c[order + 1, 0]
                    disc = a1 * a1 - 4 * a2 * a0
                    sq = math.sqrt(max(disc, 0.0))
                    ok = a2 != 0 and disc >= 0
                    tau[2] = (-a1 + sq) / (2 * a2) if ok else 0.0
                    tau[3] = (-a1 + -sq) / (2 * a2) if ok else 0.0
                    tau[4] = -a0 / a1 if (a2 == 0 and a1 != 0) else 0.0
                    nt = 5
                elif r > 2:
                    # order 1 isolates the roots of the second derivative and, on the way, of the
                    # third and fourth: the later orders read those levels
                    if order == 1:
                        nlev[:] = 0
                        if hk > 0:
                            _isolated_roots(c[2], r, hk, d, lev, nlev)
                    for m in range(r):
                        tau[2 + m] = lev[order - 1, m] if m < nlev[order - 1] else 0.0
                    nt = 2 + r
                for m in range(2, nt):
                    x = tau[m]
                    if x != x:
                        x = 0.0
                    tau[m] = min(max(x, 0.0), hk)
            no = n[order]
            peak = 0.0
            for m in range(nt):
                v = c[order, no - 1]
                for q in range(no - 2, -1, -1):
                    v = v * tau[m] + c[order, q]
                peak = max(peak, abs(v))
            best = max(best, peak / limit[order - 1, a])
    return best


@numba.njit(cache=True, nogil=True, error_model="numpy")
def general_ratios_at(coeffs, h, limit, pieces):
    """:func:`piece_ratios_at` of a profile of any degree: derivative rows
    ``c[o - 1, m + 1] * (m + 1)``, Horner's rule, the roots of the next derivative in closed form
    to degree 2 and by :func:`_isolated_roots` above, each replaced by 0 where NaN and clipped to
    ``[0, h]``: the operations of the NumPy reference (``tests/interpolators/_peaks_reference.py``)
    but for the roots above degree 2, which it takes from companion-matrix eigenvalues."""
    K, D, A = coeffs.shape
    out = np.zeros(pieces.size)
    c, n, tau = np.zeros((5, D)), np.zeros(5, np.int64), np.zeros(D + 2)
    d, lev, nlev = np.zeros((D, D)), np.zeros((D, D)), np.zeros(D, np.int64)  # _isolated_roots' scratch
    for i in range(pieces.size):
        k = pieces[i]
        out[i] = _piece_ratio(coeffs, k, h[k], limit, D - 1, c, n, tau, d, lev, nlev)
    return out


#: relative margin on :func:`window_maxima`'s bound of a piece: Horner's rule and the bound's own
#: sums round by at most ``2 D u`` (``u`` = 1.1e-16, ``D <= 10`` coefficients), far below it
BOUND_MARGIN = 1e-12


@numba.njit(cache=True, nogil=True, error_model="numpy")
def window_maxima(coeffs, h, limit, first, last):
    """``max(per_piece[first_c:last_c])`` of :class:`PiecePeaks` for every window ``c``, finding the
    roots only in the pieces that may hold it; the same floats.

    Every piece's ratio is at least its ratio at its two ends (``L``: the same Horner values its
    exact ratio takes the largest of) and at most ``B = max sum_m |c_m| h^m / limit`` over its
    derivatives (``|p(t)| <= sum |c_m| t^m`` on ``[0, h]``, times ``1 + BOUND_MARGIN``). A window's
    largest value is therefore the largest of ``L`` over its pieces and of the exact ratios of the
    pieces whose ``B`` exceeds that: a piece left out is at most its ``B``, which is at most a
    value that is kept. Pieces of rounding length count 0, as in :attr:`PiecePeaks.per_piece`.
    """
    K, D, A = coeffs.shape
    C = first.size
    low, high = np.zeros(K), np.zeros(K)
    done = np.zeros(K, np.int8)  # 1: low and high set, 2: exact ratio in low
    c, n, tau = np.zeros((5, D)), np.zeros(5, np.int64), np.zeros(D + 2)
    d, lev, nlev = np.zeros((D, D)), np.zeros((D, D)), np.zeros(D, np.int64)
    out = np.zeros(C)
    for w in range(C):
        m = 0.0
        for k in range(first[w], last[w]):
            if done[k] == 0:
                done[k] = 1
                hk = h[k]
                if hk > DEGENERATE_PIECE:
                    lo_k, hi_k = 0.0, 0.0
                    for a in range(A):
                        _derivative_rows(coeffs, k, a, c, n)
                        for order in range(1, 4):
                            no = n[order]
                            v0 = c[order, no - 1]
                            vh = c[order, no - 1]
                            s = abs(c[order, no - 1])
                            for q in range(no - 2, -1, -1):
                                v0 = v0 * 0.0 + c[order, q]
                                vh = vh * hk + c[order, q]
                                s = s * hk + abs(c[order, q])
                            lo_k = max(lo_k, max(abs(v0), abs(vh)) / limit[order - 1, a])
                            hi_k = max(hi_k, s / limit[order - 1, a])
                    low[k], high[k] = lo_k, hi_k * (1.0 + BOUND_MARGIN)
            m = max(m, low[k])
        for k in range(first[w], last[w]):
            if done[k] == 1 and high[k] > m:
                low[k] = _piece_ratio(coeffs, k, h[k], limit, D - 1, c, n, tau, d, lev, nlev)
                done[k] = 2
                m = max(m, low[k])
        out[w] = m
    return out
