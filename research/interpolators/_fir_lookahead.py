"""Look-ahead of the FIR planner on programs of short blocks (beyond Sencer 2015).

Sencer 2015 assumes every block is longer than the filter window ``T_d``; on CAM programs a
window spans many chords. :func:`look_ahead` builds the candidate plans that ``plan_fir``
verifies: for every vertex, either eq 13/14's dwell (a gap of ``T_d - T_k``) or full overlap at
the largest feed whose windowed displacement (``_fir_feed``: every direction change inside the
window, with their cancellation) stays within the tolerance; block feeds follow the staircase of
the windows that reach into each line (:func:`line_pieces`).

**Nesting in eps** (issue "FIR cornering on real CAM programs": a cycle time that never increases
when eps grows). A candidate is a *dwell set* (which vertices dwell, and under which of the two
tolerance rules) plus the feeds and overlaps that follow from the tolerance. The dwell sets are
decisions on estimates (dwell cost ``T_d - T_k`` against the slow-down cost), and they change with
eps in a way that is not nested: at a looser eps a vertex's slow-down gets cheaper, or eq 13/14
allows full overlap there while its window still needs a slow-down, and the small-gap dwell that
made the tighter eps fast is no longer offered (measured: benchmarks/README.md, bench_cam section).
So a call at ``eps`` also offers the dwell sets its rules decide at ``eps q^k``, ``q = NEST_RATIO``,
``k = 1 .. NEST_STEPS``, each planned with ``eps``'s own feeds and overlaps.

What is exact:

1. The candidates at ``eps`` hold every dwell set that a call at ``eps q^k`` (``k <= NEST_STEPS``)
   decides at its own tolerance: a decision is one function of the level's tolerance, the same at
   every level and in every call (:func:`_dwell_cheaper`: the whole chain's window error at the
   break-even feed, eq 13/14 at the level's tolerance, the tolerance-free displacement of the
   other turns). Lines exactly (up to the rounding of ``eps q^k``); with arcs, the levels keep
   ``eps``'s arc feeds (eq 8) and sampled arc turns, so there the sets are those of the level's
   rules on ``eps``'s feeds, not the call's own.
2. ``plan_fir`` returns the least verified cycle time over its candidates (its branch and bound
   drops a candidate only on a lower bound of that candidate's verified time, and each
   candidate's verification is independent of the others), so offering more candidates never
   makes a plan slower.

**Deeper levels.** Below ``eps q^NEST_STEPS`` the points ``q^m`` of a fixed grid (``m`` integer,
tolerances in mm; :func:`deep_levels`) offer, ``DEEP_STEPS`` of them, one dwell set each: the
"isolated" rule's cost set (where its dwell is estimated cheaper than the slow-down). A grid
point, unlike ``eps q^k``, is the same tolerance for every eps within a factor ``q^-1`` of each
other, so its set is offered at both ends of a small eps step unless the step crosses a grid
point. Why that set only: on bench_cam's eps ladder (seeds 0-149, lines / arcs), 3 of the 8
programs that rose were won at the lower eps by the "isolated" cost set of ``eps q^4``, below the
higher eps's levels; every set of two more levels ``eps q^5, eps q^6`` (6 candidates more on the
quick CAM file instead of 2) cost +16 % planning time there, and the same one set at
``eps q^5, eps q^6`` instead of on the grid moved the rise to other programs (12, 106 arcs).

**Window reach** (issue "cycle time flat in the chord tolerance"). A vertex's window feed ``f`` is
the largest *constant* feed at which its windowed displacement stays within the tolerance; the
blocks then follow the staircase of the window feeds (:func:`line_pieces`: the minimum over the
windows that cover a point). Holding each feed over the window's whole support, ``f T_d / 2`` each
side, makes that staircase a minimum filter of width ``f T_d`` over the path: where the curvature
varies, every block runs at the feed of the tightest vertex within ``f T_d / 2``, far below its own
window's (measured on bench_cam's waterline file at 1 um chords: windows of 168-200 mm/s on blocks
run at 105 mm/s, next to a stretch of R ~ 36 mm). At 10 um chords the dwell sets lifted that (a
dwell vertex sets no window feed, and its chord turns are large enough for eq 13/14 to give a
cheap gap), which is why the coarsest chords planned fastest. How far a feed must be held depends
on which turns make the window's displacement. The vertex's own turn is a velocity step at the
window's centre, felt over the whole support (eq 13/14), so its share needs ``T_d / 2``. The other
turns of a curve cut into chords are spread over the window; on a curve of radius ``R`` at
constant feed the filtered point lies ``f^2 var / (2 R)`` inside it, ``var = sum T_i^2 / 12`` the
kernel's second moment, so the displacement is that of a window whose weight sits at the kernel's
rms half-width ``sigma = sqrt(var)`` (19.4 ms for 60/30 ms, against 45 ms): their share is held
over ``sigma``. :func:`window_half_width` weights the two by the shares of the tolerance-free
displacement at full overlap (``T_d / 2`` on isolated corners, about ``sigma`` on fine chords); what
the blocks beyond the reach add at their own (higher) window feeds is left to the verification,
whose repairs slow the window of a vertex that breaks the tolerance. The shorter reach is not
faster on every program (a repair scales whole blocks where the staircase slowed only their ends),
so each dwell set is offered with both reaches, and the branch and bound's minimum is never slower
than the whole-support candidates alone; but "every vertex that can dwell" only with the whole
support (few of its vertices hold a window feed; its shorter-reach copies cost two more
verification rounds on the quick CAM file and won 14 of 1,800 random plans, by up to 2.1 %).
Swept on the quick file (benchmarks/README.md, bench_cam section; one reach for every vertex, as
a share of ``T_d / 2``): 1, 0.75, 0.625, 0.5, 0.43 (``sigma``), 0.375 and 0.25 give the four chord
tolerances a sum of 100.2, 97.9, 96.7, 95.0, 94.7, 94.1 and 95.6 s: ``sigma`` lies in the flat
optimum of the sweep (not fitted to it).

What is not proven, and rests on the verification (measured instead): that a dwell set planned at
the looser eps verifies no slower than at the tighter one. Its ingredients move the right way --
eq 13/14's ``T_k`` does not fall as the tolerance grows at a fixed speed change, and a feed within
a tolerance is within every larger one -- but a larger window feed changes the speed change at a
neighbouring dwell corner, the largest feed of a window whose turns cancel is not monotone in the
tolerance, and a repair (a window's feeds scaled by ``sqrt(eps / error)``) can leave the looser plan
slower. Nor are dwell sets of tolerances between the levels, or below ``eps q^NEST_STEPS``,
offered: for a ratio that is not a power of ``q`` only the decisions of the nearby levels are.
An exact construction over a sweep is ``plan_fir_sweep`` (``_fir_candidates``), which plans each
tolerance; one call cannot be made exactly monotone this way without planning every tighter
tolerance.
"""

