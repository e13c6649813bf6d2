"""Reductions of the run figure for long programs (``research.experiments.run_figure``), against
direct computations on the full series."""

import numpy as np

from research.experiments.run_figure import _envelope, _near


def test_envelope_keeps_every_stretch_extremes_and_ends():
    """M4 (first, last, min, max of each of ``bins`` equal-count stretches): on random walks of
    several lengths, the kept samples are samples of the series in time order, at most ``4 bins``,
    and each stretch's smallest and largest values and its first and last samples are among them
    (found here by a loop over the stretches); short series come back whole."""
    rng = np.random.default_rng(0)
    for n, bins in ((1000, 300), (10_000, 37), (123_457, 1500)):
        t = np.arange(n) * 1e-3
        y = np.cumsum(rng.normal(size=n))
        tk, yk = _envelope(t, y, bins)
        if n <= 4 * bins:
            assert tk is t and yk is y
            continue
        idx = np.rint(tk / 1e-3).astype(int)
        assert np.all(np.diff(idx) > 0) and yk.size <= 4 * bins
        np.testing.assert_array_equal(yk, y[idx])
        w = -(-n // bins)
        kept = set(idx.tolist())
        for b in range(bins):
            s = y[b * w: (b + 1) * w]
            if not s.size:
                continue
            assert b * w in kept and min((b + 1) * w, n) - 1 in kept
            assert s.min() in yk[(idx >= b * w) & (idx < (b + 1) * w)]
            assert s.max() in yk[(idx >= b * w) & (idx < (b + 1) * w)]


def test_near_keeps_the_samples_in_the_zoom_and_their_neighbours():
    """The samples of a circle traversed twice that fall in a box, with one neighbour each side of
    every run, runs separated by a NaN row: every sample in the box is kept, each kept sample is in
    the box or next to one that is, and the three visits (start, after one turn, end) are three runs
    (two NaN rows between)."""
    s = np.linspace(0.0, 4 * np.pi, 4001)
    q = np.stack([np.cos(s), np.sin(s), 0.01 * s], axis=1)
    centre, r = np.array([1.0, 0.0, 0.0]), 0.1
    out = _near(q, centre, r)
    nan = np.isnan(out[:, 0])
    assert nan.sum() == 2 and not nan[0] and not nan[-1]
    inside = np.all(np.abs(q[:, :2] - centre[:2]) <= r, axis=1)
    kept = {tuple(p) for p in out[~nan]}
    assert all(tuple(p) in kept for p in q[inside])
    near = inside.copy()
    near[:-1] |= inside[1:]
    near[1:] |= inside[:-1]
    assert kept == {tuple(p) for p in q[near]}
    assert _near(q, np.array([5.0, 5.0, 0.0]), r).shape == (0, 3)
