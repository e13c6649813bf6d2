"""A limit-holding candidate for chains of short blocks under limits far below the FIR envelope:
block feeds capped window by window and joined by staircases of isolated steps (beyond Sencer 2015).

A block shorter than the FIR window cannot start from rest above the feed of one isolated step,
``dV = min(A_i T_1, J_i T_1 T_2)`` (a velocity step through the chain peaks at ``dV / T_1`` and
``dV / (T_1 T_2)``, Sencer 2015 §2.1), and phase 1 of ``_fir_limits`` (every block alone) takes
every block of such a chain to it: on a CAM file of 0.5 mm chords at 0.1x the envelope, 18 mm/s
where the path's curvature allows ~40-85 mm/s. Inside one motion the feed may change by such
steps as long as each is held for ``T_d`` (the steps are then isolated). :func:`capped_staircase`
caps the feeds of the blocks around every corner whose window breaks a limit (by the window's peak
ratio to the power ``1 / POWER``: where its peaks grow as a power of the feed of at most 3, the
cap stays at or above the feed the window allows) and joins the caps by
:func:`staircase`, until every window keeps the limits; the planner verifies and repairs the
result like any candidate.
"""

from __future__ import annotations

from collections.abc import Callable

import numba
import numpy as np

#: rounds of capping the breaking windows' blocks and joining the caps
ROUNDS = 12
#: a window's peak ratio taken to grow as the feed to this power at most when its blocks are capped
#: (a step's peaks grow as the feed, the curvature's acceleration as its square, its jerk as its cube)
POWER = 3.0


def staircase(lengths: np.ndarray, cap: np.ndarray, step: float, hold: float) -> np.ndarray:
    """``(M,)`` block feeds [mm/s] at most ``cap`` ``(M,)``, from rest to rest, that change only by
    steps of at most ``step`` [mm/s] up (in path order) and down (in reverse), each level held for
    at least ``hold`` [s] before the next rise (a level changes at a block boundary)."""
    lengths, cap = np.ascontiguousarray(lengths, dtype=np.float64), np.ascontiguousarray(cap, dtype=np.float64)
    up, down = np.empty(lengths.size), np.empty(lengths.size)
    _rises(lengths, cap, float(step), float(hold), 1, up)
    _rises(lengths, cap, float(step), float(hold), -1, down)
    return np.minimum(up, down)


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _rises(lengths, cap, step, hold, direction, out):
    """The levels of :func:`staircase` rising in path order (``direction`` 1) or in reverse (-1)."""
    M = lengths.size
    level, spent = 0.0, hold
    for m in range(M):
        i = m if direction > 0 else M - 1 - m
        if cap[i] < level:  # a drop (limited by the pass the other way): a new level
            level, spent = cap[i], 0.0
        elif spent >= hold and level < cap[i]:
            level, spent = min(level + step, cap[i]), 0.0
        out[i] = level
        spent += lengths[i] / level


def capped_staircase(lengths: np.ndarray, ceiling: np.ndarray, step: float, hold: float,
                     windows: Callable[[np.ndarray], tuple[np.ndarray, tuple]]) -> np.ndarray:
    """``(M,)`` block feeds [mm/s]: ``ceiling`` ``(M,)`` joined by :func:`staircase`, the blocks of
    every window above a limit capped at their feed over its ratio to the power ``1 / POWER``, for
    :data:`ROUNDS` rounds or until every window keeps the limits.

    Args:
        lengths: ``(M,)`` block lengths [mm]; ceiling: ``(M,)`` each block's own bound [mm/s];
        step: the isolated step [mm/s]; hold: ``T_d`` [s].
        windows: ``feeds -> (ratios (C,), (blocks, first, last))``: every corner window's largest
            peak / limit at those feeds; window ``c`` covers ``blocks[first[c]:last[c]]``
            (``_fir_limit_spread.CornerWindows.with_blocks``).
    """
    cap = np.asarray(ceiling, dtype=np.float64).copy()
    feeds = staircase(lengths, cap, step, hold)
    for _ in range(ROUNDS):
        ratios, (blocks, first, last) = windows(feeds)
        bad = np.flatnonzero(ratios > 1.0)
        if not bad.size:
            break
        counts = last[bad] - first[bad]
        window = np.repeat(np.arange(bad.size), counts)  # each (window, block) pair of the breaking windows
        b = blocks[first[bad][window] + np.arange(window.size) - np.repeat(np.cumsum(counts) - counts, counts)]
        np.minimum.at(cap, b, feeds[b] / ratios[bad][window] ** (1.0 / POWER))
        feeds = staircase(lengths, cap, step, hold)
    return feeds