from __future__ import annotations

import numpy as np

from research.interpolators._fir_blocks import PulseTable
from research.interpolators._fir_feed import ChainError
from research.interpolators._fir_kernels import VERIFY_ATOL
from research.interpolators._fir_candidate_kernels import candidate_pieces, line_piece_feeds, slowing_windows, staircase_cuts
from research.interpolators._fir_profile import kernel_second_integral, overlaps, speed_change
from research.paths.toolpath import ToolPath
from research.piecewise import bucket_size


#: The dwell sets of the tolerances ``eps * NEST_RATIO^k``, ``k = 1 .. NEST_STEPS``, are offered at
#: ``eps`` as well (nesting in eps, module docstring); ``NEST_STEPS = 0`` is the planner without
#: nesting. Swept (benchmarks/README.md, bench_cam section: 0, 1, 2, 4 steps of 2^-1/2, 8 of 2^-1/4):
#: 4 steps of 2^-1/2 (down to eps / 4) is where the rate of rising programs stops falling fast
#: against the planning cost.
NEST_RATIO = 2.0 ** -0.5
NEST_STEPS = 4

#: Below those, the levels ``k = NEST_STEPS + 1 .. NEST_STEPS + DEEP_STEPS`` offer one dwell set
#: each: where the dwell under the "isolated" rule is estimated cheaper than the slow-down (module
#: docstring, "Deeper levels": why that set, measured).
DEEP_STEPS = 2
_DEEP_SET = 1  # index of the "isolated" cost set among the sets of _dwell_sets


