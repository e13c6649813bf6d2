"""The FIR planner's schedule and exact profile on concrete arrays (NumPy + Numba), for its rounds.

``plan_fir`` decides on primal values: which corners dwell, which feeds a window lowers, which
corners a verification round repairs. Those rounds need the timing of a candidate (eq 5 pulse
lengths, eq 13/14 overlaps) and its exact filtered profile, many times per plan; built with JAX
(``_fir_settle._timing_kernel``, ``_fir_blocks.build_profile``) each costs a dispatch and a device sync,
and XLA's moving average (a general merge by two searches and a gather) dominates long paths. Here
the same formulas run on NumPy arrays: :func:`timing` mirrors ``_fir_settle._timing_kernel`` and
:func:`profile` mirrors ``build_profile`` (the same pieces, padding included, so a plan built here
has the same arrays as the JAX one up to rounding). The moving average of a piecewise polynomial
(Sencer 2015 eq 1-4: ``y(t) = (C(t) - C(t - T)) / T`` with ``C`` the antiderivative) is one linear
merge of the breaks ``b`` and ``b + T``, each new piece two Taylor re-centrings
(:func:`_moving_average`), as ``research.piecewise.PiecewisePolynomial.moving_average``.

Times and integrals as double-doubles: the breaks are absolute times, and after hours of motion
``b + T`` rounds by ~1e-11 s; a local time or piece length taken from rounded absolute breaks moved
every piece's value, and the running integrals (``C`` and the position) lost the digits of a large
displacement, so the profile drifted off the path (6.4 um at the end of a 5.2 h plan; the checks
took the drift as slack). Here the breaks carry their rests (``lo``: the input's running sum by
two-sums, each merged ``b + T`` by one), lengths and local times are differences of breaks first
(:func:`_between`), ``C(t) - C(t - T)`` is a running double-double sum of the pieces between
(:func:`_window_add`) and the position's constants one of all pieces (:func:`_add`); the returned breaks are the rounded ones (a local time off by their rest,
< 1e-11 s, does not accumulate). The same 5.2 h plan ends 8.5e-14 mm from the path's end. The
JAX form keeps plain sums (its plans are short: gradients of one plan).

JAX stays the differentiable form: ``plan_fir`` rebuilds the chosen plan with it when an input is
a tracer (``jax.grad`` / ``jax.jacfwd``).
"""

from __future__ import annotations

import functools
import math

import equinox as eqx
import jax
import numba
import numpy as np

from research._device import device_array, device_arrays
from research.interpolators._illinois import narrowed, secant_point
from research.piecewise import PiecewisePolynomial

_OPTIONS = dict(cache=True, nogil=True, error_model="numpy")


class _PathPieces:
    """The path's piece table (shared with its cache, not copied) and the position once built: a
    plain object, hashed by identity, so that it can be a static field."""

    __slots__ = ("table", "built")

    def __init__(self, table):
        self.table, self.built = table, None


class ProfileInputs(eqx.Module):
    """What rebuilds a plan's exact position profile (:func:`profile`), in place of its
    coefficients: the per-piece timing, the corner gaps and the delays; the pieces' geometry is the
    path's own ``_fir_blocks.PulseTable``: ``2 P + M_pad`` floats against the profile's
    ``K ((D + n + 1) d + 1) + 1`` (``K <= 2^n (P + 1)`` pieces: each filter merges the breaks ``b``
    and ``b + T``, the last closes with a rest piece; ``D`` coefficient rows of the input pieces).

    Attributes:
        fraction: ``(P,)`` share of its block's pulse time taken by each piece.
        piece_tv: ``(P,)`` pulse length [s] of each piece's block at the piece's feed (eq 5).
        gaps: ``(M_pad,)`` dwell ``T_d - T_k`` [s] after each block (0 after the last and padding).
        delays: ``(n,)`` filter delays [s]; start: ``(d,)`` start point [mm].
        span: ``(2,)`` first and last break of the profile [s] (its cycle time without a rebuild).
    """

    fraction: np.ndarray
    piece_tv: np.ndarray
    gaps: np.ndarray
    delays: np.ndarray
    start: np.ndarray
    span: jax.Array
    pieces: _PathPieces = eqx.field(static=True)

    def __init__(self, table, fraction, piece_tv, gaps, delays, start, span):
        self.fraction, self.piece_tv, self.gaps, self.delays, self.start = fraction, piece_tv, gaps, delays, start
        self.span, self.pieces = device_array(span), _PathPieces(table)

    def position(self) -> PiecewisePolynomial:
        """The exact position profile [mm], built on the first call (the same arrays as the
        planner's, which built it from the same inputs) and kept."""
        if self.pieces.built is None:
            t = self.pieces.table
            _, _, breaks, coeffs, _ = profile(self.start, t.geo, t.block, t.gap, self.fraction, self.piece_tv, self.gaps,
                                              self.delays, t.joins)
            self.pieces.built = PiecewisePolynomial(*device_arrays(breaks, coeffs))
        return self.pieces.built

    def durations(self) -> np.ndarray:
        """``(P,)`` length [s] of every input piece, the dwell of its block for a gap piece (the
        durations the path check's thinned grid and ``RoundChecks`` read)."""
        return input_durations(self.pieces.table, np.asarray(self.fraction), np.asarray(self.piece_tv),
                               np.asarray(self.gaps))


