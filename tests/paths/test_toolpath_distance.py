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


@pytest.mark.parametrize("seed, spread", [(0, 0.05), (1, 0.05), (2, 0.05), (3, 0.05), (4, 0.6), (5, 0.6)])
def test_distance_to_planar_circles_and_spirals_is_the_least_over_the_arc(seed, spread):
    """Planar arcs of less than a turn, circles and spirals (end radius within 5 % of the start's,
    as the reader's spiral arcs, and within 60 %), CW and CCW, from random points within half a
    radius of the arc, near its centre and beyond it, off its plane: ``ToolPath.distance`` equals
    the least distance over the arc written here from its definition (angle ``phi`` from the start
    about the normal, radius linear in ``phi``), found on 20,001 angles and refined by a bounded
    scalar search. Near a spiral's centre the projection angle and the ends missed inner minima
    (1.9 um at 7.1 mm) before the kernel scanned the sweep there; most points project outside the
    sweep, where the kernel takes the ends alone when its stationary band misses the sweep
    (``OUTSIDE_BAND``)."""
    from scipy.optimize import minimize_scalar

    rng = np.random.default_rng(seed)
    for _ in range(6):
        c = rng.normal(size=3) * 5.0
        r0 = rng.uniform(0.5, 10.0)
        r1 = r0 * (1.0 + rng.choice([0.0, 1.0]) * rng.uniform(-spread, spread))
        sw = rng.uniform(0.1, 2 * np.pi - 0.1)
        n = np.array([0.0, 0.0, rng.choice([-1.0, 1.0])])
        e1 = np.array([np.cos(t := rng.uniform(0, 2 * np.pi)), np.sin(t), 0.0])
        e2 = np.cross(n, e1)

        def point(phi):
            r = r0 + (r1 - r0) * phi / sw
            return c + np.asarray(r)[..., None] * (np.cos(phi)[..., None] * e1 + np.sin(phi)[..., None] * e2)

        tp = ToolPath(point(np.array(0.0)), [point(np.array(sw))], [c], [n], [sw])
        ang = rng.uniform(0.0, 2 * np.pi, 150)
        rad = r0 * np.where(rng.random(150) < 0.3, rng.uniform(0.0, 0.1, 150), rng.uniform(0.5, 1.5, 150))
        q = c + rad[:, None] * (np.cos(ang)[:, None] * e1 + np.sin(ang)[:, None] * e2) + np.outer(rng.normal(0, 0.2 * r0, 150), n)
        grid = np.linspace(0.0, sw, 20001)
        got = tp.distance(q)
        for i in range(len(q)):
            d = np.linalg.norm(point(grid) - q[i], axis=1)
            k = int(np.argmin(d))
            lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, grid.size - 1)]
            best = minimize_scalar(lambda p: np.linalg.norm(point(np.array(p)) - q[i]), bounds=(lo, hi),
                                   method="bounded", options={"xatol": 1e-12})
            true = min(float(best.fun), float(d[0]), float(d[-1]))
            assert abs(got[i] - true) <= 1e-9 * max(1.0, true)
