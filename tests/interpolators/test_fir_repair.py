"""``_fir_repair``: the bound of a round's first half against the whole round's repairs, and the
branch and bound of ``plan_fir`` that uses it.

Expected values are the module's claim checked on its definition: for any superset of the
violators at errors no smaller (what the path samples add in a full round), the full repairs leave
every factor and shrink at most the bound's; the bound of the full set itself equals the full
repairs where no window reaches past a vertex's own two blocks (blocks longer than a window,
without head and tail pieces); a window inside its lines' pieces slows those pieces only; and
the plan is the least verified time over the candidates, each verified alone (no bound involved);
a candidate that releases its profile while suspended and rebuilds it ends with the plan of one
that keeps it (the same arrays, bit for bit).
"""

import numpy as np
import pytest

import research.interpolators._fir_settle as settle
from research.interpolators import plan_fir
from research.interpolators._fir_repair import Repairs
from research.paths import Polyline


def _closed_curve(seed):
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 2.0 * np.pi, 600)
    r = 30.0 + 8.0 * np.sin(3.0 * t) + 3.0 * np.cos(7.0 * t)
    pts = np.column_stack([r * np.cos(t), r * np.sin(t), 2.0 * np.sin(2.0 * t)]) + rng.normal(0.0, 0.002, (600, 3))
    return Polyline(np.round(pts, 3))


def _case(rng, M, long_blocks=False, pieces=True):
    """Random repairs; ``pieces``: lines with head and tail pieces of random shares (some none)."""
    lengths = rng.uniform(20.0, 40.0, M) if long_blocks else rng.uniform(0.1, 3.0, M)
    full = rng.random(M - 1) < 0.6
    tv = rng.uniform(0.01, 0.1, M - 1)
    tb = np.concatenate([tv, tv[-1:]])
    feeds = rng.uniform(50.0, 250.0, M)
    head = np.where(rng.random(M) < 0.6, rng.uniform(0.0, 0.5, M), 0.0) if pieces else np.zeros(M)
    tail = np.where(rng.random(M) < 0.6, rng.uniform(0.0, 0.5, M), 0.0) if pieces else np.zeros(M)
    return Repairs(full, head, tail, tv, tb, feeds, lengths, 0.09, 2), tv


def test_bound_is_at_least_every_superset_repair():
    rng = np.random.default_rng(20261202)
    for trial in range(200):
        M = int(rng.integers(3, 60))
        rep, tv = _case(rng, M)
        factor = rng.uniform(0.3, 1.0, (M, 3))
        shrink = rng.uniform(0.2, 1.0, M - 1)
        viol = rng.random(M - 1) < 0.4
        errors = np.where(viol, tv * rng.uniform(1.0, 20.0, M - 1), tv * rng.uniform(0.0, 1.0, M - 1))
        late = bool(rng.random() < 0.1)
        f_b, s_b = rep.bound(viol, errors, late, factor, shrink)
        # the full round: more violators (path samples charged to vertices), larger errors, arcs
        more = viol | (rng.random(M - 1) < 0.3)
        e_full = np.where(more, np.maximum(errors, tv) * rng.uniform(1.0, 3.0, M - 1), errors)
        arc_dev = np.where(rng.random(M) < 0.1, rng.uniform(0.1, 1.0, M), 0.0)
        f_a, s_a = factor.copy(), shrink.copy()
        rep.apply(more, e_full, arc_dev, late, f_a, s_a)
        assert np.all(f_a <= f_b * (1 + 1e-15)), trial
        assert np.all(s_a <= s_b * (1 + 1e-15)), trial
        assert np.all(f_b <= factor) and np.all(s_b <= shrink)  # the bound repairs too (never speeds up)


def test_bound_is_the_repair_when_windows_hold_only_their_own_blocks():
    """Blocks of 20-40 mm against windows of at most 250 mm/s x 0.045 s = 11 mm each side: every
    window is the vertex's two blocks, so the bound and the repair agree (up to the order of the
    products)."""
    rng = np.random.default_rng(7)
    for _ in range(50):
        M = int(rng.integers(3, 30))
        rep, tv = _case(rng, M, long_blocks=True, pieces=False)
        factor, shrink = np.ones((M, 3)), np.ones(M - 1)
        viol = rng.random(M - 1) < 0.5
        errors = np.where(viol, tv * rng.uniform(1.0, 5.0, M - 1), 0.0)
        f_b, s_b = rep.bound(viol, errors, False, factor, shrink)
        rep.apply(viol, errors, np.zeros(M), False, factor, shrink)
        np.testing.assert_allclose(f_b, factor, rtol=1e-14)
        np.testing.assert_allclose(s_b, shrink, rtol=1e-14)
        assert np.any(factor < 1.0) or not np.any(viol & rep.full)


