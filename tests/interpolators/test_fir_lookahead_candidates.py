"""Look-ahead candidates kept as what builds them (``_fir_lookahead.Candidate``; issue 19 item 4,
planning memory) against the forms they replace: their arrays built once and held (as the planner
held them before), the duplicate check comparing every pair, and eq 13/14 overlaps of all levels in
one batch. The programs are ``research.paths.library.random_program`` with eps and F drawn after
them from the same seeded generator (as in ``test_fir_monotone``)."""

import numpy as np
import pytest

import research.interpolators._fir_lookahead as lookahead
from research.interpolators import _fir_settle, plan_fir
from research.interpolators._fir_profile import overlaps
from research.interpolators._fir_settle import _pulse_table
from research.interpolators.fir import _as_toolpath
from research.paths.library import random_program

DELAYS = (0.06, 0.03)


def _program(seed: int, arcs: bool):
    rng = np.random.default_rng(seed)
    tp = _as_toolpath(random_program(rng, arcs=arcs))
    eps, feed = float(np.exp(rng.uniform(np.log(0.005), np.log(0.5)))), float(rng.uniform(20.0, 300.0))
    return tp, eps, feed


def _candidates(seed: int, arcs: bool, delays=DELAYS):
    tp, eps, feed = _program(seed, arcs)
    M = tp.n_blocks
    t_in, t_out = tp.tangents()
    return lookahead.look_ahead(tp, _pulse_table(tp), np.full(M, feed), np.ones(M), np.asarray(delays),
                                np.full(M - 1, eps), t_in, t_out, False)


@pytest.mark.parametrize("arcs", [False, True])
def test_a_candidate_builds_new_equal_arrays(arcs):
    """Each call builds the same arrays, new ones (the planner repairs ``factor`` in place, so a
    later build must not see it), with boolean flags and the other turns' tolerance 0 at full
    overlap (seeds 0-5)."""
    for seed in range(6):
        cands = _candidates(seed, arcs)
        assert len(cands) > 1
        for c, measured in cands:
            assert measured is None
            a = c()
            a[0][...] = -1.0  # a repair in place
            b = c()
            assert not np.shares_memory(a[0], b[0])
            for x, y in zip(c(), b):
                np.testing.assert_array_equal(x, y)
            full, others = b[3], b[4]
            assert full.dtype == bool and np.all(others[full] == 0.0) and np.all(b[0] > 0)


@pytest.mark.parametrize("arcs", [False, True])
def test_duplicate_check_is_the_pairwise_comparison(arcs, monkeypatch):
    """The key only picks which kept candidates a new one is compared with: with every key equal
    (each new candidate compared with every kept one by ``np.array_equal`` on flags, other turns'
    tolerances, feed factors and shares, the check before the key) the same candidates come out,
    and no two of them are equal (seeds 0-5)."""
    for seed in range(6):
        got = [c() for c, _ in _candidates(seed, arcs)]
        with monkeypatch.context() as m:
            m.setattr(lookahead, "_key", lambda arrays: 0)
            want = [c() for c, _ in _candidates(seed, arcs)]
        assert len(got) == len(want)
        for g, w in zip(got, want):
            for x, y in zip(g, w):
                np.testing.assert_array_equal(x, y)
        for i in range(len(got)):
            for j in range(i):
                assert not all(np.array_equal(got[i][k], got[j][k]) for k in range(5)), (seed, i, j)


@pytest.mark.parametrize("arcs", [False, True])
@pytest.mark.parametrize("delays", [DELAYS, (0.05, 0.03, 0.012)])
def test_plans_equal_those_of_candidates_built_once(arcs, delays, monkeypatch):
    """``plan_fir`` with the candidates built when started equals, bit for bit, ``plan_fir`` with
    every candidate's arrays built once by the look-ahead and held to the end (each start given
    its own copy of the feed factors), on seeds 0-3 (two and three filters). On arc programs the
    candidates the planner starts come from ``with_table`` (the look-ahead's, on the table whose
    sub-arcs are cut where their windows end); the look-ahead before the cut is left as it is."""
    look, rebind = _fir_settle.look_ahead, _fir_settle.with_table

    def once(candidates):
        out = []
        for c, bound in candidates:
            arrays = c()
            out.append((lambda arrays=arrays: (arrays[0].copy(),) + arrays[1:], bound))
        return out

    def held(*args, measure=None):
        return look(*args, measure=measure) if measure is None else once(look(*args, measure=measure))

    for seed in range(4):
        tp, eps, feed = _program(seed, arcs)
        lazy = plan_fir(tp, feed, delays, eps)
        with monkeypatch.context() as m:
            m.setattr(_fir_settle, "look_ahead", held)
            m.setattr(_fir_settle, "with_table", lambda *args, **kwargs: once(rebind(*args, **kwargs)))
            once_plan = plan_fir(tp, feed, delays, eps)
        assert lazy.rounds == once_plan.rounds and lazy.path_deviation == once_plan.path_deviation
        for name in ("start_times", "pulse_times", "overlaps", "feeds", "corner_times"):
            np.testing.assert_array_equal(getattr(lazy, name), getattr(once_plan, name))
        np.testing.assert_array_equal(lazy.position.breaks, once_plan.position.breaks)
        np.testing.assert_array_equal(lazy.position.coeffs, once_plan.position.coeffs)


