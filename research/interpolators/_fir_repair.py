"""The repairs of ``plan_fir``'s verification rounds, and a bound on them from the vertex errors.

A round checks a candidate plan on its exact profile (vertex errors, then the sampled path
deviation, ``_fir_verify.RoundChecks``) and repairs every violator (``fir`` module docstring): a
full-overlap vertex slows the blocks of its window by ``sqrt(eps / error)`` (the error of a chain
is quadratic in feed) -- of a line the window reaches only in part, the line piece on the window's
side (its tail from the left, its head from the right, ``_fir_lookahead.line_pieces``) where that
piece holds the whole stretch the window covers, else the whole line -- a dwell corner shrinks its overlap by ``(eps / error)^(1/(n+1))`` (the
small-overlap scaling of ``H2``, Sencer 2015 eq 13/14), an arc whose own deviation breaks its
tolerance slows by ``sqrt(eps / deviation)``, and after the scaling rounds a violator becomes an
exact stop. (The first version scaled every block of the window whole, a long line for a window
reaching a fraction of a millimetre into it. Growing a piece shorter than the stretch covered, at
its own lower feed, was tried as well: benchmarks/README.md, "Local window repairs".)

The branch and bound of ``plan_fir`` orders candidates by the predicted time of their repaired
plans. :meth:`Repairs.bound` gives, from the vertex errors alone (the first half of a round),
factors and shrinks at least as large as :meth:`Repairs.apply` leaves for the whole round, whose
violators are a superset (path samples charged to vertices and arcs add to them) at errors no
smaller (a vertex's error is the larger of its distance and its charged path deviation): each
factor is ``0.98 sqrt(ratio) < 1`` or ``min(0.98 ratio^(1/(n+1)), 1) <= 1`` with ``ratio = eps /
error`` no larger in the full round, and a vertex's window always holds its own two blocks (the
window ``[lo, hi)`` of :meth:`Repairs.apply` has ``lo <= j`` and ``hi >= j + 2``). Of block ``j``
the full round slows at least its tail piece (the whole block where it has none), of block
``j + 1`` at least its head piece; the bound slows exactly those, so it multiplies a subset of
the factors each piece gets in the full round. Its predicted time is then
a lower bound on the full round's where the prediction falls as factors and shrinks grow (the
assumption the branch and bound already rests on: repairs only lower feeds and shrink overlaps).
"""

from __future__ import annotations

import numba
import numpy as np


