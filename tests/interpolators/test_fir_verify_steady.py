"""The path check's steady spans (``_fir_verify.steady_spans``): where no sample's averaging
window holds an input break, the grid is thinned, so a check costs in proportion to the program's
pieces and not to its duration.

References: the index sets are checked against NumPy set computations; the thinned check
against the full grid on the same profile; an arc's steady deviation against eq 8 of Sencer 2015
read for a circle (the FIR average of a constant-speed circular motion is a circle of radius
``R prod sinc(Omega T_i / 2)``, ``Omega = F / R``: issue "FIR cornering on real CAM programs", item
1). Nothing is compared with the planner's earlier output."""

import numpy as np
import pytest

from research.interpolators import _fir_profile, _fir_verify, plan_fir
from research.interpolators._fir_blocks import PulseTable
from research.interpolators._fir_verify import STEADY_SAMPLES, path_deviations, steady_spans
from research.interpolators._fir_verify_kernels import grid_times, thinned_runs
from research.paths import Polyline
from research.paths.gcode import parse_gcode
from research.paths.toolpath import ToolPath
from research.piecewise import NumpyPiecewise

DELAYS = np.array([0.06, 0.03])


def _disjoint(rng, n, hi):
    """``n`` sorted, disjoint integer intervals ``[lo, hi]`` within ``[0, hi]`` (some single points)."""
    cuts = np.sort(rng.choice(hi, 2 * n, replace=False))
    return cuts[0::2].astype(np.int64), cuts[1::2].astype(np.int64)


@pytest.mark.parametrize("seed", range(20))
def test_thinned_runs_keep_every_index_outside_the_spans_and_the_strided_ones_inside(seed):
    """Random runs and spans: the indices the thinned runs (``grid_times``'s input) produce are,
    in order, those of the runs outside every span, and inside a span those ``s_first + n stride``
    (counted from the span's start, whichever run meets it)."""
    rng = np.random.default_rng(seed)
    first, last = _disjoint(rng, int(rng.integers(1, 8)), 400)
    s_first, s_last = _disjoint(rng, int(rng.integers(0, 6)), 400)
    stride = rng.integers(1, 9, s_first.size).astype(np.int64)
    want = []
    for a, b in zip(first, last):
        for i in range(a, b + 1):
            inside = np.flatnonzero((s_first <= i) & (i <= s_last))
            if inside.size == 0 or (i - s_first[inside[0]]) % stride[inside[0]] == 0:
                want.append(i)
    f, c, s = thinned_runs(first, last, s_first, s_last, stride)
    got = [int(a + k * st) for a, n, st in zip(f, c, s) for k in range(n)]
    assert got == want


def test_grid_times_follow_strided_runs():
    """Runs with strides: any chunk of the times equals the NumPy gather of each sample's run,
    ``t0 + (first + k stride) period`` clipped to ``[t0, t1]``."""
    first = np.array([0, 7, 30, 100], np.int64)
    count = np.array([5, 0, 12, 3], np.int64)
    stride = np.array([1, 3, 4, 1], np.int64)
    ends = np.cumsum(count)
    t0, t1, period = 0.25, 0.25 + 101 * 1e-3, 1e-3
    k = np.arange(ends[-1])
    run = np.searchsorted(ends, k, side="right")
    want = np.clip(t0 + (first[run] + (k - (ends[run] - count[run])) * stride[run]) * period, t0, t1)
    for i, j in ((0, ends[-1]), (3, 14), (9, 9)):
        np.testing.assert_array_equal(grid_times(i, j, first, count, stride, ends, t0, t1, period), want[i:j])