@pytest.mark.parametrize("delays", [(0.08,), DELAYS])
def test_closed_form_overlaps_are_elementwise(delays):
    """What deciding the levels one at a time rests on: eq 13/14's closed forms (one and two
    filters) give each element the value it has in a batch of rows, bit for bit (zero speed
    changes and zero tolerances included)."""
    rng = np.random.default_rng(0)
    tol = np.exp(rng.uniform(np.log(1e-5), np.log(1.0), (7, 1001)))
    tol[:, :4] = 0.0
    dF = rng.uniform(0.0, 400.0, 1001)
    dF[::97] = 0.0
    d = np.asarray(delays)
    batch = overlaps(tol, np.tile(dF, (7, 1)), d)
    for k in range(7):
        np.testing.assert_array_equal(overlaps(tol[k], dF, d), batch[k])


def range_min(first, last, values, n, initial):
    """``min(initial[k], min{values[r] : first[r] <= k <= last[r]})`` cell by cell (ranges outside
    ``[0, n - 1]`` cover only the cells they hold)."""
    out = np.array(initial, dtype=np.float64)
    for a, b, v in zip(first, last, values):
        a, b = max(int(a), 0), min(int(b), n - 1)
        if a <= b:
            out[a:b + 1] = np.minimum(out[a:b + 1], v)
    return out


def numpy_candidate(tp, table, F_cmd, F, s_v, full, f, hold):
    """``_fir_lookahead._candidate`` by whole-array NumPy (its form before the compiled pass, the
    range minima cell by cell): ``(factor, head, tail, arc_rel)``."""
    from research.interpolators._fir_lookahead import line_pieces

    M, L = tp.n_blocks, tp.lengths
    query = np.flatnonzero(full)
    slow = f < np.maximum(F[:-1], F[1:])[query] * (1 - 1e-12)
    j, f = query[slow], f[slow]
    half = hold[j]
    lo, hi = s_v[j] - half * f, s_v[j] + half * f
    cum = np.concatenate([[0.0], np.cumsum(L)])
    right = np.searchsorted(cum, hi, side="right")
    first, last = np.searchsorted(cum, lo, side="left"), right - 2
    body = range_min(first, last, f, M, F)
    k_r = np.clip(right - 1, 0, M - 1)
    k_l = np.clip(np.searchsorted(cum, lo, side="right") - 1, 0, M - 1)
    t_cum = np.concatenate([[0.0], np.cumsum(L / body)])
    reach_r = np.minimum(hi - cum[k_r], np.maximum(half - (t_cum[k_r] - t_cum[j + 1]), 0.0) * f)
    reach_l = np.minimum(cum[k_l + 1] - lo, np.maximum(half - (t_cum[j + 1] - t_cum[k_l + 1]), 0.0) * f)
    inside_r = (hi < cum[k_r + 1]) & (reach_r > 0)
    inside_l = (lo > cum[k_l]) & (reach_l > 0)
    head, tail, piece_f = line_pieces(k_r[inside_r], reach_r[inside_r], f[inside_r], k_l[inside_l], reach_l[inside_l],
                                      f[inside_l], L, body, F, tp.is_arc)
    span = table.arc_span
    a_first = np.searchsorted(span[:, 1], lo, side="right")
    a_last = np.searchsorted(span[:, 0], hi, side="left") - 1
    A = span.shape[0]
    arc_f = range_min(a_first, a_last, f, A, np.full(A, np.inf)) if A else np.zeros(0)
    arc_rel = np.minimum(arc_f / F[table.block[table.arc_pieces]], 1.0) if A else np.zeros(0)
    return piece_f / F_cmd[:, None], head, tail, arc_rel


