"""Look-ahead candidates kept as what builds them (``_fir_lookahead.Candidate``; issue 19 item 4,
planning memory) against the forms they replace: their arrays built once and held (as the planner
held them before), the duplicate check comparing every pair, and eq 13/14 overlaps of all levels in
one batch. The programs are ``research.paths.library.random_program`` with eps and F drawn after
them from the same seeded generator (as in ``test_fir_monotone``)."""

import numpy as np
import pytest

import research.interpolators._fir_lookahead as lookahead
from research.interpolators import fir, plan_fir
from research.interpolators._fir_profile import overlaps
from research.interpolators.fir import _as_toolpath, _pulse_table
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
                                np.full(M - 1, eps), t_in, t_out)


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
    """The digest only picks which kept candidates a new one is compared with: with every digest
    equal (each new candidate compared with every kept one by ``np.array_equal`` on flags, other
    turns' tolerances, feed factors and shares, the check before the digest) the same candidates
    come out, and no two of them are equal (seeds 0-5)."""
    for seed in range(6):
        got = [c() for c, _ in _candidates(seed, arcs)]
        with monkeypatch.context() as m:
            m.setattr(lookahead, "_digest", lambda arrays: b"")
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
    its own copy of the feed factors), on seeds 0-3 (two and three filters)."""
    look = fir.look_ahead

    def held(*args, **kwargs):
        out = []
        for c, bound in look(*args, **kwargs):
            arrays = c()
            out.append((lambda arrays=arrays: (arrays[0].copy(),) + arrays[1:], bound))
        return out

    for seed in range(4):
        tp, eps, feed = _program(seed, arcs)
        lazy = plan_fir(tp, feed, delays, eps)
        with monkeypatch.context() as m:
            m.setattr(fir, "look_ahead", held)
            once = plan_fir(tp, feed, delays, eps)
        assert lazy.rounds == once.rounds and lazy.path_deviation == once.path_deviation
        for name in ("start_times", "pulse_times", "overlaps", "feeds", "corner_times"):
            np.testing.assert_array_equal(getattr(lazy, name), getattr(once, name))
        np.testing.assert_array_equal(lazy.position.breaks, once.position.breaks)
        np.testing.assert_array_equal(lazy.position.coeffs, once.position.coeffs)


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
