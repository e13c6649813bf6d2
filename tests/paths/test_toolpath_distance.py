"""``ToolPath.distance_bound`` on lines (its compiled pass) against the distance to every segment."""

import numpy as np
import pytest

from research.paths import Polyline
from research.paths.toolpath import ToolPath


@pytest.mark.parametrize("dim", [2, 3])
def test_distance_bound_on_lines_is_the_distance_to_the_nearest_segment(dim):
    """Points near a random polyline: the bound is never below the true distance (projection on
    every segment, computed here) and equals it on all but a few crowded points."""
    rng = np.random.default_rng(dim)
    tp = ToolPath.from_polyline(Polyline(np.cumsum(rng.normal(size=(200, dim)), axis=0)))
    q = tp.starts[rng.integers(0, tp.n_blocks, 2000)] + rng.normal(scale=0.3, size=(2000, dim))
    got = tp.distance_bound(q, near=rng.integers(0, tp.n_blocks, 2000))
    a, ab = tp.starts[None, :, :], (tp.ends - tp.starts)[None, :, :]
    u = np.clip(np.sum((q[:, None, :] - a) * ab, axis=2) / np.sum(ab * ab, axis=2), 0.0, 1.0)
    true = np.min(np.linalg.norm(q[:, None, :] - (a + u[:, :, None] * ab), axis=2), axis=1)
    assert np.all(got >= true - 1e-12)
    assert np.mean(np.abs(got - true) <= 1e-12) > 0.99


def test_distance_in_chunks_is_the_distance_over_every_segment(monkeypatch):
    """``ToolPath.distance`` runs its queries in chunks (its candidate lists grow with the passes
    near a point: one contour run 8 times took 7.6 GB for 1.4 million points in one pass). With
    chunks of 7 points, on a contour run three times at 0.05 mm apart, it gives the distance to
    every segment computed here by brute force."""
    from research.paths import toolpath

    rng = np.random.default_rng(5)
    loop = np.cumsum(rng.normal(size=(60, 2)), axis=0)
    passes = np.vstack([np.column_stack([loop, np.full(len(loop), -0.05 * k)]) for k in range(3)])
    tp = ToolPath.from_polyline(Polyline(passes))
    q = tp.starts[rng.integers(0, tp.n_blocks, 500)] + rng.normal(scale=0.2, size=(500, 3))
    monkeypatch.setattr(toolpath, "_DISTANCE_CHUNK", 7)
    got = tp.distance(q)
    a, ab = tp.starts[None, :, :], (tp.ends - tp.starts)[None, :, :]
    u = np.clip(np.sum((q[:, None, :] - a) * ab, axis=2) / np.sum(ab * ab, axis=2), 0.0, 1.0)
    true = np.min(np.linalg.norm(q[:, None, :] - (a + u[:, :, None] * ab), axis=2), axis=1)
    np.testing.assert_allclose(got, true, rtol=0, atol=1e-12)