@pytest.mark.parametrize("arcs", [False, True])
def test_compiled_candidate_matches_the_numpy_form(arcs):
    """``_candidate`` (``_fir_candidate_kernels.candidate_pieces``: galloping searches, ranges pushed down
    level by level) against its whole-array NumPy form, bit for bit: on every candidate of seeded
    random programs, and on the same programs with random feeds and reaches (windows from none
    to many blocks, feeds above and below the blocks')."""
    rng = np.random.default_rng(7)
    n_arcs = 0
    for seed in range(8):
        tp, eps, feed = _program(seed, arcs)
        table = _pulse_table(tp)
        n_arcs += table.arc_span.shape[0]
        M = tp.n_blocks
        F_cmd, s_v = np.full(M, feed), np.cumsum(tp.lengths)[:-1]
        cases = []
        for c, _ in _candidates(seed, arcs):
            a = c()
            cases.append((F_cmd * np.ones(M), a[3], c._feeds, c._hold))
        for _ in range(3):
            F = feed * rng.uniform(0.3, 1.0, M)
            full = rng.random(M - 1) < rng.uniform(0.2, 1.0)
            f = feed * rng.uniform(0.01, 1.2, int(full.sum()))
            hold = rng.uniform(0.0, 0.2, M - 1) * rng.choice([0.01, 1.0, 20.0], M - 1)
            cases.append((F, full, f, hold))
        for F, full, f, hold in cases:
            got = lookahead._candidate(tp, F_cmd, F, s_v, np.concatenate([[0.0], np.cumsum(tp.lengths)]),
                                       (np.ascontiguousarray(table.arc_span[:, 0]),
                                        np.ascontiguousarray(table.arc_span[:, 1]),
                                        F[table.block[table.arc_pieces]]), full, f, hold)
            want = numpy_candidate(tp, table, F_cmd, F, s_v, full, f, hold)
            for g, w in zip(got, want):
                np.testing.assert_array_equal(g, w)
    assert n_arcs > 0 or not arcs


def _kinked_chain(seed: int) -> np.ndarray:
    """400 chords of 0.3 mm turning by 0.01 +- 0.004 rad each, with 12 kinks of 0.05-0.3 rad
    (a finishing pass with a few sharper vertices): windows of many chords whose reach at the
    commanded feed holds a kink that their own (slower) window does not."""
    rng = np.random.default_rng(seed)
    ang = np.cumsum(rng.normal(0.0, 0.004, 400) + 0.01)
    ang[rng.choice(400, 12, replace=False)] += rng.choice([-1.0, 1.0], 12) * rng.uniform(0.05, 0.3, 12)
    return np.vstack([[0.0, 0.0], np.cumsum(0.3 * np.column_stack([np.cos(ang), np.sin(ang)]), axis=0)])


def test_window_feeds_are_feasible_roots_on_the_chain_without_the_dwell_turns():
    """Every candidate's window feeds (its full-overlap vertices) keep the windowed displacement
    within eps on the chain without its dwell turns, and none lies below the lowest feed at which
    that displacement reaches eps (found independently: a scan of the feeds up to F, refined by
    bisection; to the search's stopping band), so no window is slower than its first root. Holds
    for the windows the look-ahead re-solves and for those that keep their feed on the whole chain
    (their own reach holds no dwell turn). Line programs (seeds 0-9) and kinked chord chains
    (seeds 0-1, where such windows are many)."""
    from research.interpolators._fir_feed import ChainError
    from research.paths import Polyline

    programs = [_program(seed, False) + (4000,) for seed in range(10)]
    programs += [(_as_toolpath(Polyline(_kinked_chain(seed))), 0.02, 150.0, 600) for seed in range(2)]
    for tp, eps, feed, n_grid in programs:
        M = tp.n_blocks
        t_in, t_out = tp.tangents()
        s_v, du = np.cumsum(tp.lengths)[:-1], t_in[1:] - t_out[:-1]
        cands = lookahead.look_ahead(tp, _pulse_table(tp), np.full(M, feed), np.ones(M), np.asarray(DELAYS),
                                     np.full(M - 1, eps), t_in, t_out, False)
        grid = np.linspace(0.0, 1.0, n_grid + 1)[1:]
        for c, _ in cands:
            chain = ChainError(s_v[c.full], du[c.full], np.asarray(DELAYS))
            s, f = s_v[c.full], c._feeds
            assert np.all(chain(s, f) <= eps * (1 + 1e-9))
            j = np.flatnonzero(f < feed)
            if not j.size:
                continue
            over = chain(np.repeat(s[j], grid.size), feed * np.tile(grid, j.size)).reshape(j.size, -1) > eps
            first = np.argmax(over, axis=1)  # every window below F has an infeasible feed above its own
            lo, hi = np.where(first > 0, feed * grid[first - 1], 0.0), feed * grid[first]
            for _ in range(60):
                mid = 0.5 * (lo + hi)
                ok = chain(s[j], mid) <= eps
                lo, hi = np.where(ok, mid, lo), np.where(ok, hi, mid)
            # the search stops within _fir_feed._CLOSE = 2^-30 (log of the error) of eps: ~1e-9
            # of the feed where the error grows about linearly with it, more where it grows slower
            assert np.all(f[j] >= lo * (1 - 1e-8)), (tp.n_blocks, f[j] / lo)
