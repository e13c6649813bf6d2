"""Velocity pulses of line and arc blocks, and the exact FIR-filtered profile built from them.

Sencer 2015 eq 5 turns a G01 block into a rectangular velocity pulse ``F u`` of length
``T_v = L / F``. An arc block (beyond the paper) is the same pulse with a turning direction: the
input position runs along the arc at constant angular rate, ``phi(t) = Phi t / T_v``, so its
velocity is ``P'(phi) Phi / T_v``. Its components are sinusoids, which a piecewise polynomial
cannot hold exactly; each arc is cut into sub-arcs of at most :data:`SUB_ARC` rad and ``dP/du``
(``u`` the fraction of the block) is interpolated at :data:`DEGREE` + 1 Chebyshev nodes per
sub-arc, with the constant term corrected so that every sub-arc integrates exactly to its chord:
positions never drift. The interpolation error of a degree-5 fit over pi/8 is about
``(pi/16)^6 / (6! 2^5) = 2.5e-9`` of the arc speed, so a 100 mm arc is reproduced to well under a
nanometre, and the filtered profile stays exact for that polynomial input.

The pulse table (one row per piece: block, gap or motion, geometric coefficients) depends on the
geometry only; feeds and overlaps scale it to time in :func:`build_profile` (jitted, shapes
bucketed so paths of similar size share compiled code).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import jax
import jax.numpy as jnp
import numpy as np

from research.paths.toolpath import ToolPath
from research.piecewise import PiecewisePolynomial, bucket_size, taylor_shift

#: largest sub-arc angle of one polynomial velocity piece [rad]
SUB_ARC = np.pi / 8
#: degree of the polynomial velocity of an arc piece
DEGREE = 5
#: a sub-arc is cut (:meth:`PulseTable.cut_arcs`) only more than this share of its length from
#: either end (no piece of a few ulps of the path's arc length)
MIN_CUT = 1e-9


@dataclass(frozen=True)
class PulseTable:
    """Velocity pieces of a tool path in block-fraction units, padded to bucketed sizes.

    Attributes:
        block: ``(P,)`` block of each piece (``M_pad`` for padding).
        gap: ``(P,)`` True for the dwell piece after a block (its length is that corner's gap).
        fraction: ``(P,)`` share of the block's pulse time ``T_v`` taken by a motion piece.
        geo: ``(P, DEGREE + 1 or 1, d)`` coefficients of ``dP/du`` [mm] in powers of the local block
            fraction ``u'`` (motion pieces; 0 for gaps and padding).
        role: ``(P,)`` 0 / 1 / 2 for the head / body / tail piece of a line, -1 otherwise.
        first_motion, last_motion: ``(M,)`` the first and last motion piece of each block.
        arc_pieces: ``(A,)`` the sub-arc pieces of all arc blocks, in path order.
        arc_span: ``(A, 2)`` arc length [mm] along the path at which each sub-arc starts and ends.
        n_blocks: real blocks ``M``; ``m_pad``: padded block count.
        joins: ``(P,)`` True for a piece that goes on with the polynomial of the piece before it
            (a sub-arc cut by :meth:`cut_arcs`): at one feed the two are one input piece; None
            where no piece does.
    """

    block: np.ndarray
    gap: np.ndarray
    fraction: np.ndarray
    geo: np.ndarray
    role: np.ndarray
    first_motion: np.ndarray
    last_motion: np.ndarray
    arc_pieces: np.ndarray
    arc_span: np.ndarray
    n_blocks: int
    m_pad: int
    joins: np.ndarray | None = None

    @staticmethod
    def from_path(path: ToolPath) -> "PulseTable":
        M, d = path.n_blocks, path.dim
        arc = path.is_arc
        deg = DEGREE if arc.any() else 0
        # a line is three collinear pieces (head, body, tail) whose shares and feeds the planner
        # sets, so a long line can slow down only where a curved window reaches into it
        n_sub = np.full(M, 3, dtype=np.int64)
        n_sub[arc] = np.maximum(1, np.ceil(path.sweeps[arc] / SUB_ARC)).astype(np.int64)
        # layout per block: its motion pieces, then its gap piece (the last block has none)
        per_block = n_sub + 1
        per_block[-1] -= 1
        P = int(per_block.sum())
        first = np.concatenate([[0], np.cumsum(per_block)[:-1]])
        block = np.repeat(np.arange(M), per_block)
        local = np.arange(P) - first[block]
        gap = local == n_sub[block]
        fraction = np.where(gap, 0.0, 1.0 / n_sub[block])
        role = np.where(gap | arc[block], -1, local)  # 0 head, 1 body, 2 tail of a line; -1 otherwise
        Pp, Mp = bucket_size(P, 64), bucket_size(M, 16)  # small paths share one compiled build
        pad = Pp - P
        geo = np.zeros((Pp, deg + 1, d))  # padded: the pieces past P stay 0
        lines = np.flatnonzero(~arc[block] & ~gap)
        geo[lines, 0, :] = (path.ends - path.starts)[block[lines]]  # dP/du = L u for a line (any share)
        if arc.any():
            k = np.flatnonzero(arc)
            geo[np.repeat(first[k], n_sub[k]) + _ranks(n_sub[k])] = _arc_pieces(path, k, n_sub[k])
        arc_pieces = np.flatnonzero(~gap & arc[block])
        cum = np.concatenate([[0.0], np.cumsum(path.lengths)])
        k, i = block[arc_pieces], local[arc_pieces]
        share = path.lengths[k] / n_sub[k]
        arc_span = np.stack([cum[k] + i * share, cum[k] + (i + 1) * share], axis=1)
        return PulseTable(
            np.concatenate([block, np.full(pad, Mp)]), np.concatenate([gap, np.ones(pad, bool)]),
            np.concatenate([fraction, np.zeros(pad)]), geo,
            np.concatenate([role, np.full(pad, -1)]), first, first + n_sub - 1, arc_pieces, arc_span, M, Mp,
        )

    def cut_arcs(self, path: ToolPath, at: np.ndarray) -> "PulseTable":
        """The table with its sub-arcs cut at the path arc lengths ``at`` [mm] (any order; those not
        inside a sub-arc are ignored): the planner cuts the sub-arcs where its windows end, so that
        a window reaching into an arc slows the stretch it covers, not the whole sub-arc it ends in
        (``_fir_lookahead.arc_cuts``). No cut is made within :data:`MIN_CUT` of a sub-arc's length
        of either of its ends or of the cut before it.

        The pieces of a cut sub-arc take its own polynomial, each re-centred on its start (a Taylor
        shift; ``joins`` marks them): the input path is the same function as before the cut, only
        its pieces may now run at different feeds, and the first piece keeps the sub-arc's
        coefficients as they are. Their spans are the cut values themselves (a window ending at a
        cut overlaps the piece before it, not the one after); the sub-arcs not cut keep their rows."""
        A = self.arc_pieces.size
        at = np.unique(np.asarray(at, dtype=np.float64))
        if not A or not at.size:
            return self
        lo, hi = self.arc_span[:, 0], self.arc_span[:, 1]
        margin = MIN_CUT * (hi - lo)
        owner = np.minimum(np.searchsorted(hi, at, side="left"), A - 1)  # the sub-arc each may be inside
        inside = (at > lo[owner] + margin[owner]) & (at < hi[owner] - margin[owner])
        at, owner = at[inside], owner[inside]
        # and none within the margin of the cut before it in its sub-arc
        near = np.zeros(at.size, dtype=bool)
        near[1:] = (owner[1:] == owner[:-1]) & (np.diff(at) <= margin[owner[1:]])
        at, owner = at[~near], owner[~near]
        if not at.size:
            return self
        M, Mp = self.n_blocks, self.m_pad
        n_cut = np.bincount(owner, minlength=A)  # cuts inside each sub-arc
        P_real = int(np.searchsorted(self.block, M, side="left"))
        rows = np.ones(P_real, dtype=np.int64)
        rows[self.arc_pieces] += n_cut  # each sub-arc becomes 1 + its cuts pieces
        new_of = np.concatenate([[0], np.cumsum(rows)[:-1]])  # first new row of each old row
        src = np.repeat(np.arange(P_real), rows)
        block, gap, role, fraction = self.block[src], self.gap[src], self.role[src], self.fraction[src]
        geo = self.geo[src]
        joins = np.zeros(src.size, dtype=bool) if self.joins is None else self.joins[src]
        # the pieces of the cut sub-arcs, in order: offsets (block fractions) from the sub-arc's start
        cut = np.flatnonzero(n_cut)
        k = self.block[self.arc_pieces[cut]]  # their blocks
        parts = n_cut[cut] + 1
        own = np.repeat(np.arange(cut.size), parts)  # cut sub-arc of each piece
        j = np.arange(own.size) - np.repeat(np.cumsum(parts) - parts, parts)  # index within it
        share = self.fraction[self.arc_pieces[cut]]  # the sub-arc's block fraction
        inner = np.flatnonzero(j < parts[own] - 1)  # every piece but the last of its sub-arc ends at a cut
        # the cut's offset from its sub-arc's start, as a block fraction (arc length over the block's)
        offset = (at - lo[cut][own[inner]]) / path.lengths[k[own[inner]]]
        u0 = np.zeros(own.size)
        u1 = share[own].copy()
        u1[inner], u0[inner + 1] = offset, offset
        s0, s1 = lo[cut][own], hi[cut][own]
        s1[inner], s0[inner + 1] = at, at
        target = new_of[self.arc_pieces[cut]][own] + j
        fraction[target] = u1 - u0
        geo[target] = taylor_shift(self.geo[self.arc_pieces[cut]][own], u0)
        joins[target] = j > 0
        span = np.repeat(self.arc_span, 1 + n_cut, axis=0)
        at_cut = np.repeat(n_cut > 0, 1 + n_cut)
        span[at_cut, 0], span[at_cut, 1] = s0, s1
        arc_pieces = np.flatnonzero(np.repeat(np.isin(np.arange(P_real), self.arc_pieces), rows))
        P = src.size
        pad = bucket_size(P, 64) - P
        return PulseTable(
            np.concatenate([block, np.full(pad, Mp)]), np.concatenate([gap, np.ones(pad, bool)]),
            np.concatenate([fraction, np.zeros(pad)]), np.concatenate([geo, np.zeros((pad,) + geo.shape[1:])]),
            np.concatenate([role, np.full(pad, -1)]), new_of[self.first_motion],
            new_of[self.last_motion] + rows[self.last_motion] - 1, arc_pieces, span, M, Mp,
            np.concatenate([joins, np.zeros(pad, bool)]),
        )

    def pieces(self, head: np.ndarray, tail: np.ndarray, factor: np.ndarray,
               arc_rel: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Shares and feed factors of every piece for line heads / tails of shares ``head``,
        ``tail`` ``(M,)`` and feed factors ``factor`` ``(M, 3)`` (head, body, tail); a sub-arc takes
        its block's body factor times its own ``arc_rel`` ``(A,)`` (<= 1; default 1)."""
        (i0, b0), (i1, b1), (i2, b2), blk, column, real = self._roles
        frac = self.fraction.copy()
        frac[i0] = head[b0]
        frac[i1] = 1.0 - head[b1] - tail[b1]
        frac[i2] = tail[b2]
        f = factor[blk, column]
        if arc_rel is not None:
            f[self.arc_pieces] *= arc_rel
        return np.where(real, frac, 0.0), np.where(real, f, 1.0)

    def block_pieces(self, ks: np.ndarray, gaps: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """``(idx, owner)``: the pieces of blocks ``ks`` (ascending ``(K,)``), each block's motion
        pieces then (with ``gaps``) its gap piece (the path's last block has none), and the
        position in ``ks`` of each piece's block."""
        ks = np.asarray(ks, dtype=np.int64)
        first = self.first_motion[ks]
        counts = self.last_motion[ks] - first + 1 + ((ks < self.n_blocks - 1) if gaps else 0)
        owner = np.repeat(np.arange(ks.size), counts)
        return first[owner] + np.arange(owner.size) - np.repeat(np.cumsum(counts) - counts, counts), owner

    def pieces_at(self, idx: np.ndarray, head: np.ndarray, tail: np.ndarray, factor: np.ndarray,
                  arc_rel: np.ndarray | None = None, g: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`pieces` of the real pieces ``idx`` only (the same floats), with the block feed
        factors times ``g`` ``(M,)`` where given (``pieces(head, tail, factor * g[:, None])``):
        a few blocks' pieces without the whole path's."""
        idx = np.asarray(idx, dtype=np.int64)
        role, blk = self.role[idx], self.block[idx]
        frac = self.fraction[idx]  # a copy (fancy index)
        for k, share in ((0, lambda b: head[b]), (1, lambda b: 1.0 - head[b] - tail[b]), (2, lambda b: tail[b])):
            at = role == k
            frac[at] = share(blk[at])
        column = np.where(role < 0, 1, role)
        f = factor[blk, column] * g[blk] if g is not None else factor[blk, column]
        if arc_rel is not None and self.arc_pieces.size:
            pos = np.minimum(np.searchsorted(self.arc_pieces, idx), self.arc_pieces.size - 1)
            arc = self.arc_pieces[pos] == idx
            f[arc] *= arc_rel[pos[arc]]
        return frac, f

    @cached_property
    def _roles(self):
        """Index arrays of :meth:`pieces` (the head, body and tail pieces of lines and their blocks;
        each piece's block and factor column; the real pieces), made once per table."""
        blk = np.minimum(self.block, self.n_blocks - 1)
        rows = tuple((i, blk[i]) for i in (np.flatnonzero(self.role == k) for k in range(3)))
        return rows + (blk, np.where(self.role < 0, 1, self.role), self.block < self.n_blocks)


def _ranks(n: np.ndarray) -> np.ndarray:
    """``0 .. n_j - 1`` for every entry of ``n`` ``(J,)``, concatenated."""
    return np.arange(int(n.sum())) - np.repeat(np.cumsum(n) - n, n)


def _arc_pieces(path: ToolPath, arcs: np.ndarray, n: np.ndarray) -> np.ndarray:
    """``(sum n, DEGREE + 1, d)`` coefficients of ``dP/du`` on the ``n[j]`` equal sub-arcs of arc
    block ``arcs[j]``, in powers of ``u' = u - u_i`` (block fraction ``u = phi / Phi``), all arcs at
    once: ``dP/du`` at the Chebyshev nodes of every sub-arc, one interpolation solve per sub-arc
    (a batch of the same 6 x 6 system), and the constant term corrected so that each sub-arc
    integrates exactly to its chord."""
    x = 0.5 * (1.0 - np.cos(np.pi * (np.arange(DEGREE + 1) + 0.5) / (DEGREE + 1)))  # Chebyshev nodes in [0, 1]
    vander = np.vander(x, DEGREE + 1, increasing=True)
    owner = np.repeat(np.arange(arcs.size), n)  # arc of each sub-arc
    i = _ranks(n)  # index of each sub-arc in its arc
    block, sweep = arcs[owner], path.sweeps[arcs][owner]
    h = 1.0 / n[owner]
    u = h[:, None] * (i[:, None] + x[None, :])  # (S, DEGREE + 1)
    vel = (path.arc_derivatives(np.repeat(block, DEGREE + 1), (sweep[:, None] * u).reshape(-1), 1)
           * np.repeat(sweep, DEGREE + 1)[:, None]).reshape(-1, DEGREE + 1, path.dim)  # dP/du
    # sub-arc ends: the arc's points at its sub-arc angles, the block's own start and end at the ends
    ends0 = path.arc_points(block, sweep * h * i)
    ends1 = path.arc_points(block, sweep * h * (i + 1))
    first, last = i == 0, i == n[owner] - 1
    ends0[first] = path.starts[arcs]
    ends1[last] = path.ends[arcs]
    b = np.linalg.solve(vander[None], vel)  # coefficients in x = u' / h
    # exact chord: integral over the piece = h * sum b_m / (m + 1)
    b[:, 0] += (ends1 - ends0) / h[:, None] - np.sum(b / np.arange(1, DEGREE + 2)[None, :, None], axis=1)
    return b / h[:, None, None] ** np.arange(DEGREE + 1)[None, :, None]


@jax.jit
def build_profile(start, geo, block, gap, fraction, piece_tv, gaps, delays):
    """Schedule the pulses and filter them exactly.

    Args:
        start: ``(d,)`` start point [mm]; ``geo, block, gap, fraction``: a :class:`PulseTable`.
        fraction: ``(P,)`` share of its block's length taken by each piece.
        piece_tv: ``(P,)`` ``L / F`` of each piece's block length at that piece's feed [s] (the
            pulse length the whole block would take at it; padding: any positive value).
        gaps: ``(M_pad,)`` dwell after each block [s], ``T_d - T_k`` (0 after the last and on padding).
        delays: ``(n,)`` filter delays [s].

    Returns:
        ``(block_starts (M_pad,), block_ends (M_pad,), position PiecewisePolynomial, centre (M_pad,))``:
        the start and end of each block's pulse, the exact position, and the time at which the
        averaging window is centred on each corner's gap (the bisector point of eq 13/14).
    """
    gp = jnp.concatenate([gaps, jnp.zeros(1)])
    durations = jnp.where(gap, gp[block], fraction * piece_tv)
    breaks = jax.lax.cummax(jnp.concatenate([jnp.zeros(1), jnp.cumsum(durations)]))
    powers = jnp.arange(geo.shape[1], dtype=jnp.float64)
    scale = piece_tv[:, None] ** -(powers[None, :] + 1.0)  # d/dt = (1 / T_v) d/du, u' = tau / T_v
    coeffs = jnp.where(gap[:, None, None], 0.0, geo * scale[:, :, None])
    velocity = PiecewisePolynomial(breaks, coeffs)
    for i in range(delays.shape[0]):
        velocity = velocity.moving_average(delays[i])
    position = velocity.antiderivative(start)
    M = gaps.shape[0]
    # start of every block = break at its first piece, end = break at its gap piece
    first = jnp.searchsorted(block, jnp.arange(M), side="left")
    starts = breaks[first]
    ends = breaks[jnp.searchsorted(block, jnp.arange(M), side="right")] - gaps
    Td = jnp.sum(delays)
    centre = ends + 0.5 * gaps + 0.5 * Td
    return starts, ends, position, centre
