"""The alpha searches of :func:`research.interpolators.mtp_motion` (DiMarco 2015 sigmoid moves):
a plain move's first decade from the closed form, each bisection's result found on the bisection's
own grid by guided probes, and peaks read from the search's unequally spaced samples.
"""

from __future__ import annotations

import math

import numpy as np


def decade_bracket(alpha, has_room, within_limits):
    """``(lo, hi)``: a decade of alpha from the closed form ``alpha`` with room to stop at ``lo``,
    ``lo`` within the limits and ``hi = 10 lo`` (or the decade point above) not; None where that
    needs ``alpha_room`` (no room at ``alpha``, or none found before the limits hold). For a plain
    move, whose peaks and stop start grow with alpha, the largest alpha within the limits lies in
    it, where the search up from ``alpha_room`` arrives after as many decades as it went down (a
    0.5 mm chord at 200 mm/s had room down to 1e-12 of the closed form: 13 builds down, 16 up)."""
    if not has_room(alpha):
        return None
    if within_limits(alpha):
        lo, hi = alpha, 10.0 * alpha
        while within_limits(hi):
            lo, hi = hi, 10.0 * hi
        return lo, hi
    hi, lo = alpha, alpha / 10.0
    while has_room(lo) and not within_limits(lo) and lo > 1e-12 * alpha:
        hi, lo = lo, lo / 10.0
    return (lo, hi) if has_room(lo) and within_limits(lo) else None


#: guided probes of :func:`bisection_on_grid` before it bisects (swept 4 / 6 / 8 / 12: 60
#: random plain moves in 7.3 / 6.3 / 6.1 / 5.8 s, a 50 mm move in 48 / 36 / 34 / 34 builds)
GUIDED_PROBES = 8


def bisection_on_grid(lower, value, lo: float, hi: float, steps: int, guided: bool = True) -> tuple[float, float]:
    """The bracket ``steps`` bisections of ``[lo, hi]`` on ``log alpha`` end with (midpoints
    ``sqrt(lo hi)``; the lower end moves to a midpoint where ``lower(mid)``, else the upper end),
    found in fewer evaluations where ``lower`` holds below one alpha and not above it.

    The bisection's midpoints form a grid of ``2^steps`` steps; each is computed here by the
    operations the bisection uses on its way to it (so the same floats). The search keeps the
    largest grid index known to be ``lower`` and the smallest known not to be, and probes first
    where the secant of ``value`` (a continuous function that is > 0 exactly where ``lower``
    holds: the margin to a limit, minus the stop's start) in ``log alpha`` through the two
    known ends crosses 0, on the grid point below it after the upper end moved and above it after
    the lower end moved (two probes where ``value`` is linear in ``log alpha``, as a peak that is
    a power of alpha), bisecting the indices after :data:`GUIDED_PROBES` probes. Where ``lower``
    holds below one alpha only, the bracket is the bisection's, bit for bit. Not ``guided``, it is
    the bisection itself (its midpoints, in its order; ``value`` is not called).

    Args:
        lower: ``alpha -> bool``; value: ``alpha -> float`` (see above); lo, hi: the bracket
            (``lower(lo)``, not ``lower(hi)``, as the bisection assumes); steps: its bisections;
            guided: probe where ``value``'s secant leads (else bisect from the first step).

    Returns:
        ``(lo, hi)`` after the bisections.
    """
    top = 1 << steps

    def point(j):  # grid index j in (0, top): the bisection's midpoint on the way to it
        a, b = lo, hi
        for k in range(steps - 1, -1, -1):
            mid = math.sqrt(a * b)
            if j & ((1 << (k + 1)) - 1) == 1 << k:
                return mid
            if (j >> k) & 1:
                a = mid
            else:
                b = mid
        raise AssertionError("a grid index in (0, 2^steps) is a midpoint")

    j_lo, j_hi = 0, top
    x_lo, x_hi = lo, hi
    probes = GUIDED_PROBES if guided else 0
    value = value if guided else (lambda x: 0.0)
    v_lo, v_hi = value(lo), value(hi)  # (the callers evaluated both ends already: memoized)
    last = 0  # the end the last probe moved: -1 lower, 1 upper, 0 none yet
    log_lo, span = math.log(lo), math.log(hi) - math.log(lo)
    for probe in range(probes + steps):
        if j_hi - j_lo <= 1:
            break
        j = (j_lo + j_hi) // 2
        if probe < probes and v_lo != v_hi:
            a, b = math.log(x_lo), math.log(x_hi)
            u = (a + (b - a) * v_lo / (v_lo - v_hi) - log_lo) / span * top  # the secant's zero, as an index
            if math.isfinite(u):
                j = min(max(math.floor(u) if last >= 0 else math.ceil(u), j_lo + 1), j_hi - 1)
        x = point(j)
        if lower(x):
            if last < 0:  # the lower end moved twice: halve the upper end's value (Illinois)
                v_hi *= 0.5
            j_lo, x_lo, v_lo, last = j, x, value(x), -1
        else:
            if last > 0:  # the upper end moved twice: halve the lower end's value
                v_lo *= 0.5
            j_hi, x_hi, v_hi, last = j, x, value(x), 1
    return x_lo, x_hi


def grid_peak(motion, t: np.ndarray, y: np.ndarray, order: int) -> float:
    """Largest ``|d^order s / dt^order|`` of ``motion`` from its samples ``y`` on the grid ``t``
    (``sigmoid._grid``, not equally spaced): the largest sample, or the exact value at the vertex
    of the parabola through the top three samples (their divided differences) where that is
    larger. Read as equally spaced (``sigmoid._peak``), a peak between spacings of 0.22 and 0.09 ms
    came out 6.5e-6 below the true one and the move broke its acceleration limit by 5.5e-6; the
    vertex's own value never lies above the true peak, where a parabola's would at a kink (a
    blend's start)."""
    i = int(np.argmax(y))
    best = float(y[i])
    if 0 < i < y.size - 1:
        t0, t1, t2 = t[i - 1], t[i], t[i + 1]
        d1, d2 = (y[i] - y[i - 1]) / (t1 - t0), (y[i + 1] - y[i]) / (t2 - t1)
        q = (d2 - d1) / (t2 - t0)
        if q < 0:
            x = min(max(0.5 * (t0 + t1) - d1 / (2 * q), t0), t2)
            best = max(best, float(np.abs(motion.derivatives(np.array([x]))[order][0])))
    return best
