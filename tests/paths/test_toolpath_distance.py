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