class Repairs:
    """The repairs of one candidate's rounds.

    Args:
        full: ``(M - 1,)`` full-overlap flags of the candidate's vertices.
        head, tail: ``(M,)`` shares of each block's length its head and tail pieces run (0 on
            arcs and on lines without such a piece).
        tol_vertex: ``(M - 1,)`` tolerance per vertex [mm]; tol_block: ``(M,)`` per block [mm].
        feeds: ``(M,)`` commanded feeds [mm/s]; lengths: ``(M,)`` block lengths [mm].
        Td: total filter delay [s]; n_filters: the number of filters ``n``.
        cum: ``(M + 1,)`` arc length at each block start [mm] if already computed (the candidates
            of one plan share it); else from ``lengths``.
    """

    def __init__(self, full, head, tail, tol_vertex, tol_block, feeds, lengths, Td: float, n_filters: int, cum=None):
        self.full, self.tv, self.tb, self.F = full, tol_vertex, tol_block, feeds
        # the head and tail pieces' lengths [mm] are ``head * lengths`` and ``tail * lengths``, formed
        # where used (the candidate holds ``head`` and ``tail``, the path ``lengths``: no (M,) arrays here)
        self.head, self.tail, self.lengths = head, tail, lengths
        self.cum = np.concatenate([[0.0], np.cumsum(lengths)]) if cum is None else cum
        self.Td, self.n = float(Td), int(n_filters)
        self.M = feeds.size

    def apply(self, viol, errors, arc_dev, late: bool, factor, shrink) -> None:
        """One round's repairs, in place on ``factor`` ``(M, 3)`` and ``shrink`` ``(M - 1,)``:
        every violating vertex ``viol`` (error ``errors`` [mm]) becomes an exact stop when
        ``late``, else slows its window's blocks (full overlap) or shrinks its overlap (dwell);
        an arc block whose own deviation ``arc_dev`` [mm] is > 0 slows. Vertices in path order,
        each window's width at the feed its earlier neighbours' repairs left."""
        j = np.flatnonzero(viol)
        if late:
            shrink[j] = 0.0  # exact stop: the vertex is on the trajectory
        elif j.size:
            _repair_vertices(j, self.tv[j] / errors[j], self.full, self.F, self.cum, self.head, self.tail,
                             self.lengths, self.Td, self.n, factor, shrink)
        for k in np.flatnonzero(arc_dev):
            factor[k] *= min(0.98 * np.sqrt(self.tb[k] / arc_dev[k]), 0.98)

    def bound(self, viol, errors, late: bool, factor, shrink):
        """New ``(factor, shrink)``, each entry ``>=`` what :meth:`apply` leaves for any superset
        of the violators ``viol`` at errors ``>= errors`` (module docstring): the same repairs,
        each full-overlap vertex ``j`` slowing only the tail piece of block ``j`` and the head
        piece of block ``j + 1`` (the whole block where it has no such piece)."""
        factor, shrink = factor.copy(), shrink.copy()
        j = np.flatnonzero(viol)
        if late:
            shrink[j] = 0.0
            return factor, shrink
        ratio = self.tv[j] / errors[j]
        zero = self.full[j] & ~(ratio > 0.0)  # full-overlap vertices of tolerance 0 stop (as apply)
        shrink[j[zero]] = 0.0
        j, ratio = j[~zero], ratio[~zero]
        w = self.full[j]
        g = np.ones((self.M, 3))
        gw, jw = 0.98 * np.sqrt(ratio[w]), j[w]
        for k, c, share in ((jw, 2, self.tail), (jw + 1, 0, self.head)):
            own = share[k] * self.lengths[k] > 0.0  # the piece's length [mm]
            np.multiply.at(g, (k[own], c), gw[own])
            for c_all in range(3):
                np.multiply.at(g, (k[~own], c_all), gw[~own])
        shrink[j[~w]] *= np.minimum(0.98 * ratio[~w] ** (1.0 / (self.n + 1)), 1.0)
        return factor * g, shrink


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _repair_vertices(viol, ratio, full, F, cum, head, tail, lengths, Td, n, factor, shrink):
    """The vertex repairs of :meth:`Repairs.apply` (not late), in place, vertices ``viol`` in path
    order with ``ratio = eps / error``: a full-overlap vertex slows the blocks of its window
    ``[lo, max(hi, j + 2))``, its half-width ``T_d F_j / 2`` at the tail feed its earlier
    neighbours' repairs left, by ``0.98 sqrt(ratio)`` (or stops exactly where ``ratio`` is 0: a
    tolerance of 0, which no feed keeps and a zero feed would never leave) -- of an end block the window reaches only in
    part, the piece on its side (tail of ``lo``, head of ``hi - 1``) where that piece is at least
    as long as the stretch covered, else the whole block; a dwell corner shrinks its overlap by
    ``0.98 ratio^(1/(n+1))``; ``ratio`` is taken at most 1, so a repair never speeds a window up
    (a violation read against a looser tolerance than the one it broke gave ratios above 1:
    ``_fir_verify._bound_waiting``) and a dwell shrinks in every round. A compiled loop: each window
    depends on the repairs before it."""
    M = F.size
    for q in range(viol.size):
        j = viol[q]
        if full[j] and not ratio[q] > 0.0:  # a tolerance of 0: no feed keeps it, an exact stop does
            shrink[j] = 0.0
        elif full[j]:  # slow the window's blocks: the error of a chain is quadratic in feed
            half = 0.5 * Td * F[j] * factor[j, 2]
            a, b = cum[j + 1] - half, cum[j + 1] + half
            lo = max(np.searchsorted(cum, a, side="right") - 1, 0)
            hi = max(min(np.searchsorted(cum, b, side="left"), M), j + 2)
            g = 0.98 * np.sqrt(min(ratio[q], 1.0))
            for k in range(lo, hi):
                if k == lo and cum[k] < a and cum[k + 1] - a <= tail[k] * lengths[k]:
                    factor[k, 2] *= g  # the window covers only the block's tail piece
                elif k == hi - 1 and cum[k + 1] > b and b - cum[k] <= head[k] * lengths[k]:
                    factor[k, 0] *= g  # ... only its head piece
                else:
                    for c in range(3):
                        factor[k, c] *= g
        else:
            shrink[j] *= 0.98 * min(ratio[q], 1.0) ** (1.0 / (n + 1))