def input_durations(table, fraction: np.ndarray, piece_tv: np.ndarray, gaps: np.ndarray) -> np.ndarray:
    """``(P,)`` length [s] of every input piece of ``table`` (``_fir_blocks.PulseTable``): its share
    ``fraction`` of its block's pulse ``piece_tv``, or for a gap piece its block's dwell ``gaps``
    ``(M_pad,)`` (0 after the last block)."""
    return np.where(table.gap, np.append(gaps, 0.0)[table.block], fraction * piece_tv)


def kernel_second_integral(r: np.ndarray, delays: np.ndarray) -> np.ndarray:
    """``H2(r)`` of ``_fir_chain.kernel_second_integral`` in NumPy (same subsets, same order)."""
    n = delays.size
    r = np.asarray(r, dtype=np.float64)
    total = np.zeros_like(r)
    for bits in range(1 << n):
        subset = np.array([(bits >> (n - 1 - i)) & 1 for i in range(n)], dtype=np.float64)  # itertools.product order
        shift = np.sum(subset * delays)
        total = total + (-1.0) ** int(subset.sum()) * np.maximum(r - shift, 0.0) ** (n + 1)
    return total / (math.factorial(n + 1) * np.prod(delays))


@functools.lru_cache(maxsize=64)
def _h_full(delays: tuple) -> np.ndarray:
    """``H2(T_d / 2)`` of the (sorted) delays: :func:`kernel_second_integral` once per chain."""
    d = np.asarray(delays, dtype=np.float64)
    h = kernel_second_integral(np.array(0.5 * float(d.sum())), d)
    h.setflags(write=False)
    return h


def speed_change(f_out: np.ndarray, f_in: np.ndarray, t_out: np.ndarray, t_in: np.ndarray,
                 turn: bool) -> np.ndarray:
    """``_fir_overlap.corner_speed_change`` on concrete arrays [mm/s] per corner (feeds ``(K,)``
    [mm/s], unit tangents ``(K, d)``; ``turn`` as there)."""
    f_out, f_in = np.asarray(f_out, dtype=np.float64), np.asarray(f_in, dtype=np.float64)
    change = np.linalg.norm(f_in[..., None] * t_in - f_out[..., None] * t_out, axis=-1)
    if not turn:
        return change
    return np.minimum(change, np.maximum(f_out, f_in) * np.linalg.norm(t_in - t_out, axis=-1))


def overlaps(tolerance: np.ndarray, speed_change: np.ndarray, delays: np.ndarray) -> np.ndarray:
    """``_fir_overlap.overlap_time`` (eq 13/14) on concrete arrays: the closed forms of one and two
    filters in NumPy; three or more filters by a compiled root search of ``H2(T_k / 2) = eps /
    |dF|`` (:func:`_invert_h2`; the JAX form's optimistix bisection stops at 1e-13 relative, this
    one at the float resolution, so the two agree to about that)."""
    d = np.sort(np.asarray(delays, dtype=np.float64))[::-1]
    dF = np.asarray(speed_change, dtype=np.float64)
    tol = np.broadcast_to(np.asarray(tolerance, dtype=np.float64), dF.shape)
    Td = float(d.sum())
    turning = dF > 0
    h_full = _h_full(tuple(d.tolist()))
    if d.size > 2:
        shifts, signs = _subsets(tuple(d.tolist()))
        denom = math.factorial(d.size + 1) * float(np.prod(d))
        h = np.minimum(tol / np.where(turning, dF, 1.0), h_full)
        Tk = 2.0 * _invert_h2(np.ascontiguousarray(h.ravel()), shifts, signs, d.size + 1, denom, 0.5 * Td).reshape(h.shape)
        return np.where(turning & (h < h_full), np.clip(Tk, 0.0, Td), Td)
    h = np.minimum(tol / np.where(turning, dF, 1.0), h_full)
    if d.size == 1:
        Tk = np.sqrt(8.0 * d[0] * h)  # eq 13
    else:
        T1, T2 = d[0], d[1]
        in_first = h <= T2**2 / (6.0 * T1)
        first = np.cbrt(48.0 * T1 * T2 * h)  # eq 14, first branch
        second = T2 + np.sqrt(np.where(in_first, 1.0, 8.0 * T1 * h - T2**2 / 3.0))  # eq 14, second branch
        Tk = np.where(in_first, first, second)
    return np.where(turning & (h < h_full), np.clip(Tk, 0.0, Td), Td)