def _slow_arc_profile(feed):
    """Line 10 mm, quarter arc R 5 mm, line 10 mm at ``feed`` [mm/s], 10 ms dwell gaps: the
    exact profile and its input (as ``plan_fir``'s schedule builds them)."""
    tp = ToolPath.from_polyline(Polyline([[0.0, 0.0], [10.0, 0.0]]))
    tp = tp.then_arc([15.0, 5.0], [10.0, 5.0], ccw=True)
    tp = ToolPath(tp.start, np.vstack([tp.ends, [[15.0, 15.0]]]), np.vstack([tp.centers, [[np.nan, np.nan]]]),
                  np.vstack([tp.normals, [[np.nan] * 3]]), np.concatenate([tp.sweeps, [0.0]]))
    table = PulseTable.from_path(tp)
    M, Mp = tp.n_blocks, table.m_pad
    frac, factor = table.pieces(np.zeros(M), np.zeros(M), np.ones((M, 3)))
    piece_tv = np.concatenate([tp.lengths, np.ones(Mp - M + 1)])[table.block] / (feed * factor)
    gaps = np.concatenate([np.full(M - 1, 0.01), np.zeros(Mp - M + 1)])
    starts, _, breaks, coeffs, centre = _fir_profile.profile(tp.start, table.geo, table.block, table.gap, frac,
                                                             piece_tv, gaps, DELAYS)
    durations = np.where(table.gap, np.append(gaps, 0.0)[table.block], frac * piece_tv)
    return tp, NumpyPiecewise(breaks, coeffs), starts[:M], centre[: M - 1], durations


def test_thinned_check_finds_the_full_grids_deviations_on_a_slow_arc():
    """At 2 mm/s (a 17 s program, spans of seconds) the thinned check takes a fraction of the
    full grid's samples and finds the same deviations: the largest, and the arc's, whose
    tolerance is set at half its steady radial error ``R (1 - sinc(W T1 / 2) sinc(W T2 / 2))`` so
    that its largest sample is reported; both at least that steady error."""
    feed, R = 2.0, 5.0
    tp, pos, starts, centre, durations = _slow_arc_profile(feed)
    W = feed / R
    steady = R * (1.0 - np.prod(np.sinc(W * DELAYS / 2.0 / np.pi)))
    tol = np.array([1.0, 0.5 * steady, 1.0])
    Td, period = float(DELAYS.sum()), 1e-3
    full = path_deviations(pos, tp, starts, centre, Td, tol, period)
    thin = path_deviations(pos, tp, starts, centre, Td, tol, period, durations)
    assert thin[0] == pytest.approx(full[0], rel=1e-9)
    assert set(thin[2]) == set(full[2]) == {1}
    assert thin[2][1] == pytest.approx(full[2][1], rel=1e-6)
    assert thin[2][1] >= steady * (1 - 1e-6)
    t0, t1 = float(pos.breaks[0]), float(pos.breaks[-1])
    n_full = int(np.ceil((t1 - t0) / period)) + 1
    spans = steady_spans(starts, durations, t0, Td, period)
    n_thin, _ = _fir_verify._sample_times(np.zeros(1, np.int64), np.array([n_full - 1]), t0, t1, period, centre,
                                          spans)
    assert spans[0].size >= 5 and n_thin < 0.2 * n_full


def test_a_program_at_a_thousandth_of_a_mm_per_minute_is_checked_by_its_pieces_not_its_duration(monkeypatch):
    """Regression (stress sweep, a mutated program with ``G1 F0.001``): the path check sampled
    every ms of the ~2e6 s motion and did not finish. Now every check takes at most
    ``STEADY_SAMPLES + T_d / period + 4`` samples per input piece (thinned steady spans and the
    dense grid next to every break) plus the corner instants, and the plan's cycle is the
    program's length over its feed plus the filter delay (one block's ramps: eq 5)."""
    counts = []
    check = _fir_verify.RoundChecks.samples_check

    def counted(self, certify=True):
        out = check(self, certify)
        counts.append(self.samples)
        return out

    monkeypatch.setattr(_fir_verify.RoundChecks, "samples_check", counted)
    prog = parse_gcode("G21 G90\nG1 X10 Y0 F0.001\nG1 X10 Y10\nG2 X20 Y10 I5 J0\nM2\n")
    plan = plan_fir(prog.blocks, np.asarray(prog.block_feeds), tuple(DELAYS), 0.05)
    length = float(np.sum(prog.blocks.lengths))
    pieces = PulseTable.from_path(prog.blocks).block.size
    per_piece = STEADY_SAMPLES + float(DELAYS.sum()) / 1e-3 + 4
    assert counts and max(counts) <= pieces * per_piece + prog.blocks.n_blocks
    feed = 0.001 / 60.0  # [mm/s]
    assert float(plan.cycle_time) >= length / feed
    assert float(plan.cycle_time) <= length / feed * (1 + 1e-6) + 3 * float(DELAYS.sum())