def look_ahead(tp: ToolPath, table: PulseTable, F_cmd, base, delays, tol_v, t_in, t_out, turn: bool, measure=None):
    """Candidate plans, each kept as a :class:`Candidate` whose call builds its arrays
    ``(factor, head, tail, full, others, arc_rel)``: feed factors ``(M, 3)`` (head, body, tail),
    head and tail shares ``(M,)``, full-overlap flags ``(M - 1,)``, the tolerance other turns take
    at dwell corners ``(M - 1,)`` and the slow-down of every sub-arc ``(A,)`` (a window reaching
    into an arc slows only the sub-arcs it covers).

    A candidate is a set of dwell vertices (the rest run at full overlap) and the dwell corners'
    tolerance rule; its feeds and overlaps are then those of ``tol_v`` (eq 13/14 at the dwell
    corners, the window feeds of the other vertices on the chain without the dwell turns, held on
    the blocks over the reach of :func:`window_half_width` and over the whole support). The
    rule says how much of the tolerance a dwell corner may use: ``"budget"`` gives it what the
    other direction changes of its window leave at full overlap (triangle inequality; right for
    curves cut into chords), ``"isolated"`` the whole tolerance (right for isolated corners and
    zigzags whose neighbours dwell too). The dwell sets: where the dwell is estimated cheaper than
    the slow-down (both rules), every vertex that can dwell, none (:func:`_dwell_sets`) -- decided
    at ``tol_v`` and at each tighter tolerance ``tol_v * NEST_RATIO^k`` (module docstring: why).
    All are verified; the fastest verified plan is kept.

    Args:
        tp, table: the path and its pulse table; F_cmd, base: ``(M,)`` commanded feeds [mm/s] and
            their factors (arcs, limits); delays: ``(n,)`` filter delays [s]; tol_v: ``(M - 1,)``
            vertex tolerances [mm]; t_in, t_out: ``(M, d)`` block tangents at start and end.
        turn: the dwell corners' speed change (``_fir_overlap.corner_speed_change``).
        measure: called on each candidate's arrays while they are built (once, for the duplicate
            check), or None.

    Returns:
        ``[(candidate, measure(its arrays) or None)]``, the candidates in order, none equal to
        another (flags, tolerances of other turns, feed factors and shares). Held so, the
        candidates cost their dwell sets and window feeds (:class:`Candidate`), not their arrays:
        the planner builds those again when it starts one (its branch and bound starts few)."""
    M = tp.n_blocks
    Td = float(delays.sum())
    F = F_cmd * base
    du = t_in[1:] - t_out[:-1]
    s_v = np.cumsum(tp.lengths)[:-1]
    Fv = np.minimum(F[:-1], F[1:])
    dF = speed_change(F[:-1], F[1:], t_out[:-1], t_in[1:], turn)
    h_full = float(kernel_second_integral(0.5 * Td, delays))
    # a vertex held to tolerance 0 whose own turn moves its full-overlap window by at most the
    # verification's absolute slack (VERIFY_ATOL, 1 pm) at its feed is straight to the planner (a
    # line split at a point rounded off it): its turn is left out of the chain, and it is not stopped
    # for it -- only where a window's other turns reach it, and then by the dwell decisions, not always
    straight = (tol_v <= 0) & (Fv * np.linalg.norm(du, axis=1) * h_full <= VERIFY_ATOL)
    du = np.where(straight[:, None], 0.0, du)
    arc_turns = _arc_turns(tp, float(np.min(tol_v, initial=np.inf))) if tp.is_arc.any() else (np.zeros(0), np.zeros((0, tp.dim)))

    if arc_turns[0].size:  # every turn in arc-length order, vertices first where equal (a stable sort)
        s_all, du_all = np.concatenate([s_v, arc_turns[0]]), np.concatenate([du, arc_turns[1]])
        order_all = np.argsort(s_all, kind="stable")
        s_all, du_all, is_vertex = s_all[order_all], du_all[order_all], order_all < M - 1
        vertex_of = order_all[is_vertex]
        order_all = None

    def chain(keep):
        if not arc_turns[0].size:  # the vertices' arc lengths are sorted already (a stable sort keeps them)
            return ChainError(s_v[keep], du[keep], delays)
        # the stable order of the kept vertices and the arc turns is the whole order without the others
        take = ~is_vertex
        take[is_vertex] = keep[vertex_of]
        return ChainError(s_all[take], du_all[take], delays)

    every = chain(np.ones(M - 1, dtype=bool))
    d_all = every.displacement(s_v, Fv)
    # what the other direction changes in the window add at full overlap (tolerance-free): a dwell
    # under the "budget" rule gets the rest of the tolerance (triangle inequality), if any is left
    other = np.linalg.norm(d_all - Fv[:, None] * du * h_full, axis=1)
    e_all = np.linalg.norm(d_all, axis=1)
    own = Fv * np.linalg.norm(du, axis=1) * h_full
    with np.errstate(invalid="ignore"):
        hold = window_half_width(delays, np.nan_to_num(own / (own + other), nan=1.0))
    d_all = own = None
    every_rho = float(every.rho.max())
    reach = Fv * every_rho  # a window at a feed <= Fv sums the turns strictly inside s_v +- reach
    # the vertices strictly inside each window's reach: indices [w_lo, w_hi)
    w_lo, w_hi = np.searchsorted(s_v, s_v - reach, side="right"), np.searchsorted(s_v, s_v + reach, side="left")
    memo, solved = {}, []  # gap bytes -> feeds of the vertices that do not dwell; (gap, its feeds (M - 1,)) solved

    def feeds_without(gap):
        """Window feeds of the vertices that do not dwell, on the chain without the dwell turns:
        only windows that reach a removed turn change (the others sum the same turns), and a
        window whose reach holds the same dwell vertices as in a set solved before takes that
        set's feed (it sums the same turns; up to the rounding of the chain's prefix sums).

        A window that reaches a removed turn at the commanded feed but not at its own feed on the
        whole chain (``f_w``) keeps that feed: below the nearest removed turn's entry the two
        chains sum the same turns, so ``f_w`` is a root of both (its error within the search's
        stopping band of the tolerance), and the error above it exceeds the tolerance on both up
        to that entry. Where the error is monotone in the feed it is the same root the search on
        the smaller chain finds (to the band, ~1e-9); where it is not, that search may return a
        higher root beyond the entry, or not (``ChainError.largest_feed``: one of the roots)."""
        key = gap.tobytes()
        if key not in memo:
            # the windows that reach a removed turn at their own feed: a dwell vertex strictly inside
            removed = np.concatenate([[0], np.cumsum(gap)])
            f = f_w.copy()
            q = np.flatnonzero((removed[own_hi] > removed[own_lo]) & ~gap)
            for g_old, f_old in solved:  # f_old: that set's feeds (f_w at its dwell vertices)
                if not q.size:
                    break
                moved = np.concatenate([[0], np.cumsum(g_old != gap)])
                same = moved[w_hi[q]] == moved[w_lo[q]]
                f[q[same]] = f_old[q[same]]
                q = q[~same]
            if q.size:
                # warm-started from the whole chain's feeds: most removed turns sit near a window's
                # edge and move its root little (bench_cam's 10^4 file: 1.33 -> 1.15 us a re-solved window)
                f[q] = chain(~gap).largest_feed(s_v[q], Fv[q], tol_v[q], start=f_w[q])
            solved.append((gap, f))
            memo[key] = f[~gap]
        return memo[key]

    # level 0: the tolerance itself; levels 1 .. NEST_STEPS: the tighter ones whose dwell sets are
    # offered too; then the deep levels. Decided one level at a time (no (levels, M - 1) arrays).
    K1 = NEST_STEPS + 1 + DEEP_STEPS
    ratios = NEST_RATIO ** np.arange(NEST_STEPS + 1)
    deep_tol = deep_levels(tol_v * NEST_RATIO**NEST_STEPS)

    def level(k):
        return tol_v * ratios[k] if k <= NEST_STEPS else deep_tol[k - NEST_STEPS - 1]

    # eq 13/14 overlaps of the two tolerances a dwell may use (concrete arrays, _fir_profile.overlaps):
    # closed forms for one or two filters, taken level by level (elementwise: the same values);
    # three or more filters invert in one batch over every level, as the one search it always was
    Tk = None
    if delays.size > 2:
        pad = bucket_size(M - 1, 16) - (M - 1)
        both = np.stack([np.maximum(level(k) - other, 0.0) for k in range(K1)] + [level(k) for k in range(K1)])
        both = np.pad(both, ((0, 0), (0, pad)), constant_values=1.0)
        Tk = overlaps(both, np.tile(np.pad(dF, (0, pad), constant_values=1.0), (2 * K1, 1)), delays)[:, : M - 1]
        both = None
    # every level reads the window error only through the dwell decisions of _dwell_sets: one
    # evaluation per rule at the break-even feed (_dwell_cheaper), the same function of the level's
    # tolerance at every level and in every call; level 0 also searches the plans' window feeds
    L = tp.lengths
    cap = 0.5 * (L[:-1] + L[1:])
    sets, seen = [], set()
    for k in range(K1):
        tol_k = level(k)
        need, budget = e_all > tol_k, tol_k - other
        if Tk is None:
            Tk_budget, Tk_whole = overlaps(np.maximum(budget, 0.0), dF, delays), overlaps(tol_k, dF, delays)
        else:
            Tk_budget, Tk_whole = Tk[k], Tk[K1 + k]
        if k == 0:  # window feeds on the whole chain at the tolerance itself: the feeds of the plans
            f_w = Fv.copy()
            j_q = np.flatnonzero(need)
            if j_q.size:
                f_w[j_q] = every.largest_feed(s_v[j_q], Fv[j_q], tol_k[j_q], e_all[j_q])
            need_0, budget_0 = need, budget
        # the dwell costs of the two rules where the vertex can dwell under them (NaN: it cannot;
        # the deep levels only the "isolated" rule's)
        cost_b = np.where(_can_dwell(need, budget, Tk_budget, Td) & (k <= NEST_STEPS), Td - Tk_budget, np.nan)
        cost_w = np.where(_can_dwell(need, tol_k, Tk_whole, Td), Td - Tk_whole, np.nan)
        cheaper = _dwell_cheaper(every, s_v, Fv, cap, Td, tol_k, np.stack([cost_b, cost_w]))
        cost_b = cost_w = None
        for i, (rule, gap) in enumerate(_dwell_sets(cheaper, need, budget, tol_k, Tk_budget, Tk_whole, Td)):
            if k > NEST_STEPS and i != _DEEP_SET:
                continue
            # the dwell set and rule define the candidate; at tol_v a vertex that needs a slow-down
            # and has no feed (zero tolerance) stops exactly whatever the set
            gap = gap | (need_0 & ((f_w <= 0) | ((tol_v <= 0) & ~straight)))
            key = (rule if gap.any() else 1, gap.tobytes())
            if key not in seen:
                seen.add(key)
                sets.append((rule, gap, i == _EVERY_CAN, k > NEST_STEPS))
    Tk = Tk_budget = Tk_whole = need = budget = tol_k = cheaper = j_q = every = None  # (and the chain's prefix sums)
    # the vertices strictly inside each window at its own feed on the whole chain (feeds_without)
    own_lo = np.searchsorted(s_v, s_v - f_w * every_rho, side="right")
    own_hi = np.searchsorted(s_v, s_v + f_w * every_rho, side="left")
    # every set with its feeds held over the whole support T_d / 2, and over the reach of
    # window_half_width as well (module docstring, "Window reach": neither is faster on every
    # program), but "every vertex that can dwell", which few windows hold a feed in
    support = np.full(M - 1, 0.5 * Td)
    context = (tp, F_cmd, F, s_v, np.concatenate([[0.0], np.cumsum(tp.lengths)]), _arcs(table, F))
    out, shared, kept = [], {}, {}
    for rule, gap, every_can, deep in sets:
        reaches = (hold,) if deep else (hold, support) if not every_can else (support,)
        full = shared.setdefault(("full", gap.tobytes()), ~gap)
        f = feeds_without(gap)
        dwell_tol = np.clip(tol_v - (budget_0, tol_v)[rule], 0.0, tol_v)[gap]
        for h in reaches if np.any(hold < support) else (support,):
            c = Candidate(context, full, f, h, dwell_tol)
            arrays = c()
            key = _key(arrays[:5])
            # a duplicate of a kept candidate (equal flags, tolerances of other turns, feed factors
            # and shares) is not offered again: an equal key is confirmed on the rebuilt arrays
            if not any(all(np.array_equal(a, b) for a, b in zip(arrays[:5], o()[:5])) for o in kept.get(key, ())):
                kept.setdefault(key, []).append(c)
                out.append((c, None if measure is None else measure(arrays)))
            arrays = None
    return out