@functools.lru_cache(maxsize=64)
def _subsets(delays: tuple) -> tuple[np.ndarray, np.ndarray]:
    """Shift ``sum_{i in S} T_i`` and sign ``(-1)^|S|`` of every subset ``S`` of the filters, in the
    order of :func:`kernel_second_integral` (read-only arrays, once per chain)."""
    d = np.asarray(delays, dtype=np.float64)
    n = d.size
    shifts, signs = np.empty(1 << n), np.empty(1 << n)
    for bits in range(1 << n):
        subset = np.array([(bits >> (n - 1 - i)) & 1 for i in range(n)], dtype=np.float64)
        shifts[bits], signs[bits] = np.sum(subset * d), (-1.0) ** int(subset.sum())
    shifts.setflags(write=False)
    signs.setflags(write=False)
    return shifts, signs


@numba.njit(**_OPTIONS)
def _invert_h2(target, shifts, signs, power, denom, half):
    """``r`` in ``[0, half]`` with ``H2(r) = target[i]`` for every ``i`` (``H2`` of
    :func:`kernel_second_integral`: ``sum_S sign_S (r - shift_S)_+^power / denom``, increasing on
    ``[0, T_d / 2]`` as ``H2' = H1 >= 0``): 0 for a target of 0 or less, ``half`` for one at or
    above ``H2(half)``; otherwise false position with the Illinois modification (Dowell & Jarratt
    1971) on the bracket ``[0, half]``, to the float resolution of ``half``."""
    out = np.empty(target.size)
    f_half = 0.0
    for k in range(shifts.size):
        f_half += signs[k] * max(half - shifts[k], 0.0) ** power
    f_half /= denom
    for i in range(target.size):
        y = target[i]
        if y <= 0.0:
            out[i] = 0.0
            continue
        if y >= f_half:
            out[i] = half
            continue
        x0, x1, f0, f1 = 0.0, half, -y, f_half - y
        side = 0
        for _ in range(200):
            x = secant_point(x0, f0, x1, f1)
            if x <= x0 or x >= x1:
                break
            fx = 0.0
            for k in range(shifts.size):
                fx += signs[k] * max(x - shifts[k], 0.0) ** power
            fx = fx / denom - y
            if fx == 0.0:
                x0 = x1 = x
                break
            x0, f0, x1, f1, side = narrowed(x0, f0, x1, f1, side, x, fx)
        out[i] = 0.5 * (x0 + x1)
    return out


def timing(lengths_p, feeds_p, blk, piece_factor, motion_ends, tangents, full, shrink, others, tol_vertex, delays,
           turn: bool):
    """``_fir_settle._timing_kernel`` on the real corners (``M - 1``), NumPy: the pulse length of every
    piece ``(P,)`` [s] (eq 5 at its feed) and the overlap of every corner ``(M - 1,)`` [s] (eq 13/14,
    or ``T_d`` at full overlap, times its shrink factor). Elementwise for one or two filters: the
    pieces up to a block's first motion piece and the corners before it (``plan_fir``'s
    ``prefix_bound``) give the same values as the whole path's. ``turn``: ``_fir_overlap.corner_speed_change``'s."""
    piece_tv = lengths_p[blk] / (feeds_p[blk] * piece_factor)
    M = tol_vertex.size + 1
    f_in = feeds_p[1:M] * piece_factor[motion_ends[0][1:M]]  # entry feed of the block after each corner
    f_out = feeds_p[: M - 1] * piece_factor[motion_ends[1][: M - 1]]  # exit feed of the block before it
    dF = speed_change(f_out, f_in, tangents[1][: M - 1], tangents[0][1:M], turn)
    Td = float(np.sum(delays))
    if M == 1:
        return piece_tv, np.zeros(0)
    if delays.size > 2:  # the JAX inversion on the padded shapes of every corner
        ov = np.where(full, Td, overlaps(np.maximum(tol_vertex - others, 0.0), dF, delays))
    else:  # closed forms, elementwise: only the dwell corners' (most corners of a CAM program are full)
        dwell = ~np.asarray(full, dtype=bool)
        ov = np.full(M - 1, Td)
        ov[dwell] = overlaps(np.maximum(tol_vertex[dwell] - others[dwell], 0.0), dF[dwell], delays)
    return piece_tv, ov * shrink


