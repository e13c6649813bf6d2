"""False position with the Illinois modification (Dowell & Jarratt 1971), the bracketed root search
of the compiled kernels (``_fir_piece_peaks._isolated_roots``, ``_fir_profile._invert_h2``): each
step takes the secant point of the bracket ``[x0, x1]`` (its midpoint if rounding puts it outside)
and halves the function value kept at the end that stays twice in a row, so the bracket shrinks on
both sides (superlinear, never slower than bisection by more than a constant)."""

from __future__ import annotations

import numba


@numba.njit(inline="always", cache=True, nogil=True, error_model="numpy")
def secant_point(x0, f0, x1, f1):
    """The next point inside ``(x0, x1)`` (``f0``, ``f1`` of opposite signs): the secant's zero, or the
    midpoint where rounding puts that outside the open bracket."""
    x = x1 - f1 * (x1 - x0) / (f1 - f0)
    if not (x0 < x < x1):
        x = 0.5 * (x0 + x1)
    return x


@numba.njit(inline="always", cache=True, nogil=True, error_model="numpy")
def narrowed(x0, f0, x1, f1, side, x, fx):
    """The bracket ``(x0, f0, x1, f1, side)`` after the point ``x`` with value ``fx`` (not 0): it
    replaces the end whose value has its sign; the other end's value is halved when the same end
    was replaced the step before (``side``: -1 the lower end, 1 the upper, 0 none yet)."""
    if (fx < 0.0) == (f0 < 0.0):
        x0, f0 = x, fx
        if side == -1:
            f1 *= 0.5
        side = -1
    else:
        x1, f1 = x, fx
        if side == 1:
            f0 *= 0.5
        side = 1
    return x0, f0, x1, f1, side