def test_a_window_inside_the_pieces_slows_only_the_pieces():
    """One violating full-overlap vertex between two long lines whose tail and head pieces hold its
    window ``T_d F / 2`` (at the tail feed): those two pieces slow by ``0.98 sqrt(eps / error)``
    and nothing else changes; with pieces shorter than the window, both lines slow whole (the
    window's distances by hand: 0.045 s x 100 mm/s = 4.5 mm each side)."""
    lengths, feeds = np.array([30.0, 25.0]), np.array([100.0, 100.0])
    for head1, whole in ((0.2, False), (0.1, True)):  # 5 mm or 2.5 mm of the second line
        head, tail = np.array([0.0, head1]), np.array([0.2, 0.0])  # 6 mm of the first line
        rep = Repairs(np.ones(1, bool), head, tail, np.full(1, 0.05), np.full(2, 0.05), feeds, lengths, 0.09, 2)
        factor, shrink = np.ones((2, 3)), np.ones(1)
        rep.apply(np.ones(1, bool), np.full(1, 0.2), np.zeros(2), False, factor, shrink)
        g = 0.98 * np.sqrt(0.25)
        expected = np.ones((2, 3))
        expected[0, 2] = g
        if whole:
            expected[1] = g
        else:
            expected[1, 0] = g
        np.testing.assert_allclose(factor, expected, rtol=1e-15)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_branch_and_bound_returns_the_least_verified_candidate(seed, monkeypatch):
    """A rounded CAM-like closed curve of 599 chords (11 candidates, the first-blocks bound on:
    M / 8 >= 32): the cycle time equals the least over the candidates each planned alone, which
    verifies every one to the end (to 1e-12: see below). A bound above a candidate's verified time
    (tried: the first blocks' or a round's first half) drops the winner on these programs."""
    args = (_closed_curve(seed), 200.0, (0.06, 0.03), 0.05)
    found = []
    look_ahead = settle.look_ahead

    def grab(*a, **k):
        found.extend(look_ahead(*a, **k))
        return found

    monkeypatch.setattr(settle, "look_ahead", grab)
    whole = float(plan_fir(*args).cycle_time)
    assert len(found) > 5
    alone = []
    for c in list(found):
        monkeypatch.setattr(settle, "look_ahead", lambda *a, c=c, **k: [c])
        alone.append(float(plan_fir(*args).cycle_time))
    # equal up to rounding: a candidate checked after another adopts that one's check and redoes
    # it only where their profiles differ, the rest kept "up to the time shift" (RoundChecks), so
    # its repairs can differ from its check alone in the last bits (seed 0: 3.5e-15 s)
    best = int(np.argmin(alone))
    assert abs(whole - alone[best]) <= 1e-12 * whole
    assert all(t > whole * (1 + 1e-9) for i, t in enumerate(alone) if i != best and t != alone[best])


@pytest.mark.parametrize("seed", [0, 1])
def test_released_profiles_rebuild_the_same_plan(seed, monkeypatch):
    """Every suspended candidate releasing its profile (``_HELD_PROFILES = 0``, rebuilt on resume)
    gives the plan of none releasing it, bit for bit; and the closed curve does release some."""
    from research.interpolators._fir_verify import RoundChecks

    args = (_closed_curve(seed), 200.0, (0.06, 0.03), 0.05)
    released = []
    swap = RoundChecks.swap_profile

    def counted(self, position, *resumed):
        released.append(position is None)
        return swap(self, position, *resumed)

    monkeypatch.setattr(RoundChecks, "swap_profile", counted)
    monkeypatch.setattr(settle, "_HELD_PROFILES", 10**6)
    keep = plan_fir(*args)
    assert not released
    monkeypatch.setattr(settle, "_HELD_PROFILES", 0)
    rebuilt = plan_fir(*args)
    assert any(released)
    for name in ("start_times", "pulse_times", "overlaps", "feeds", "corner_times"):
        np.testing.assert_array_equal(getattr(rebuilt, name), getattr(keep, name))
    np.testing.assert_array_equal(rebuilt.position.coeffs, keep.position.coeffs)
    assert (rebuilt.rounds, rebuilt.path_deviation) == (keep.rounds, keep.path_deviation)