def profile(start, geo, block, gap, fraction, piece_tv, gaps, delays, joins=None):
    """``_fir_blocks.build_profile`` on concrete arrays (same arguments and results, NumPy):
    ``(block_starts, block_ends, breaks, coeffs, centre)`` with the position profile as its breaks
    ``(K + 1,)`` and ascending local coefficients ``(K, D, d)``.

    The input pulses (:func:`_input_pulses`), each filter in turn (:func:`_moving_average`, the last one
    integrated: the position) and the blocks' times (:func:`_block_times`) are compiled apart, the
    filters once per coefficient row count ``D`` met (:func:`_filter`): a path of lines (``D = 1``)
    through two filters compiles the forms of 1 and 2 rows, a path with arcs (``D = 6``) of 6 and 7.
    ``joins``: ``PulseTable.joins`` (None: no piece goes on with the one before it), whose pieces
    at their predecessor's feed lengthen it (:func:`_input_pulses`)."""
    delays = np.ascontiguousarray(delays, dtype=np.float64)
    # the blocks' times first: no filter's input is held once the next one is built (memory)
    (vb, vl, vc), (starts, ends, centre) = _pulses_and_times(geo, block, gap, fraction, piece_tv, gaps, delays, joins)
    for k in range(delays.size - 1):
        vb, vl, vc = _moving_average(vb, vl, vc, delays[k])
    # the last filter integrated as it goes: the position, closed by a rest piece of zero length (as
    # the JAX form's trailing empty piece): the right-hand limit at the end time is the machine at
    # rest (v = a = j = 0), not the last decelerating piece's left limit (sampled trajectories end
    # at rest, ``Trajectory.from_piecewise``)
    pos_breaks, _, position = _filter(vb, vl, vc, delays[-1], start, True)
    return starts, ends, pos_breaks, position, centre


def schedule_span(geo, block, gap, fraction, piece_tv, gaps, delays, joins=None):
    """The block times and the span of :func:`profile` without its filters (the same arguments):
    ``(block_starts, block_ends, span, centre)`` with ``span`` ``(2,)`` the profile's first and
    last break [s], the same floats. Each filter's merge runs from its input's first break to
    its last plus ``T`` (``_merge_step``: ``breaks[K] + T``, rounded, the largest break it
    meets; an empty last piece leaves that value all the same), so the span is the input's
    first break and its last plus each delay in turn, rounded after each. What ``plan_fir``
    without refinement or limits needs: its plan keeps the inputs, not the coefficients
    (:class:`ProfileInputs`), and checks nothing on the profile."""
    delays = np.ascontiguousarray(delays, dtype=np.float64)
    (vb, _, _), times = _pulses_and_times(geo, block, gap, fraction, piece_tv, gaps, delays, joins)
    end = float(vb[-1])
    for d in delays.tolist():
        end = end + d
    starts, ends, centre = times
    return starts, ends, np.array([float(vb[0]), end]), centre


def _pulses_and_times(geo, block, gap, fraction, piece_tv, gaps, delays, joins):
    """``((breaks, low parts, coefficients) of the input pulses, (block starts, ends, corner
    instants))`` of :func:`profile` (:func:`_input_pulses`, :func:`_block_times`)."""
    block, gaps = np.ascontiguousarray(block), np.ascontiguousarray(gaps, dtype=np.float64)
    joins = np.zeros(block.size, dtype=bool) if joins is None else np.ascontiguousarray(joins)
    vb, vl, vc, block = _input_pulses(np.ascontiguousarray(geo, dtype=np.float64), block,
                                      np.ascontiguousarray(gap), np.ascontiguousarray(fraction, dtype=np.float64),
                                      np.ascontiguousarray(piece_tv, dtype=np.float64), gaps, joins)
    Td = 0.0
    for d in delays.tolist():  # summed in order, as the compiled build did
        Td += d
    return (vb, vl, vc), _block_times(vb, block, gaps, Td)


