"""The mirror's path check on a thinned grid (``_fir_mirror_check``): the global period is set by
the profile's largest acceleration, and the profile's pieces where the distance to the path bends
less take longer strides with the same margin (``local_strides``).

References: the span overlay is checked against NumPy set computations; the strides against the
exact acceleration of the profile (its pieces are cubic for two filters, so ``|a|`` is largest
at a piece's ends) and, on arcs, the curvature of the distance from the concave side, ``|v|^2 /
rho`` (``d = R - |p - c|``); the planned trajectory against the programmed path by
``ToolPath.distance`` on a dense grid. Nothing is compared with the planner's earlier output."""

import numpy as np
import pytest

from research.interpolators import plan_fir, plan_fir_mirror
from research.interpolators._fir_certify import derivative_bound
from research.interpolators._fir_mirror_check import SAMPLE_MARGIN, local_strides, sample_period
from research.interpolators._fir_verify_kernels import overlay_spans, thinned_runs
from research.paths import Polyline
from research.paths.gcode import parse_gcode
from research.paths.toolpath import ToolPath

DELAYS = np.array([0.06, 0.03])
CHECK = 1e-3


def _disjoint(rng, n, hi):
    """``n`` sorted, disjoint integer intervals ``[lo, hi]`` within ``[0, hi]``."""
    cuts = np.sort(rng.choice(hi, 2 * n, replace=False))
    return cuts[0::2].astype(np.int64), cuts[1::2].astype(np.int64)


@pytest.mark.parametrize("seed", range(20))
def test_overlaid_spans_keep_the_steady_ones_and_cut_the_local_ones_around_them(seed):
    """Random steady spans over random local spans: the overlay is sorted and disjoint, holds every
    steady span as it was, covers the same indices as the two together, and each of its other
    spans lies inside one local span, with its stride, outside every steady span."""
    rng = np.random.default_rng(seed)
    s_first, s_last = _disjoint(rng, int(rng.integers(0, 6)), 500)
    s_stride = rng.integers(1, 30, s_first.size).astype(np.int64)
    c_first, c_last = _disjoint(rng, int(rng.integers(1, 12)), 500)
    c_stride = rng.integers(1, 9, c_first.size).astype(np.int64)
    f, la, st = overlay_spans(s_first, s_last, s_stride, c_first, c_last, c_stride)
    assert np.all(f <= la) and np.all(f[1:] > la[:-1])
    steady = {(int(a), int(b), int(s)) for a, b, s in zip(s_first, s_last, s_stride)}
    got = {(int(a), int(b), int(s)) for a, b, s in zip(f, la, st)}
    assert steady <= got

    def covered(first, last):
        return set().union(*(range(a, b + 1) for a, b in zip(first, last))) if first.size else set()

    assert covered(f, la) == covered(s_first, s_last) | covered(c_first, c_last)
    in_steady = covered(s_first, s_last)
    for a, b, s in got - steady:
        c = np.flatnonzero((c_first <= a) & (b <= c_last))
        assert c.size == 1 and s == c_stride[c[0]]
        assert not set(range(a, b + 1)) & in_steady


def _interval_maxima(pos, kept_times, order):
    """Largest ``|q^(order)|`` over each interval between consecutive ``kept_times``, from the
    values at its ends and at the profile's breaks inside it (both sides): exact for ``|a|`` of
    cubic pieces (linear in each piece), the values at those points for ``|v|``."""
    c = np.asarray(pos.coeffs)
    breaks = np.asarray(pos.breaks)

    def value(piece, tau):
        m = np.arange(c.shape[1])
        fall = np.ones(m.size)
        for j in range(order):
            fall = fall * (m - j)
        w = np.where(m >= order, fall, 0.0)[None, :] * tau[:, None] ** np.maximum(m - order, 0)[None, :]
        return np.linalg.norm(np.einsum("km,kma->ka", w, c[piece]), axis=1)

    P = c.shape[0]
    at = np.clip(np.searchsorted(breaks, kept_times, side="right") - 1, 0, P - 1)
    v_kept = value(at, kept_times - breaks[at])
    inner = np.arange(1, P)
    v_break = np.maximum(value(inner - 1, breaks[inner] - breaks[inner - 1]), value(inner, np.zeros(inner.size)))
    times = np.concatenate([kept_times, breaks[inner]])
    vals = np.concatenate([v_kept, v_break])
    order_ = np.argsort(times, kind="stable")
    times, vals = times[order_], vals[order_]
    out = np.empty(kept_times.size - 1)
    lo = np.searchsorted(times, kept_times[:-1], side="left")
    hi = np.searchsorted(times, kept_times[1:], side="right")
    for i in range(out.size):
        out[i] = vals[lo[i]:hi[i]].max()
    return out


