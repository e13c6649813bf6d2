"""Look-ahead feeds for FIR cornering of arcs and chains of short blocks (beyond Sencer 2015).

The paper bounds the error of one corner between two long blocks (eq 13/14). On CAM programs the
averaging window ``T_d`` spans many blocks, and what it averages is the path itself. Two closed
forms of the FIR chain's kernel give feeds that keep the tolerance there:

* **Arcs** (eq 8): a constant-speed circular motion of radius ``R`` at feed ``F`` comes out of the
  chain as a circle of radius ``R prod_i sinc(Omega T_i / 2)``, ``Omega = F / R``, with
  ``sinc(x) = sin(x) / x``. The radial error ``R (1 - prod sinc)`` rises with ``F``; the arc's feed
  is the largest one that keeps it within the tolerance (:func:`arc_feed_caps`).
* **Chains of short blocks**: with full overlap and a constant feed ``F`` the input position runs
  the path at ``F`` and each direction change ``du_i`` (at arc length ``s_i``) is a velocity step
  ``F du_i``. The output, taken at the instant the window is centred on a vertex at ``s_j``, is
  displaced from that vertex by exactly (superposition of eq 13/14's bisector term)::

      d_j(F) = F sum_i du_i H2(T_d / 2 - |s_i - s_j| / F),   |s_i - s_j| < F T_d / 2,

  with ``H2`` the second integral of the chain's impulse response (``_fir_chain``). For one
  isolated corner this is eq 13/14 at full overlap; for a circle tessellated into chords it is the
  sinc shrink above (to the chord error); for chords that zigzag about a smooth curve (rounded
  CAM coordinates) the alternating ``du_i`` cancel, which the per-corner rule cannot see.
  ``|d_j|`` bounds the distance from the vertex to the trajectory; the largest feed with
  ``|d_j(F)| <= eps`` is found by a safeguarded Newton search (:meth:`ChainError.largest_feed`), each
  evaluation a direct sum over the window's turns (or, for windows of very many turns, prefix sums
  of ``du_i (s_i - o)^m`` over chunks of turns, each about its own origin ``o``: ``H2`` is a
  truncated power of degree ``n + 1``).

Where a single sharp corner needs a slow-down, the paper's dwell (partial overlap, eq 13/14) is
cheaper; the look-ahead of ``fir`` picks per corner the option of lower estimated time. Everything is
verified on the exact profile afterwards (``fir``), so these feeds are a starting point whose
quality sets the cycle time, not the tolerance.
"""

from __future__ import annotations

import itertools
import math

import numpy as np

from research.interpolators._fir_kernels import chain_displacements, chain_largest_feeds


_ARC_STEPS = 60  # arc feeds to machine precision (cheap: one evaluation per arc and step)
_DIRECT = 64  # windows of at most this many direction changes are summed directly
_CHUNK = 1024  # turns per chunk of the prefix sums of larger windows (ChainError.prefix)
_BISECTION_STEPS = 36  # feed resolution F_max / 2^36, below 1e-10 F
_CLOSE = 0.5 ** 30  # a feed whose |d_j| is this close below eps (log ratio) is the root (to ~1e-9 F)
_TINY = 1e-12  # floor of |d_j| / eps in the log-space secant (an error 1e-12 eps is no error)