@numba.njit(inline="always", **_OPTIONS)
def _over(x, m):
    """``x / m`` for an integer ``m >= 1``: ``x * (1 / m)`` at a power of two (``1 / m`` exact, both
    round the same real number, so the same bits) without a division, which costs several
    multiplications; the test folds away where ``m`` is a compile-time constant (the unrolled row
    loops of :func:`_filter_rows`)."""
    if m & (m - 1) == 0:
        return x * (1.0 / m)
    return x / m


@numba.njit(inline="always", **_OPTIONS)
def _add(hi, lo, a, s):
    """``(hi[a], lo[a]) += s`` as a double-double (two-sum, renormalized)."""
    x = hi[a]
    t = x + s
    z = t - x
    r = lo[a] + ((x - (t - z)) + (s - z))
    hi[a] = t + r
    lo[a] = r - (hi[a] - t)


@numba.njit(inline="always", **_OPTIONS)
def _window_add(breaks, lo, coeffs, k, sign, wh, wl, hq, D):
    """``(wh, wl) += sign * integral of piece k`` on every axis (double-doubles, :func:`_add`): the
    running integral of the input over the window ``[t - T, t]`` between the two pieces in use."""
    h = _between(breaks, lo, 0.0, 0, k + 1, 0, k)
    hq[0] = h
    for m in range(1, D):
        hq[m] = hq[m - 1] * h  # h^(m + 1) by products (a C pow costs tens of ns)
    for a in range(coeffs.shape[2]):
        s = 0.0
        for m in range(D):
            s += _over(coeffs[k, m, a], m + 1) * hq[m]
        _add(wh, wl, a, sign * s)


@numba.njit(inline="always", **_OPTIONS)
def _shifted_c(coeffs, k, a, delta, c, D):
    """Piece ``k`` of ``C`` on axis ``a`` less its constant term (ascending coefficients ``(D + 1,)``
    into ``c``; piece ``K`` the end value held after the last break, all 0), re-centred by
    ``delta``: the Taylor shift of ``research.piecewise.taylor_shift``. ``c[0]`` is then the
    integral from the piece's break to ``delta``; the integral up to that break is added apart
    (:func:`_window_add`)."""
    K = coeffs.shape[0]
    c[0] = 0.0
    for m in range(D):
        c[m + 1] = _over(coeffs[k, m, a], m + 1) if k < K else 0.0
    for i in range(D):
        for m in range(D - 1, i - 1, -1):
            c[m] = c[m] + delta * c[m + 1]


def _moving_average(breaks, lo, coeffs, delay):
    """``PiecewisePolynomial.moving_average`` (Sencer 2015 eq 1) on concrete arrays: breaks ``(K' + 1,)``
    (and their low parts, :func:`_between`) and coefficients ``(K', D + 1, A)`` of ``(C(t) - C(t - T))
    / T`` (:func:`_filter_rows`)."""
    return _filter(breaks, lo, coeffs, delay, np.zeros(coeffs.shape[2]), False)


def _filter(breaks, lo, coeffs, delay, initial, integrate: bool):
    """:func:`_filter_rows` through the compiled form of its row count ``D = coeffs.shape[1]``.

    ``D`` is a constant in the code of :data:`_ROWS`' functions for the counts the planner meets
    (lines 1, arcs ``DEGREE + 1`` = 6, each filter one more): the loops over rows then unroll and
    the small arrays stay in registers (2-2.5x faster, the same operations in the same order); any
    other count runs the generic form. Chosen here, not in compiled code, each is compiled on its
    first use only (a compiled choice compiles every branch: 38 s of a fresh install's first plan)."""
    rows = _ROWS.get(coeffs.shape[1], _rows_any)
    return rows(breaks, lo, coeffs, delay, np.ascontiguousarray(initial, dtype=np.float64), integrate)


# one function per row count, written out: Numba caches a compiled function by its source, and the
# constant in each one's source is what unrolls its row loops
@numba.njit(**_OPTIONS)
def _rows_any(breaks, lo, coeffs, delay, initial, integrate):
    return _filter_rows(breaks, lo, coeffs, delay, initial, integrate, coeffs.shape[1])


@numba.njit(**_OPTIONS)
def _rows1(breaks, lo, coeffs, delay, initial, integrate):
    return _filter_rows(breaks, lo, coeffs, delay, initial, integrate, 1)


