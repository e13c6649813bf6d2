"""``ToolPath.arc_chord_turns`` (the arcs as small turns for the FIR look-ahead) against the chords of
``to_polyline``, the block tangents, and arc lengths written in closed form here."""

import numpy as np
import pytest

from research.interpolators._fir_lookahead import _arc_turns
from research.paths.toolpath import ToolPath


def wavy_arcs(n: int, seed: int) -> ToolPath:
    """``n`` half-turn arcs of random radius (0.4-2 mm) alternating G2/G3 along x, each followed by a
    short line: the pattern of adaptive clearing. The i-th arc: centre ``(x_i + r_i, 0)``, start
    ``(x_i, 0)``, end ``(x_i + 2 r_i, 0)``, sweep pi, so its length is ``pi r_i`` exactly."""
    rng = np.random.default_rng(seed)
    r = rng.uniform(0.4, 2.0, n)
    ends, centers, normals, sweeps, x = [], [], [], [], 0.0
    for i in range(n):
        ends.append([x + 2 * r[i], 0.0])
        centers.append([x + r[i], 0.0])
        normals.append([0.0, 0.0, 1.0 if i % 2 else -1.0])
        sweeps.append(np.pi)
        x += 2 * r[i]
        ends.append([x + 0.3, 0.0])
        centers.append([np.nan, np.nan])
        normals.append([0.0, 0.0, 0.0])
        sweeps.append(0.0)
        x += 0.3
    return ToolPath([0.0, 0.0], ends, centers, normals, sweeps), r


@pytest.mark.parametrize("tol", [1e-3, 5e-4, 0.2])  # 0.2 mm: arcs of one chord
def test_chord_turns_are_the_chords_turns_and_add_up_to_the_arcs_turning(tol):
    """Per arc, ``n + 1`` turns: the first chord's direction less the start tangent at ``1 / 4n``
    of the arc, the direction changes of ``to_polyline``'s chords (unit directions differenced
    here) at ``j / n``, and the end tangent less the last chord's direction at ``1 - 1 / 4n``;
    they add up to the arc's whole turning ``t_out - t_in`` (``ToolPath.tangents``)."""
    tp, _ = wavy_arcs(40, 1)
    block, fraction, du = tp.arc_chord_turns(tol)
    chords, owner = tp.to_polyline(tol)
    u = np.diff(chords.points, axis=0)
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    t_in, t_out = tp.tangents()
    arcs = np.flatnonzero(tp.is_arc)
    n = np.bincount(owner, minlength=tp.n_blocks)[arcs]
    np.testing.assert_array_equal(block, np.repeat(arcs, n + 1))
    first = np.searchsorted(owner, arcs)  # the arc's first chord
    for k, a in enumerate(arcs):
        rows = np.flatnonzero(block == a)
        c = first[k] + np.arange(n[k])
        want = np.vstack([u[c[0]] - t_in[a], u[c[1:]] - u[c[:-1]], t_out[a] - u[c[-1]]])
        np.testing.assert_allclose(du[rows], want, rtol=0, atol=1e-14)
        np.testing.assert_allclose(du[rows].sum(axis=0), t_out[a] - t_in[a], rtol=0, atol=1e-14)
        j = np.arange(n[k] + 1.0)
        np.testing.assert_array_equal(fraction[rows], np.where(j == 0, 0.25 / n[k], np.where(j == n[k], 1 - 0.25 / n[k], j / n[k])))


def test_look_ahead_turns_sit_at_their_exact_arc_length():
    """2,000 arcs: the look-ahead's arc turns lie at ``sum of earlier lengths + (j / n) pi r``,
    written here from the closed-form arc lengths. A running sum of chord lengths (what the
    polyline gives) falls behind by ``~ L dphi^2 / 24`` per arc: here 0.21 mm by the end (3.5 mm
    on the 101,262-block program of ``benchmarks/bench_adaptive.py``, against windows of 3.6 mm)."""
    tp, r = wavy_arcs(2000, 2)
    s, du = _arc_turns(tp, 0.05)
    lengths = np.empty(2 * r.size)
    lengths[0::2], lengths[1::2] = np.pi * r, 0.3
    start = np.concatenate([[0.0], np.cumsum(lengths)[:-1]])
    block, fraction, _ = tp.arc_chord_turns(1e-4)  # the sagitta _arc_turns uses at eps >= 10 um
    want = start[block] + fraction * lengths[block]
    np.testing.assert_allclose(s, want, rtol=0, atol=1e-9 * lengths.sum())
    chords, owner = tp.to_polyline(1e-4)
    inner = np.flatnonzero(owner[1:] == owner[:-1])
    drift = want[-2] - chords.arc_length[inner[-1] + 1]  # the last arc's last chord vertex, both ways
    assert drift > 0.1  # [mm]: what the chord sum would have misplaced, 1e4 times the tolerance above