def _subsets(delays: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Sums ``sigma_S`` and signs ``(-1)^|S|`` over all subsets of the filters."""
    sums, signs = [], []
    for pick in itertools.product((0, 1), repeat=delays.size):
        sums.append(float(np.dot(pick, delays)))
        signs.append((-1.0) ** sum(pick))
    return np.asarray(sums), np.asarray(signs)


def arc_feed_caps(radii: np.ndarray, delays: np.ndarray, tolerance: np.ndarray, feed: np.ndarray) -> np.ndarray:
    """Largest feed ``<= feed`` [mm/s] whose steady radial error ``R (1 - prod sinc(F T_i / 2R))``
    (eq 8) is at most ``tolerance`` [mm]; ``feed`` where ``radii`` is ``inf`` (lines).

    Example (60/30 ms filters, R = 20 mm, eps = 50 um; the small-angle form
    ``F ~ sqrt(24 R eps / sum T_i^2)`` gives 73.03 mm/s):
        >>> round(float(arc_feed_caps(np.array([20.0]), np.array([0.06, 0.03]), np.array([0.05]), np.array([150.0]))[0]), 2)
        73.06
    """
    r = np.asarray(radii, dtype=np.float64)
    d = np.asarray(delays, dtype=np.float64)
    out = np.array(np.broadcast_to(feed, r.shape), dtype=np.float64)
    arc = np.isfinite(r)
    if not arc.any():
        return out
    R, eps, hi = r[arc], np.broadcast_to(tolerance, r.shape)[arc], out[arc]

    def error(F):
        x = F[:, None] * d[None, :] / (2.0 * R[:, None])
        return R * (1.0 - np.prod(np.sinc(x / np.pi), axis=1))

    # the shrink is monotone while the argument stays below pi (the first zero of sinc)
    hi = np.minimum(hi, 2.0 * np.pi * R / d.max())
    ok = error(hi) <= eps
    lo = np.where(ok, hi, 0.0)
    top = hi.copy()
    for _ in range(_ARC_STEPS):
        mid = 0.5 * (lo + top)
        good = error(mid) <= eps
        lo = np.where(ok, lo, np.where(good, mid, lo))
        top = np.where(ok | good, top, mid)
    out[arc] = lo
    return out


class ChainError:
    """``|d_j(F)|`` of the module docstring for query points on one turn list.

    Args:
        s: ``(T,)`` arc length of every direction change [mm], non-decreasing.
        du: ``(T, d)`` direction change ``u_{i+1} - u_i`` there.
        delays: filter delays [s].
    """

    def __init__(self, s: np.ndarray, du: np.ndarray, delays: np.ndarray):
        self.delays = np.sort(np.asarray(delays, dtype=np.float64))[::-1]
        self.p = self.delays.size + 1
        self.Td = float(self.delays.sum())
        self.norm = 1.0 / (math.factorial(self.p) * float(np.prod(self.delays)))
        sums, signs = _subsets(self.delays)
        keep = sums < 0.5 * self.Td
        self.rho, self.sign = 0.5 * self.Td - sums[keep], signs[keep]
        self.origin = 0.5 * (float(s[0]) + float(s[-1])) if s.size else 0.0
        self.s = np.asarray(s, dtype=np.float64) - self.origin
        du = np.ascontiguousarray(du, dtype=np.float64).reshape(-1, np.shape(du)[-1])
        self.du = du
        self._prefix = None
        self.binom = np.array([math.comb(self.p, m) for m in range(self.p + 1)], dtype=np.float64)

    @property
    def prefix(self) -> np.ndarray:
        """``(K, C + 2, p + 1, d)`` prefix sums of ``du * (s - o_c)^m``, ``m = 0 .. p``, restarted in
        every chunk ``c`` of ``C =`` :data:`_CHUNK` turns about its first turn's arc length ``o_c``
        (``K`` chunks; ``[c, j, m]``: the chunk's first ``j`` turns; ``[c, C + 1, 0, 0]``: 1 once the
        chunk is filled). Made on first use as zeros, which the system maps without writing them;
        the kernels fill a chunk when a window first reads it (``_fir_kernels._window_displacement``),
        so only the chunks of dense windows cost time or memory. A chain is read by one thread, the
        plan that made it: two threads filling one chunk at once would race."""
        if self._prefix is None:
            K = -(-self.s.size // _CHUNK)
            self._prefix = np.zeros((K, _CHUNK + 2, self.p + 1, self.du.shape[1]))
        return self._prefix

    def __call__(self, s_query: np.ndarray, feed: np.ndarray) -> np.ndarray:
        """``|d_j|`` [mm] at arc lengths ``s_query`` [mm] for feeds ``feed`` [mm/s] (both ``(J,)``)."""
        return np.linalg.norm(self.displacement(s_query, feed), axis=1)

    def _args(self, q=None, F=None):
        """The kernels' chain arguments; for re-centred queries ``q`` at feeds up to ``F``, the
        prefix sums only where one of their windows holds more than :data:`_DIRECT` turns (a
        window grows with the feed; the count is the kernels' own, ``_fir_kernels._displacement``),
        an empty array where every window is summed directly."""
        prefix = None
        if self._prefix is None and q is not None:
            R = F * np.max(self.rho)
            count = np.searchsorted(self.s, q + R, side="left") - np.searchsorted(self.s, q - R, side="right")
            if not np.any(count > _DIRECT):
                prefix = np.zeros((0, _CHUNK + 2, self.p + 1, self.du.shape[1]))
        if prefix is None:
            prefix = self.prefix
        return (self.s, self.du, self.rho, self.sign, self.p, self.norm, prefix, self.binom, _DIRECT)

    def displacement(self, s_query: np.ndarray, feed: np.ndarray) -> np.ndarray:
        """``d_j`` ``(J, d)`` [mm] at arc lengths ``s_query`` [mm] for feeds ``feed`` [mm/s].

        Windows holding at most :data:`_DIRECT` direction changes are summed directly (exact in
        floating point whatever the window's size against the path), each over its own turns only;
        larger ones through the chunked prefix sums (:attr:`prefix`), whose binomial re-centring
        loses a few hundred ulps of the window's own terms wherever it lies on the path. One
        compiled loop over the queries (``_fir_kernels.chain_displacements``)."""
        q = np.asarray(s_query, dtype=np.float64).reshape(-1) - self.origin
        F = np.ascontiguousarray(np.broadcast_to(np.asarray(feed, dtype=np.float64), q.shape))
        return chain_displacements(*self._args(q, F), q, F)

    def largest_feed(self, s_query: np.ndarray, feed_max: np.ndarray, tolerance: np.ndarray,
                     error_max: np.ndarray | None = None, start: np.ndarray | None = None) -> np.ndarray:
        """Largest feed ``<= feed_max`` with ``|d_j| <= tolerance``, by a safeguarded Newton search
        that keeps the tolerance at its lower end. The first point is ``F eps / |d_j(F)|``, feasible
        whenever the error grows at least linearly in feed (eq 13/14 corners: linearly; chains and
        arcs: quadratically; where it is not, the bracket is ``[0, F]`` and its first step bisects).
        Each step is Newton's on ``log |d_j|`` against ``log F`` (the error is nearly a power of the
        feed, so the step lands close to the root at once) with the exact slope ``d d_j / dF``
        evaluated in the same pass over the window's turns; it aims at the middle of the stopping
        band ``(-_CLOSE, 0]`` of ``log(|d_j| / eps)``. A step that leaves the bracket (or a point
        whose error is floored, without a slope) falls back to a false-position step on the same
        logarithms with the Illinois modification (Dowell & Jarratt 1971). It stops when the low
        end's error is within ``_CLOSE`` (log ratio) of the tolerance, when the bracket is
        ``2^-_BISECTION_STEPS`` of the feed bound, or after ``2 * _BISECTION_STEPS`` evaluations
        (3-5 per query on the CAM programs, against 6-8 for the false-position search it replaced).
        Each query's search is one compiled scalar loop (``_fir_kernels.chain_largest_feeds``).
        Where ``|d_j|`` is not monotone in the feed (alternating turns), the bracket may hold more
        than one root and the search returns one of them (a feasible feed, not always the largest).

        ``error_max``: ``|d_j(feed_max)|`` where the caller has it already (saves one evaluation).
        ``start``: ``(J,)`` first points of the search (a warm start from a nearby problem's roots,
        used where within ``(0, feed_max)``), or None (the power-law point above); the result is a
        feed of the same stopping band, not the same float."""
        hi = np.array(feed_max, dtype=np.float64).reshape(-1)
        tol = np.ascontiguousarray(np.broadcast_to(np.asarray(tolerance, dtype=np.float64), hi.shape))
        e = self(s_query, hi) if error_max is None else np.array(error_max, dtype=np.float64).reshape(-1)
        q = np.asarray(s_query, dtype=np.float64).reshape(-1) - self.origin
        first = np.zeros(0) if start is None else np.ascontiguousarray(np.broadcast_to(start, hi.shape), dtype=np.float64)
        out = chain_largest_feeds(*self._args(q, hi), q, hi, tol, e, _BISECTION_STEPS, _CLOSE, _TINY, first)
        zero = tol <= 0
        if zero.any():
            out[zero] = self.reach_free_feed(q[zero], hi[zero])
        return out

    def reach_free_feed(self, q: np.ndarray, feed_max: np.ndarray) -> np.ndarray:
        """The largest feed ``<= feed_max`` [mm/s] at which no direction change lies strictly
        inside the window of the (re-centred) arc lengths ``q`` [mm]: ``|d_j| = 0`` exactly there
        (every term of the module docstring's sum vanishes), and above it a turn enters and
        ``|d_j| > 0``. The root of a zero tolerance in closed form: the window sums the turns with
        ``|s_i - s_j| < F max(rho)`` (``rho``: the kernel's half-supports), so it is ``min |s_i -
        s_j| / max(rho)`` over the turns with ``du_i != 0`` (0 where the query's own turn is one).
        The Newton search cannot take it (its stopping band is relative to the tolerance)."""
        turning = np.any(self.du != 0.0, axis=1)
        s_t = self.s[turning]
        if not s_t.size:
            return np.array(feed_max, dtype=np.float64)
        i = np.searchsorted(s_t, q)
        right = np.abs(s_t[np.minimum(i, s_t.size - 1)] - q)
        left = np.abs(q - s_t[np.maximum(i - 1, 0)])
        return np.minimum(feed_max, np.minimum(left, right) / float(np.max(self.rho)))