@numba.njit(**_OPTIONS)
def _rows2(breaks, lo, coeffs, delay, initial, integrate):
    return _filter_rows(breaks, lo, coeffs, delay, initial, integrate, 2)


@numba.njit(**_OPTIONS)
def _rows3(breaks, lo, coeffs, delay, initial, integrate):
    return _filter_rows(breaks, lo, coeffs, delay, initial, integrate, 3)


@numba.njit(**_OPTIONS)
def _rows6(breaks, lo, coeffs, delay, initial, integrate):
    return _filter_rows(breaks, lo, coeffs, delay, initial, integrate, 6)


@numba.njit(**_OPTIONS)
def _rows7(breaks, lo, coeffs, delay, initial, integrate):
    return _filter_rows(breaks, lo, coeffs, delay, initial, integrate, 7)


@numba.njit(**_OPTIONS)
def _rows8(breaks, lo, coeffs, delay, initial, integrate):
    return _filter_rows(breaks, lo, coeffs, delay, initial, integrate, 8)


_ROWS = {1: _rows1, 2: _rows2, 3: _rows3, 6: _rows6, 7: _rows7, 8: _rows8}


@numba.njit(inline="always", **_OPTIONS)
def _merge_step(breaks, delay, i, j, K):
    """One step of the merge of the breaks of ``C(t)`` (``i`` taken) and ``C(t - T)`` (``j`` taken,
    at ``b + T``), ties to ``C(t)``: ``(next break, i, j)``."""
    if j > K or (i <= K and breaks[i] <= breaks[j] + delay):
        return breaks[i], i + 1, j
    return breaks[j] + delay, i, j + 1


@numba.njit(inline="always", **_OPTIONS)
def _between(breaks, lo, delay, xs, x, ys, y):
    """``(b_x + xs T) - (b_y + ys T)`` for series flags ``xs, ys`` in {0, 1}, with the breaks
    ``b = breaks + lo`` (a double-double: ``breaks`` rounded, ``lo`` the rest): the difference of the
    rounded breaks first (exact where they lie within a factor 2, Sterbenz), then of the rests,
    then the delays. A piece's length and local time then carry no rounding of its absolute
    time: after hours of motion ``b + T`` rounds by ~1e-11 s, and a local time off by that moves
    every piece's value (hours of pieces: micrometres of drift at the path's end)."""
    d = (breaks[x] - breaks[y]) + (lo[x] - lo[y])
    if xs == ys:
        return d
    return d + delay if xs > ys else d - delay


@numba.njit(inline="always", **_OPTIONS)
def _rest(breaks, lo, delay, src, idx, b):
    """The low part of the merged break ``b`` (rounded): ``breaks[idx] + lo[idx]``, plus ``T`` for
    the series of ``C(t - T)`` (``src`` 1), less ``b`` (two-sum: exact)."""
    if src == 0:
        return lo[idx]
    x = breaks[idx]
    z = b - x
    return ((x - (b - z)) + (delay - z)) + lo[idx]


