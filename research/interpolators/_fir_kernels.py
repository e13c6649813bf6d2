"""Compiled (Numba) kernels of the FIR look-ahead: window displacements and their root search, and
the searches and tolerance slack the other kernel modules share.

The look-ahead of ``fir`` evaluates, for every vertex ``j`` of a chain of short blocks, the windowed
displacement (``_fir_feed`` module docstring)::

    d_j(F) = F sum_i du_i H2(T_d / 2 - |s_i - s_j| / F),   |s_i - s_j| < F T_d / 2,

and finds the largest feed with ``|d_j(F)| <= eps`` by a safeguarded Newton search (its slope
``d d_j / dF`` summed in the same pass). In NumPy both are vectorised over the vertices, which costs
one array pass (and a Python step) per root-search iteration over all active vertices, and a ragged
gather per evaluation. Here each vertex is one scalar loop: its turns are summed in place, its
search runs to its own end. The truncated powers ``(r)_+^(n+1)`` are products (not C ``pow``), and
the Newton search takes 3-5 evaluations per vertex where the false-position search before it took
6-8, so the feeds agree with that search's to its resolution (~1e-9 relative), not bit for bit
(benchmarks/README.md, bench_cam section); ``tests/interpolators/test_fir_kernels.py`` checks the
kernels against slow independent computations. The look-ahead's dwell decisions need no search:
one evaluation of ``|d_j|`` at a break-even feed (``_fir_lookahead._dwell_cheaper``).

The other kernels: ``_fir_candidate_kernels`` (a candidate's windows, line pieces, range minima
and predicted cycle time) and ``_fir_verify_kernels`` (the sampled path check and the
corner-distance search). All are compiled on first use and cached on disk (``cache=True``): the
first call of a fresh checkout pays the compilation (about 16 s for all of them, measured at load
4; the verification kernels' specialisations add about 8 s, at load 2), later processes load it
(0.7 s).
"""


from __future__ import annotations

import math

import numba
import numpy as np

from research._sorted_search import left as _left, left_in as _left_in, right as _right, right_in as _right_in

_OPTIONS = dict(cache=True, nogil=True, error_model="numpy")

#: rounding slack of every tolerance check of the planner: an error [mm] passes a tolerance ``eps``
#: when ``<= eps (1 + VERIFY_RTOL) + VERIFY_ATOL`` (1e-9 relative and 1 pm absolute, for the rounding
#: of the exact profile's evaluation; far below any machine's resolution); ``plan_fir``'s checks add
#: the rounding each profile has accumulated by its end (``_fir_verify.profile_rounding``: nm on
#: programs of tens of minutes, where 1 pm would have the planner repair rounding)
VERIFY_RTOL, VERIFY_ATOL = 1e-9, 1e-9


#: the cancellation the chunked prefix sums of a window may cost, in ulps of its own terms
#: (``_window_displacement``): 2^20, a relative error of about 2e-10, below the feed search's
#: stopping band (``_fir_feed._CLOSE``: 2^-30 ~ 9e-10 in log |d_j|)
_NEAR_BUDGET = 2.0 ** 20


def verified_bound(tolerance):
    """The largest error [mm] that passes ``tolerance`` [mm] (scalar or array), rounding slack included."""
    return tolerance * (1.0 + VERIFY_RTOL) + VERIFY_ATOL


@numba.njit(**_OPTIONS)
def _ipow(r, m):
    """``r^m`` for an integer ``m >= 0`` by repeated multiplication (``m`` is ``n + 1 - k`` here:
    at most a few factors)."""
    out = 1.0
    for _ in range(m):
        out *= r
    return out


@numba.njit(**_OPTIONS)
def _displacement(s, du, rho, sign, p, norm, prefix, binom, direct, q, F, out, dout):
    """``d_j`` at the re-centred arc length ``q`` for feed ``F`` into ``out`` ``(d,)`` and its
    derivative ``d d_j / dF`` into ``dout`` ``(d,)``: a direct sum over the window's turns when it
    holds at most ``direct`` of them, else the prefix sums (``ChainError.displacement``).
    (:func:`_window_displacement` with its scratch made here.)"""
    w = np.empty(max(direct, 0))
    _window_displacement(s, du, rho, sign, p, norm, prefix, binom, direct, q, F, out, dout, True, w, np.empty_like(w))