def _kept_times(pos, period, spans):
    t0, t1 = float(pos.breaks[0]), float(pos.breaks[-1])
    n = int(np.ceil((t1 - t0) / period)) + 1
    f, c, s = thinned_runs(np.zeros(1, np.int64), np.array([n - 1], np.int64), *spans)
    idx = np.concatenate([a + np.arange(k) * st for a, k, st in zip(f, c, s)])
    return np.clip(t0 + idx * period, t0, t1)


def _strides_of(plan, tp, tol):
    pos = plan.position.numpy_evaluator()
    accel = derivative_bound(pos, 2)
    period, margin = sample_period(accel, CHECK, float(np.min(tol)))
    spans = local_strides(pos, accel, tp, np.asarray(plan.start_times), np.asarray(plan.pulse_times),
                          float(DELAYS.sum()), tol, CHECK, period, margin)
    return pos, period, margin, spans


def test_local_strides_hold_the_margin_between_samples_under_the_exact_acceleration():
    """A 60-chord random polyline of long lines and short zigzags at eps 2.54 um (the inch
    quantum of ``G64 P0.0001``), F 150 mm/s: the check's global period is ``check_period / k``
    with ``k`` > 1; the local strides thin the grid (fewer samples than the dense grid), and between every
    two consecutive samples the exact ``|a|_max h^2 / 8`` is within the margin."""
    rng = np.random.default_rng(3)
    steps = rng.normal(size=(60, 2)) * np.where(rng.random(60) < 0.3, 8.0, 0.3)[:, None]
    path = Polyline(np.cumsum(np.vstack([[0.0, 0.0], steps]), axis=0))
    tol = np.full(path.n_segments, 2.54e-3)
    plan = plan_fir(path, 150.0, DELAYS, tol)
    pos, period, margin, spans = _strides_of(plan, ToolPath.from_polyline(path), tol)
    assert round(CHECK / period) > 1 and spans is not None and np.any(spans[2] > 1)
    assert spans[0].size <= pos.breaks.size - 1  # one span per profile piece at most, whatever the cycle's length
    kept = _kept_times(pos, period, spans)
    n_dense = int(np.ceil((pos.breaks[-1] - pos.breaks[0]) / period)) + 1
    assert kept.size < 0.8 * n_dense
    assert np.c_[pos.coeffs].shape[1] <= 4  # cubic pieces: |a| is linear in each
    a_max = _interval_maxima(pos, kept, 2)
    assert np.all(a_max * np.diff(kept) ** 2 / 8.0 <= margin * (1 + 1e-9))


def test_local_strides_near_arcs_keep_the_concave_distance_within_the_margin():
    """Tangent half circles of R 2 mm (a serpentine of ``G2`` / ``G3``) at eps 2.54 um, F 100
    mm/s: every block is an arc, so from the concave side the distance bends by ``|a| + |v|^2 /
    rho``, ``rho = R - (1 + 2 SAMPLE_MARGIN) eps``; between every two consecutive samples that
    times ``h^2 / 8`` is within the margin (``|a|`` exact, ``|v|`` at the interval's ends and the
    breaks inside it)."""
    R = 2.0
    lines = ["G21 G90 G17 G64 P0.00254", "G1 X0 Y0 F6000"]
    for i in range(8):
        x = 2 * R * (i + 1)
        lines.append(f"{'G2' if i % 2 == 0 else 'G3'} X{x:g} Y0 I{R:g} J0")
    prog = parse_gcode("\n".join(lines + ["M2"]))
    tp = prog.blocks
    assert np.all(tp.is_arc)
    tol = np.full(tp.n_blocks, 2.54e-3)
    plan = plan_fir(tp, 100.0, DELAYS, tol)
    pos, period, margin, spans = _strides_of(plan, tp, tol)
    assert spans is not None
    kept = _kept_times(pos, period, spans)
    assert kept.size < 0.8 * (int(np.ceil((pos.breaks[-1] - pos.breaks[0]) / period)) + 1)
    rho = R - (1 + 2 * SAMPLE_MARGIN) * 2.54e-3
    bend = _interval_maxima(pos, kept, 2) + _interval_maxima(pos, kept, 1) ** 2 / rho
    assert np.all(bend * np.diff(kept) ** 2 / 8.0 <= margin * (1 + 1e-6))