@numba.njit(**_OPTIONS)
def _filter_rows(breaks, lo, coeffs, delay, initial, integrate, D):
    """The moving average (Sencer 2015 eq 1, ``(C(t) - C(t - T)) / T``: breaks ``(K' + 1,)``, coefficients
    ``(K', D + 1, A)`` on the ``K' <= 2K + 1`` pieces of positive length of the merge of ``b`` and ``b + T``;
    the JAX form keeps the empty ones too), or with ``integrate`` its integral from the first break plus
    ``initial`` ``(A,)`` (``(K' + 1, D + 2, A)`` coefficients on ``K' + 2`` breaks), built piece by
    piece as the average comes (no averaged profile kept), closed by a rest piece of zero length
    whose value is the end value. ``C`` is never held: ``C(t) - C(t - T)`` is the integral of the
    input between the breaks of the two pieces in use, kept as a running double-double sum as the
    merge passes them (:func:`_window_add`; no large constants to cancel after hours of motion), plus
    the local parts of the two pieces (:func:`_shifted_c`). Each axis of a
    piece is built in scalars, one after the other (the axes never mix: the same operations in the
    same order as axis-innermost loops)."""
    K, _, A = coeffs.shape
    # one pass of the merge (no merged arrays kept) fills the new pieces of positive length into
    # arrays sized for all ``2 K + 1`` (a view of them returned, a copy where more than 1/8 is
    # unused: measured, the first of two filters keeps ~40 %). An empty piece is never evaluated
    # (a right search takes the next piece), integrates to 0, and the next filter's pieces that
    # would take their coefficients from it are empty too; the breaks are the same values, the
    # function the same. The merged breaks never decrease, from ``breaks[0]`` to ``breaks[K] + T``:
    # every piece is empty when those are equal, and then the first one is kept
    R = D + 2 if integrate else D + 1  # coefficient rows of a result piece
    keep_first = not (breaks[K] + delay > breaks[0])
    cap = 2 * K + 1
    out = np.empty((cap + 1, R, A)) if integrate else np.empty((cap, R, A))  # written up to the pieces kept
    out_breaks = np.empty(cap + 2) if integrate else np.empty(cap + 1)
    out_lo = np.zeros(out_breaks.size)  # the rest of each break (:func:`_between`)
    c, w, hp, acc, rest = np.empty(D + 1), np.empty(D + 1), np.empty(D + 1), np.zeros(A), np.zeros(A)
    wh, wl, hq = np.zeros(A), np.zeros(A), np.empty(max(D, 1))  # C(break of now) - C(break of before)
    i, j, q = 0, 0, 0  # breaks of C(t) taken, breaks of C(t - T) taken (ties: C(t) first); pieces kept
    left, now, before = 0.0, -1, -1
    lsrc, lidx = 0, 0  # ``left`` is ``breaks[lidx] + lsrc T``: a break of C(t) (0) or of C(t - T) (1)
    for p in range(2 * (K + 1)):
        i0, j0 = i, j
        b, i, j = _merge_step(breaks, delay, i, j, K)
        bsrc, bidx = (0, i0) if i > i0 else (1, j0)
        if p == 0:
            out_breaks[0], out_lo[0] = b, _rest(breaks, lo, delay, bsrc, bidx, b)
        elif b > left or (keep_first and p == 1):
            # the piece [left, b): piece ``now`` of C holds it at t, ``before`` at t - T (-1:
            # before breaks[0], where C is zero; K: after breaks[K], where C holds its end value)
            out_breaks[q + 1], out_lo[q + 1] = b, _rest(breaks, lo, delay, bsrc, bidx, b)
            h = _between(breaks, lo, delay, bsrc, bidx, lsrc, lidx)
            hp[0] = h
            for m in range(1, D + 1):
                hp[m] = hp[m - 1] * h
            # the offsets of the piece's left end in the two pieces in use (the same on every axis)
            at_now = _between(breaks, lo, delay, lsrc, lidx, 0, now)
            at_before = _between(breaks, lo, delay, lsrc, lidx, 1, before) if before >= 0 else 0.0
            for a in range(A):
                _shifted_c(coeffs, now, a, at_now, c, D)
                for m in range(D + 1):
                    w[m] = 0.0 + 1.0 * c[m]
                if before >= 0:
                    _shifted_c(coeffs, before, a, at_before, c, D)
                    for m in range(D + 1):
                        w[m] += -1.0 * c[m]
                w[0] += wh[a] + wl[a]  # the input's integral between the two pieces' breaks
                if not integrate:
                    for m in range(D + 1):
                        out[q, m, a] = w[m] / delay
                else:  # ``PiecewisePolynomial.antiderivative`` of this piece, in order
                    s = 0.0
                    for m in range(D + 1):
                        cm = _over(w[m] / delay, m + 1)
                        out[q, m + 1, a] = cm
                        s += cm * hp[m]
                    out[q, 0, a] = (acc[a] + initial[a]) + rest[a]
                    _add(acc, rest, a, s)  # the integral so far as a double-double
            q += 1
        # the window's integral as its ends pass breaks: a piece of C(t) fully in, one of C(t - T) out
        if i > i0 and i0 >= 1:
            _window_add(breaks, lo, coeffs, i0 - 1, 1.0, wh, wl, hq, D)
        if j > j0 and j0 >= 1:
            _window_add(breaks, lo, coeffs, j0 - 1, -1.0, wh, wl, hq, D)
        left, now, before = b, i - 1, j - 1
        lsrc, lidx = bsrc, bidx
    n_out = q
    if integrate:  # the closing rest piece: the end value (Horner on the last piece), v = a = j = 0
        h = (out_breaks[n_out] - out_breaks[n_out - 1]) + (out_lo[n_out] - out_lo[n_out - 1])
        for a in range(A):
            z = out[n_out - 1, R - 1, a]
            for m in range(R - 2, -1, -1):
                z = out[n_out - 1, m, a] + z * h
            out[n_out, 0, a] = z
            for m in range(1, R):
                out[n_out, m, a] = 0.0
        out_breaks[n_out + 1], out_lo[n_out + 1] = out_breaks[n_out], out_lo[n_out]
        n_out += 1
    if 8 * n_out < 7 * cap:  # many empty pieces (raw pulses, pulses shorter than the delay): what
        # is kept (the profile, or the next filter's input) is not held in a buffer sized for all
        return out_breaks[: n_out + 1].copy(), out_lo[: n_out + 1].copy(), out[:n_out].copy()
    return out_breaks[: n_out + 1], out_lo[: n_out + 1], out[:n_out]