def _arcs(table: PulseTable, F: np.ndarray):
    """The sub-arcs' start and end arc lengths [mm] and the feeds [mm/s] of their blocks ``(A,)``."""
    span = table.arc_span
    return np.ascontiguousarray(span[:, 0]), np.ascontiguousarray(span[:, 1]), F[table.block[table.arc_pieces]]


def arc_cuts(candidates) -> np.ndarray:
    """Arc lengths [mm] at which the windows of the candidates of :func:`look_ahead` end, ascending:
    where ``PulseTable.cut_arcs`` cuts the sub-arcs they end in.

    A window slows every piece it overlaps over the whole piece (one feed per piece); a line has
    head and tail pieces cut at its windows' reach, but a sub-arc (at most ``SUB_ARC`` of its arc)
    was slowed whole, so a window reaching a little further (at a looser tolerance: a higher
    window feed) could slow a whole further sub-arc and make the plan slower (measured:
    benchmarks/README.md, "Sub-arcs cut where windows end"). Cut at the windows' ends, the
    sub-arcs a window ends in are slowed over the stretch it covers (the value it ends at is the
    cut's: the piece after a cut does not overlap a window that ends there)."""
    ends = []
    for c, _ in candidates:
        _, _, F, s_v, _, (a0, a1, arc_F) = c._context
        _, fw, lo, hi = slowing_windows(F, s_v, c.full, c._feeds, c._hold)
        for x in (lo, hi):  # only where a window ends inside a sub-arc it slows
            a = np.minimum(np.searchsorted(a1, x, side="right"), a1.size - 1)
            ends.append(x[(a0[a] < x) & (x < a1[a]) & (fw < arc_F[a])])
    return np.unique(np.concatenate(ends)) if ends else np.zeros(0)