@numba.njit(inline="always", **_OPTIONS)
def _window_displacement(s, du, rho, sign, p, norm, prefix, binom, direct, q, F, out, dout, slope, w, wd):
    """:func:`_displacement` with the scratch ``w, wd`` of the direct sums (``direct`` floats each); where
    ``slope`` is False the direct sums of three axes and two filters leave ``dout`` unset (the
    values ``out`` are the same: they do not read the derivative). Inlined into its callers (a call
    per evaluation cost about a fifth of the root search's time).

    Direct sum: each turn adds ``du_i norm F sum_r sign_r (rho_r - x_i)_+^p`` with
    ``x_i = |s_i - q| / F``; since ``d x_i / dF = -x_i / F`` its derivative is
    ``du_i norm sum_r sign_r (rho_r - x_i)_+^(p-1) (rho_r - x_i + p x_i)`` (the boundary of the
    window adds nothing: ``(.)_+^p`` is ``C^(p-1)``). Summed turn by turn in index order
    (:func:`_direct_sum`).

    Chunked prefix sums (windows of more than ``direct`` turns): ``d_j = norm F^(1-p) S(F)`` with
    ``S = sum_i sum_r sign_r (F rho_r - |s_i - q|)_+^p du_i``. The turns are cut into chunks of
    ``C`` turns (``prefix`` ``(K, C + 2, p + 1, d)``, ``ChainError.prefix``); a chunk within
    ``q +- (kappa - 2) R`` (``R = F max rho``) adds,
    per subset term and side of ``q``, a polynomial in ``F rho_r +- (q - o_c)`` whose coefficients
    are the chunk's prefix sums of ``du_i (s_i - o_c)^m`` about its own first turn ``o_c``; the
    window's turns in a chunk reaching farther out are summed directly. Every re-centred quantity
    is then within ``kappa R`` of 0 (``kappa = _NEAR_BUDGET^(1/p)``), so the binomial cancellation
    costs at most about ``kappa^p = 2^20`` ulps, 2e-10 of the window's own terms, wherever the window
    lies on the path (one origin for the whole chain lost all precision on long programs: 22 um of 50
    at 26 m of path, metres at 165 m)."""
    R = F * np.max(rho)
    first = _right(s, q - R)
    count = _left(s, q + R) - first
    if count <= direct:
        _direct_sum(s, du, rho, sign, p, norm, q, F, first, count, out, dout, slope, w, wd)
        return
    d = du.shape[1]
    for k in range(d):
        out[k] = 0.0
        dout[k] = 0.0
    T = s.size
    C = prefix.shape[1] - 2
    last = first + count
    at = _left(s, q)
    rp, lp = np.empty(p + 1), np.empty(p + 1)  # powers of the re-centred window ends
    near = R * (_NEAR_BUDGET ** (1.0 / p) - 2.0)  # a chunk's prefix sums are read within q +- near
    for c in range(first // C, (last - 1) // C + 1):
        lo, hi = c * C, min((c + 1) * C, T)
        if not (s[lo] > q - near and s[hi - 1] < q + near):  # a chunk reaching far out: its turns
            _cut_turns(s, du, rho, sign, p, q, F, max(lo, first), min(hi, last), out, dout)
            continue
        if prefix[c, C + 1, 0, 0] == 0.0:  # not filled yet
            _fill_chunk(prefix, s, du, c, lo, hi, p)
        shift = q - s[lo]
        for r_i in range(rho.size):
            rr = rho[r_i]
            Rr = F * rr
            # this subset term's turns in the chunk, right of q: [r0, r1); left of q: [l0, l1)
            r0 = min(max(at, lo), hi)
            r1 = hi if s[hi - 1] < q + Rr else _left_in(s, q + Rr, r0, hi)
            l1 = max(min(at, hi), lo)
            l0 = lo if s[lo] > q - Rr else _right_in(s, q - Rr, lo, l1)
            if r1 > r0:
                _chunk_side(prefix, c, r0 - lo, r1 - lo, Rr + shift, -1.0, rr, sign[r_i], binom, p, rp, out, dout)
            if l1 > l0:
                _chunk_side(prefix, c, l0 - lo, l1 - lo, Rr - shift, 1.0, rr, sign[r_i], binom, p, lp, out, dout)
    if F > 0:
        scale = _ipow(1.0 / F, p - 1) * norm
        dscale = scale * (1.0 - p) / F
    else:
        scale = dscale = 0.0
    for k in range(d):
        dout[k] = dscale * out[k] + scale * dout[k]
        out[k] *= scale


@numba.njit(**_OPTIONS)
def _fill_chunk(prefix, s, du, c, lo, hi, p):
    """Fill chunk ``c`` (turns ``lo .. hi - 1``) of ``ChainError.prefix``: ``prefix[c, j, m]`` the sum
    over its first ``j`` turns of ``du_i (s_i - s_lo)^m`` (powers by repeated multiplication), and
    its flag ``prefix[c, C + 1, 0, 0] = 1``."""
    for m in range(p + 1):
        for k in range(du.shape[1]):
            prefix[c, 0, m, k] = 0.0
    for j in range(hi - lo):
        i = lo + j
        sig = s[i] - s[lo]
        pw = 1.0
        for m in range(p + 1):
            for k in range(du.shape[1]):
                prefix[c, j + 1, m, k] = prefix[c, j, m, k] + du[i, k] * pw
            pw *= sig
    prefix[c, prefix.shape[1] - 1, 0, 0] = 1.0  # filled


@numba.njit(**_OPTIONS)
def _chunk_side(prefix, c, j0, j1, end, sgn, rr, sign, binom, p, pw, out, dout):
    """Turns ``j0 .. j1 - 1`` of chunk ``c`` on one side of ``q``, added to ``S`` and ``dS / dF`` of
    :func:`_window_displacement` from the chunk's prefix sums ``P_m`` about its origin ``o``:
    ``sum_i du_i (end + sgn (s_i - o))^p = sum_m C(p, m) end^(p - m) sgn^m P_m`` (``end``: the
    subset term's window end re-centred on ``o``, ``F rho_r + q - o`` right of ``q`` with
    ``sgn = -1``, ``F rho_r - q + o`` left of it with ``sgn = +1``; ``d end / dF = rho_r``)."""
    pw[0] = 1.0
    for e in range(1, p + 1):
        pw[e] = pw[e - 1] * end
    sm = 1.0
    for m in range(p + 1):
        e = p - m
        w = sign * binom[m] * sm
        cv = w * pw[e]
        cd = w * e * rr * pw[e - 1] if e > 0 else 0.0
        for k in range(out.size):
            P = prefix[c, j1, m, k] - prefix[c, j0, m, k]
            out[k] += cv * P
            dout[k] += cd * P
        sm *= sgn


@numba.njit(**_OPTIONS)
def _cut_turns(s, du, rho, sign, p, q, F, lo, hi, out, dout):
    """Turns ``lo .. hi - 1`` (the window's turns in a chunk reaching far beyond it, whose prefix
    sums would cancel too much), added to ``S`` and ``dS / dF`` of :func:`_window_displacement`
    term by term: ``sign_r y^p du_i`` and ``sign_r p rho_r y^(p-1) du_i``
    with ``y = F rho_r - |s_i - q| > 0``."""
    for i in range(lo, hi):
        dist = abs(s[i] - q)
        for r_i in range(rho.size):
            y = F * rho[r_i] - dist
            if y > 0.0:
                t = sign[r_i] * _ipow(y, p - 1)
                h = t * y
                g = t * p * rho[r_i]
                for k in range(du.shape[1]):
                    out[k] += h * du[i, k]
                    dout[k] += g * du[i, k]


@numba.njit(inline="always", **_OPTIONS)
def _direct_sum(s, du, rho, sign, p, norm, q, F, first, count, out, dout, slope, w, wd):
    """The direct sum of :func:`_window_displacement` over the turns ``first .. first + count - 1``
    into ``out`` (and ``dout`` if ``slope``); ``w, wd``: scratch of at least ``count`` floats.

    Three axes and two filters of unequal delays (``p = 3``, two terms ``rho``): each turn's weights
    ``h norm F`` and ``g norm`` first, in one loop without branches (a term whose ``rho_r - x_i``
    is not positive is taken as ``sign_r 0^2 0 = +-0``, which leaves a sum unchanged, as the
    general loop's skip does; the square is ``_ipow``'s product ``1.0 * r * r``), then the six
    sums in turn order. The same floating-point operations in the same order as the general loop:
    the sums are the same bit for bit, but the first loop's divisions run in vector registers."""
    d = du.shape[1]
    if d == 3 and p == 3 and rho.size == 2 and F > 0:
        rA, rB, sA, sB = rho[0], rho[1], sign[0], sign[1]
        for m in range(count):
            x = abs(s[first + m] - q) / F
            r = max(rA - x, 0.0)
            r1 = sA * (r * r)
            h = 0.0 + r1 * r
            g = 0.0 + r1 * (r + p * x)
            r = max(rB - x, 0.0)
            r1 = sB * (r * r)
            h += r1 * r
            g += r1 * (r + p * x)
            w[m] = h * norm * F
            wd[m] = g * norm
        _weighted_turns3(w, du, first, count, out)
        if slope:
            _weighted_turns3(wd, du, first, count, dout)
        return
    for k in range(d):
        out[k] = 0.0
        dout[k] = 0.0
    for i in range(first, first + count):
        x = abs(s[i] - q) / F if F > 0 else np.inf
        h = 0.0
        g = 0.0
        for r_i in range(rho.size):
            r = rho[r_i] - x
            if r > 0.0:  # (r)_+^p: a term of 0 adds nothing (skipped, the same sum)
                r1 = sign[r_i] * _ipow(r, p - 1)
                h += r1 * r
                g += r1 * (r + p * x)
        wi = h * norm * F
        wdi = g * norm
        for k in range(d):
            out[k] += wi * du[i, k]
            dout[k] += wdi * du[i, k]


@numba.njit(inline="always", **_OPTIONS)
def _weighted_turns3(w, du, first, count, out):
    """``out[k] = sum_m w[m] du[first + m, k]`` for the three axes, summed in turn order (:func:`_direct_sum`)."""
    o0 = o1 = o2 = 0.0
    for m in range(count):
        i = first + m
        o0 += w[m] * du[i, 0]
        o1 += w[m] * du[i, 1]
        o2 += w[m] * du[i, 2]
    out[0], out[1], out[2] = o0, o1, o2


@numba.njit(**_OPTIONS)
def chain_displacements(s, du, rho, sign, p, norm, prefix, binom, direct, q, F):
    """``(J, d)`` displacements ``d_j`` at re-centred arc lengths ``q`` ``(J,)`` for feeds ``F`` ``(J,)``."""
    out = np.zeros((q.size, du.shape[1]))
    scratch = np.zeros(du.shape[1])
    w, wd = np.empty(max(direct, 0)), np.empty(max(direct, 0))
    for j in range(q.size):
        _window_displacement(s, du, rho, sign, p, norm, prefix, binom, direct, q[j], F[j], out[j], scratch, False, w,
                             wd)
    return out


@numba.njit(inline="always", **_OPTIONS)
def _log_error(s, du, rho, sign, p, norm, prefix, binom, direct, q, F, t, tiny, buf, dbuf, w, wd):
    """``(g, g')``: ``g = log(max(|d_j(F)|, tiny t) / t)`` and its slope ``d g / d log F =
    F (d_j . d_j') / |d_j|^2`` (NaN where the error is floored: no slope there); ``w, wd``: the
    scratch of :func:`_window_displacement`."""
    _window_displacement(s, du, rho, sign, p, norm, prefix, binom, direct, q, F, buf, dbuf, True, w, wd)
    acc = 0.0
    dot = 0.0
    for k in range(buf.size):
        acc += buf[k] * buf[k]
        dot += buf[k] * dbuf[k]
    e = math.sqrt(acc)
    if e <= tiny * t:
        return math.log(tiny), np.nan
    return math.log(e / t), F * dot / acc


@numba.njit(**_OPTIONS)
def chain_largest_feeds(s, du, rho, sign, p, norm, prefix, binom, direct, q, hi, tol, e_hi, steps, close, tiny, start):
    """Largest feed ``<= hi`` with ``|d_j| <= tol`` for every query (``ChainError.largest_feed``).

    Safeguarded Newton in log space: ``g(x) = log(|d_j(e^x)| / tol)``, ``x = log F`` (the error is
    nearly a power of the feed, so ``g`` is nearly linear in ``x``), with its exact slope from
    :func:`_displacement`. The first point is ``F = hi tol / |d_j(hi)|`` (feasible where the error
    grows at least linearly in feed); each step aims at ``g = -close / 2``, the middle of the
    stopping band ``(-close, 0]``, from the last point evaluated. A step that leaves the bracket
    ``[l, h]`` (feasible low end, infeasible high end), or a point without slope, falls back to a
    false-position step in log space with the Illinois modification (Dowell & Jarratt 1971), or to
    bisection while the low end is 0. Steps stay half a resolution inside the bracket.

    Args:
        q: ``(J,)`` re-centred arc lengths; hi, tol, e_hi: ``(J,)`` feed bound, tolerance and
            ``|d_j(hi)|``; steps, close, tiny: the search's resolution exponent, stopping distance
            (log ratio) and error floor (``_fir_feed``'s constants); start: ``(J,)`` first points
            (a warm start: the root of a nearby problem; infeasible there, it is the bracket's high
            end and Newton goes on from it) or an empty array (the power-law point).

    Returns:
        ``(J,)`` feeds [mm/s]: the low end of the bracket when its ``g`` is within ``close`` of 0,
        the bracket is ``2^-steps`` of its start, or after ``2 steps`` evaluations.
    """
    J = q.size
    buf = np.zeros(du.shape[1])
    dbuf = np.zeros(du.shape[1])
    w, wd = np.empty(max(direct, 0)), np.empty(max(direct, 0))
    out = np.empty(J)
    for j in range(J):
        out[j] = _feed_search(s, du, rho, sign, p, norm, prefix, binom, direct, q[j], hi[j], tol[j], e_hi[j], steps,
                              close, tiny, buf, dbuf, w, wd, start[j] if start.size else 0.0)
    return out


@numba.njit(**_OPTIONS)
def _feed_search(s, du, rho, sign, p, norm, prefix, binom, direct, qj, hj, t, e, steps, close, tiny, buf, dbuf, w, wd,
                 x0):
    """One query of :func:`chain_largest_feeds`; ``x0``: its first point where in ``(0, hi)`` (else
    the power-law point ``hi tol / |d_j(hi)|``)."""
    h = hj
    if e <= t:
        return h
    if not t > 0:
        return 0.0
    resolution = 0.5 ** steps
    target = -0.5 * close
    g_h = math.log(e / t)
    warm = 0.0 < x0 < h
    x = x0 if warm else h * t / e
    l, g_l, g_low = 0.0, -np.inf, -np.inf  # g_low: the low end's own g (g_l is Illinois-weighted)
    width = h * resolution
    side = 0
    for it in range(2 * steps):
        gx, slope = _log_error(s, du, rho, sign, p, norm, prefix, binom, direct, qj, x, t, tiny, buf, dbuf, w, wd)
        if gx <= 0:
            if side == -1:
                g_h = 0.5 * g_h
            g_l, g_low, l = gx, gx, x
            side = -1
        elif it == 0 and not warm:  # the first point is infeasible: the bracket stays [0, hi], bisected
            x = 0.5 * h
            continue
        else:
            if side == 1:
                g_l = 0.5 * g_l
            g_h, h = gx, x
            side = 1
        if not (h - l > width and g_low < -close):
            break
        guard = 0.5 * width
        nxt = math.exp(math.log(x) - (gx - target) / slope) if slope > 0 else np.nan
        if not (l + guard <= nxt <= h - guard):  # no slope, or a step out of the bracket
            if l > 0:
                xl = math.log(l)
                nxt = math.exp(xl + (math.log(h) - xl) * (-g_l) / (g_h - g_l))
            else:
                nxt = 0.5 * h  # no power law through F = 0: bisect
            if nxt != nxt:
                nxt = 0.5 * (l + h)
            nxt = min(max(nxt, l + guard), h - guard)
        x = nxt
    return l