@numba.njit(**_OPTIONS)
def _input_pulses(geo, block, gap, fraction, piece_tv, gaps, joins):
    """The input velocity pulses as a piecewise polynomial: breaks ``(K + 1,)`` (from 0, each piece
    its share of its block's pulse or its gap) with their low parts ``(K + 1,)`` (the running sum
    of the pieces' lengths as a double-double, :func:`_between`: each piece keeps its own length
    however long the motion before it), coefficients ``(K, D, A)`` (``geo`` in ``u`` scaled to
    time) and the block of each piece ``(K,)``. A piece that ``joins`` its predecessor (it goes
    on with its polynomial, ``PulseTable.joins``) at the same pulse length (feed) lengthens that
    piece instead of starting one (``K <= P``; the breaks where pieces start are those of the
    pieces one by one: every length is added to the running sum as it was). An empty piece (a gap
    at full overlap, a head or tail of share 0; about half the pieces of a CAM program) is left
    out unless the next piece lengthens it: the running sum does not move (it adds 0 to a
    renormalized double-double), and the filters pass an empty piece without output and add 0
    to their window sums, so the profile is the same, bit for bit, from a merge half as long."""
    P, D, A = geo.shape
    Mp = gaps.size
    breaks = np.empty(P + 1)
    lo = np.zeros(P + 1)
    coeffs = np.empty((P, D, A))
    out_block = np.empty(P, block.dtype)
    breaks[0] = 0.0
    acc, rest = 0.0, 0.0
    k = -1  # the last piece made
    for i in range(P):
        b = block[i]
        if gap[i]:
            dur = gaps[b] if b < Mp else 0.0
        else:
            dur = fraction[i] * piece_tv[i]
        s = acc + dur  # two-sum of acc + dur, then renormalized: acc + rest to ~1e-32 relative
        z = s - acc
        rest += (acc - (s - z)) + (dur - z)
        acc = s + rest
        rest -= acc - s
        if k >= 0 and dur == 0.0 and not (i + 1 < P and joins[i + 1] and not gap[i + 1]
                                            and piece_tv[i + 1] == piece_tv[i]):
            continue  # empty (a gap at full overlap, a head or tail of share 0) and not lengthened
        if k >= 0 and joins[i] and not gap[i] and piece_tv[i] == piece_tv[i - 1]:
            breaks[k + 1] = acc  # the piece before goes on
            lo[k + 1] = rest
            continue
        k += 1
        breaks[k + 1] = acc  # never below breaks[k]: dur >= 0 and acc is the sum rounded
        lo[k + 1] = rest
        out_block[k] = b
        inv = 1.0 / piece_tv[i]
        s = inv
        for m in range(D):  # d/dt = (1 / T_v) d/du: the u'^m coefficient over T_v^(m + 1)
            for a in range(A):
                coeffs[k, m, a] = 0.0 if gap[i] else geo[i, m, a] * s
            s *= inv
    return breaks[: k + 2], lo[: k + 2], coeffs[: k + 1], out_block[: k + 1]


@numba.njit(**_OPTIONS)
def _block_times(breaks, block, gaps, Td):
    """Each block's pulse start and end and its corner instant (the end, half the gap and ``T_d /
    2`` later) [s], ``(Mp,)`` each, from the input pulses' breaks."""
    P, Mp = block.size, gaps.size
    starts, ends, centre = np.empty(Mp), np.empty(Mp), np.empty(Mp)
    first = 0
    for k in range(Mp):
        while first < P and block[first] < k:
            first += 1
        last = first
        while last < P and block[last] <= k:
            last += 1
        starts[k] = breaks[first]
        ends[k] = breaks[last] - gaps[k]
        centre[k] = ends[k] + 0.5 * gaps[k] + 0.5 * Td
    return starts, ends, centre