def with_table(candidates, table: PulseTable, measure=None):
    """The candidates of :func:`look_ahead` on ``table`` (a table of the same path whose sub-arcs
    are cut, ``PulseTable.cut_arcs``): the same dwell sets, feeds and reaches, their sub-arc
    slow-downs on the new pieces, each with ``measure`` of its arrays (or None)."""
    out, contexts = [], {}
    for c, _ in candidates:
        old = c._context
        if id(old) not in contexts:
            contexts[id(old)] = old[:5] + (_arcs(table, old[2]),)
        c._context = contexts[id(old)]
        out.append((c, None if measure is None else measure(c())))
    return out


def without_dwells(candidates):
    """The candidate of :func:`look_ahead` in which no vertex dwells, its window feeds held over
    the whole support ``T_d / 2`` (the widest reach), or None (a list without it: a single block,
    no look-ahead). Its feeds keep every window within the tolerance at full overlap everywhere
    (the chain of all turns): the ceiling under which feeds that change at full overlap at every
    corner keep the tolerance too (``_fir_staircase``'s candidate)."""
    found = [c for c, _ in candidates if isinstance(c, Candidate) and c.full.all()]
    return max(found, key=lambda c: float(np.min(c._hold, initial=np.inf)), default=None)


class Candidate:
    """A candidate of :func:`look_ahead`, kept as what builds its arrays: its full-overlap flags
    ``full`` ``(M - 1,)`` (bool; shared between the candidates of one dwell set), the window feeds
    ``feeds`` [mm/s] of its full-overlap vertices, the time [s] ``hold`` ``(M - 1,)`` each holds
    them (shared), and ``dwell_tol`` [mm], the tolerance the other turns take at each dwell vertex
    (``others`` there, 0 elsewhere). Held so, a candidate costs about 9 bytes per vertex where
    its arrays cost 49 (and ``8 A`` for the sub-arcs).

    Calling it builds ``(factor, head, tail, full, others, arc_rel)`` (:func:`look_ahead`): new
    ``factor``, ``head``, ``tail``, ``others`` and ``arc_rel`` arrays on every call (the planner
    repairs ``factor`` in place), the same ones every time (the same operations on the same inputs).
    """

    __slots__ = ("_context", "full", "_feeds", "_hold", "_dwell_tol")

    def __init__(self, context, full, feeds, hold, dwell_tol):
        self._context, self.full, self._feeds, self._hold, self._dwell_tol = context, full, feeds, hold, dwell_tol

    def __call__(self):
        factor, head, tail, arc_rel = _candidate(*self._context, self.full, self._feeds, self._hold)
        others = np.zeros(self.full.size)
        others[~self.full] = self._dwell_tol
        return factor, head, tail, self.full, others, arc_rel