G64_INCH = """G20 G90 G17
G64 P0.0001
G0 X0 Y0
G1 X0.5 Y0 F1000
G1 X0.502 Y0.002
G1 X0.504 Y0.002
G1 X0.506 Y0.004
G3 X0.606 Y0.104 I0 J0.1
G1 X0.606 Y0.4
G2 X0.706 Y0.5 I0.1 J0
G1 X1.2 Y0.5
G1 X1.2 Y0.502
G1 X0.7 Y0.502
M2
"""


def test_the_mirror_at_the_inch_quantum_keeps_eps_on_a_dense_grid():
    """A program in inches at ``G64 P0.0001`` (eps 2.54 um, F 1000 in/min): 0.05 mm steps, two
    fillets of R 2.54 mm and a 0.05 mm step-over. The mirror's plan, checked on the thinned grid,
    keeps eps on the programmed path sampled every 20 us (denser than the check's own grid) and
    at every corner, and is no slower than ``plan_fir``'s."""
    prog = parse_gcode(G64_INCH)
    tol = prog.block_tolerance
    assert np.allclose(tol[np.isfinite(tol)], 2.54e-3)
    tol = np.where(np.isfinite(tol), tol, 2.54e-3)
    m = plan_fir_mirror(prog.blocks, prog.block_feeds, DELAYS, tol)
    q = np.asarray(m.plan.trajectory(2e-5).q)
    assert np.max(prog.blocks.distance(q)) <= 2.54e-3 * (1 + 1e-6)
    assert np.max(np.asarray(m.plan.corner_errors)) <= 2.54e-3 * (1 + 1e-6)
    assert m.cycle_time <= m.plain_cycle_time * (1 + 1e-12)


@pytest.mark.parametrize("share", [0.3, 1.5])
def test_keys_only_finds_the_same_broken_keys_and_the_same_clean_deviation(share):
    """``path_deviations(..., keys_only=True)`` (the mirror's check) against the full check on a
    ``plan_fir`` plan of a random 80-chord curve with arcs, checked at ``share`` of its tolerance:
    at 0.3 some vertices and blocks break it and ``keys_only`` names the same ones (its values no
    larger); at 1.5 none does and every value is the same."""
    from research.interpolators._fir_verify import path_deviations
    rng = np.random.default_rng(11)
    ang = np.cumsum(rng.normal(0.0, 0.25, 80))
    pts = np.cumsum(np.c_[np.cos(ang), np.sin(ang)] * rng.uniform(0.2, 2.0, 80)[:, None], axis=0)
    tp = ToolPath.from_polyline(Polyline(np.vstack([[0.0, 0.0], pts])))
    tol = np.full(tp.n_blocks, 0.02)
    plan = plan_fir(tp, 120.0, DELAYS, tol)
    pos = plan.position.numpy_evaluator()
    args = (pos, tp, np.asarray(plan.start_times), np.asarray(plan.corner_times), float(DELAYS.sum()), share * tol, 2e-4)
    full = path_deviations(*args)
    keys = path_deviations(*args, keys_only=True)
    assert set(keys[1]) == set(full[1]) and set(keys[2]) == set(full[2])
    if share < 1:
        assert full[1] or full[2]
        assert all(keys[1][k] <= full[1][k] for k in keys[1]) and keys[0] <= full[0]
    else:
        assert not full[1] and not full[2] and keys[0] == full[0]