def _key(arrays):
    """A key of a candidate's ``(factor, head, tail, full, others)``: the flags (one array per dwell
    set, so by identity) and the sums of the others. Arrays equal by ``np.array_equal`` have equal
    keys (equal values summed in the same order; a sum of zeros compares equal whatever its sign);
    the converse is confirmed by the caller."""
    factor, head, tail, full, others = arrays
    return (id(full),) + tuple(float(x.sum()) for x in (others, factor, head, tail))


def deep_levels(tol):
    """Tolerances ``(DEEP_STEPS, M - 1)`` [mm]: the points ``NEST_RATIO^m`` of a fixed grid (``m``
    integer, in mm) strictly below ``tol``, nearest first (module docstring, "Deeper levels");
    0 where ``tol`` is 0."""
    tol = np.asarray(tol, dtype=np.float64)
    pos = tol > 0
    with np.errstate(divide="ignore"):
        m = np.floor(np.log(np.where(pos, tol, 1.0)) / np.log(NEST_RATIO))  # q^(m+1) < tol <= q^m up to rounding
    grid = NEST_RATIO ** (m[None, :] + np.arange(1, DEEP_STEPS + 1)[:, None])
    grid = np.where(grid < tol, grid, grid * NEST_RATIO)  # strictly below tol after rounding
    return np.where(pos, grid, 0.0)


def window_half_width(delays, own_share):
    """Time [s] each side of a vertex over which its window's feed is held on the blocks
    (module docstring, "Window reach"): the kernel's half support ``T_d / 2`` for the share of the
    window's displacement that the vertex's own turn makes, its rms half-width
    ``sqrt(sum T_i^2 / 12)`` for the share the other turns of the window make.

    Args:
        delays: ``(n,)`` filter delays ``T_i`` [s].
        own_share: share in ``[0, 1]`` of the vertex's own turn in its window's displacement.

    Returns:
        Half-widths [s], shaped like ``own_share``.
    """
    d = np.asarray(delays, dtype=np.float64)
    w = np.clip(np.asarray(own_share, dtype=np.float64), 0.0, 1.0)
    return w * (0.5 * float(d.sum())) + (1.0 - w) * float(np.sqrt(np.sum(d**2) / 12.0))


_EVERY_CAN = 2  # index of "every vertex that can dwell" among the sets of _dwell_sets


def _can_dwell(need, tol, Tk, Td):
    """Where a vertex can dwell under a rule that leaves it the tolerance ``tol``: it needs a
    slow-down, ``tol > 0`` and eq 13/14 gives a gap (``T_k < T_d``)."""
    return need & (tol > 0) & (Tk < Td * (1 - 1e-12))


def _dwell_sets(cheaper, need, budget, tol, Tk_budget, Tk_whole, Td):
    """The dwell sets of one tolerance ``tol`` ``(M - 1,)``, each ``(rule, mask)`` (rule 0:
    "budget", 1: "isolated"): where the dwell is cheaper than the slow-down (``cheaper`` ``(2, M -
    1)``, each rule's, :func:`_dwell_cheaper`), every vertex that can dwell, none.

    A vertex can dwell where it needs a slow-down (``need``), its rule leaves it some tolerance
    (``budget``, ``tol``) and eq 13/14 gives a gap (``T_k < T_d``)."""
    out = []
    for rule, b, Tk in ((0, budget, Tk_budget), (1, tol, Tk_whole)):
        can = _can_dwell(need, b, Tk, Td)
        out.append((rule, can & cheaper[rule]))
        if rule == 1:
            out += [(1, can), (1, np.zeros_like(can))]
    return out


def _break_even_feed(cap, Td, Fv, cost):
    """The window feed [mm/s] whose slow-down costs ``cost`` [s] (``0 < cost < T_d``; 0 for a cost
    of ``T_d`` or more).

    The slow-down of a vertex's window from ``F_v`` to ``f`` is estimated to lose
    ``min(f T_d, cap) (1 / f - 1 / F_v)``: the time lost on the stretch the window slows, ``f T_d``,
    or its share of the blocks when neighbouring windows join (``cap`` [mm], half the two blocks).
    That is ``T_d (1 - f / F_v)`` while ``f T_d <= cap`` and ``cap (1 / f - 1 / F_v)`` above: it
    falls strictly from ``T_d`` at ``f -> 0`` to 0 at ``F_v``, so a window feed ``f`` costs more
    than a dwell of ``cost`` exactly when ``f`` is below the feed returned."""
    f = Fv * (1.0 - cost / Td)
    with np.errstate(divide="ignore"):
        beyond = 1.0 / (cost / cap + 1.0 / Fv)
    return np.maximum(np.where(f * Td <= cap, f, beyond), 0.0)


def _dwell_cheaper(chain, s_v, Fv, cap, Td, tol, costs):
    """Where each rule's dwell is cheaper than the slow-down: ``(C, M - 1)`` bool for the dwell
    costs ``costs`` ``(C, M - 1)`` [s] (NaN: the vertex cannot dwell under that rule; False there).

    The slow-down cost falls strictly with the window feed ``f``, so the dwell is cheaper exactly
    when ``f`` is below the break-even feed ``f*`` (:func:`_break_even_feed`),
    i.e. when the window's displacement at ``f*`` is above the tolerance (the error grows with
    the feed; where it does not, this is still one definite rule). One evaluation of the chain's
    error per rule and vertex, instead of the window feed's root search, and the same function of
    the tolerance wherever it is asked: a level ``eps q^k`` of a call at ``eps`` decides what a
    call at ``eps q^k`` decides at its own tolerance, bit for bit (module docstring, item 1)."""
    out = np.zeros(costs.shape, dtype=bool)
    rows, j = np.nonzero(~np.isnan(costs))
    if j.size:
        f = _break_even_feed(cap[j], Td, Fv[j], costs[rows, j])
        out[rows, j] = chain(s_v[j], f) > tol[j]
    return out


def _candidate(tp, F_cmd, F, s_v, cum, arcs, full, f, hold):
    """Feed factors ``(M, 3)``, head and tail shares ``(M,)`` and sub-arc slow-downs ``(A,)`` of the
    candidate of :func:`look_ahead` whose vertices ``full`` ``(M - 1,)`` run at full overlap with
    their window feeds ``f`` [mm/s] (on the chain without the dwell turns), each held ``hold`` [s]
    ``(M - 1,)`` each side of its vertex (:func:`window_half_width`).

    The estimate holds a constant feed through the window: a vertex between blocks of different
    feeds (a line entering a slower arc) gets the lower one on both sides of it. Blocks inside a
    window run at its feed; a window reaching into a block slows its head or tail
    (:func:`line_pieces`); the window holds its feed for ``hold`` of *time* each side of its
    vertex: through the blocks it covers, which run at their (lower) body feeds, it reaches less
    far into the end block than ``f hold``; a window ``[lo, hi]`` slows the sub-arcs it overlaps
    (on a table whose sub-arcs are cut where the windows end, :func:`arc_cuts`: the stretch it covers).
    One compiled pass (``_fir_candidate_kernels.candidate_pieces``); ``cum`` ``(M + 1,)``: the arc length [mm]
    at each block start and the path's end; ``arcs``: the sub-arcs' start and end arc lengths and
    the feeds of their blocks ``(A,)`` each."""
    head, tail, feeds, arc_rel = candidate_pieces(cum, tp.lengths, F, s_v, full, f, hold, tp.is_arc, *arcs)
    return feeds / F_cmd[:, None], head, tail, arc_rel


def line_pieces(h_blk, h_reach, h_feed, t_blk, t_reach, t_feed, L, body, F, arc):
    """Head, body and tail pieces of every line from the windows that reach into it.

    A window reaching ``reach`` [mm] into a line from its start (``h_*``) or from its end (``t_*``)
    needs the feed ``<= feed`` over that stretch; ``body`` caps the whole line (windows that cover
    it). The feed the windows allow at a point of the line is a staircase: the minimum over the
    windows that cover the point. Three pieces can follow a staircase of at most three steps
    exactly (one window at each end, overlapping or not, or two steps at one end); otherwise the
    pieces take the cut points, among the staircase's steps, that give the least block time
    ``sum length / feed`` with each piece at the lowest feed it covers (never above a window's
    feed; a staircase of end pieces, not one piece at the slowest feed of all the windows).

    Returns:
        ``(head, tail, feeds)``: head and tail shares ``(M,)`` of the block length and the feeds
        ``(M, 3)`` [mm/s] of head, body and tail (``F`` and shares 0 on arcs and untouched lines).
        One compiled pass (``_fir_candidate_kernels.line_piece_feeds``).
    """
    return line_piece_feeds(*(np.ascontiguousarray(a) for a in (h_blk, h_reach, h_feed, t_blk, t_reach, t_feed)),
                            np.ascontiguousarray(L), np.ascontiguousarray(body), np.ascontiguousarray(F),
                            np.ascontiguousarray(arc))


def staircase_cut(r_h, f_h, r_t, f_t, length, cap):
    """Best three pieces of lines under the staircase of their windows (see :func:`line_pieces`):
    cut points among the steps, each piece at the minimum feed the windows allow over it.

    Args:
        r_h, f_h: ``(B, H)`` reach [mm] from each line's start and feed [mm/s] of its head windows
            (padding: reach 0); r_t, f_t: ``(B, T)`` the same from each line's end.
        length: ``(B,)`` line lengths [mm]; cap: ``(B,)`` feed cap of the whole line [mm/s].

    Returns:
        ``(head share (B,), tail share (B,), feeds (B, 3))``.
    """
    r_h, f_h, r_t, f_t = (np.ascontiguousarray(np.atleast_2d(np.asarray(a, dtype=np.float64))) for a in (r_h, f_h, r_t, f_t))
    length, cap = np.atleast_1d(np.asarray(length, dtype=np.float64)), np.atleast_1d(np.asarray(cap, dtype=np.float64))
    return staircase_cuts(r_h, f_h, r_t, f_t, np.ascontiguousarray(length), np.ascontiguousarray(cap))


def _arc_turns(tp: ToolPath, tol: float):
    """Arc length [mm] and direction change of the turns that stand for the arcs' own turning
    (``ToolPath.arc_chord_turns``: chords of sagitta ``tol / 100``, at least 1 um and at most 0.1 mm,
    and a half-chord turn at each end, so that each arc's turns add up to its whole turning), placed
    at their exact arc length on the path: chords are shorter than their arcs, so a running sum of
    chord lengths would drift ahead of the block vertices (about 3.5 mm over the 50,006 arcs of a
    101,262-block program, against windows of 3.6 mm). The sagitta was swept (1, 3 and 10 % of
    the tolerance: the same cycle and planning times to 0.003 %, ``benchmarks/README.md``)."""
    block, fraction, du = tp.arc_chord_turns(max(min(tol, 1e-2) * 1e-2, 1e-6))
    start = np.concatenate([[0.0], np.cumsum(tp.lengths)[:-1]])
    return start[block] + fraction * tp.lengths[block], du
