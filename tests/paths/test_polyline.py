"""Polyline geometry and exact point-to-path distance."""

import numpy as np
import pytest

from research.paths import PATHS, Polyline, named_path


def brute_distance(path, q):
    a, b = path.points[:-1], path.points[1:]
    ab = b - a
    u = np.clip(np.einsum("nsd,sd->ns", q[:, None, :] - a[None], ab) / np.sum(ab * ab, axis=1), 0, 1)
    proj = a[None] + u[..., None] * ab[None]
    return np.min(np.linalg.norm(q[:, None, :] - proj, axis=2), axis=1)


def test_named_paths():
    assert set(PATHS) == {"corner90", "diamond", "zigzag", "sencer2015_fig4"}
    assert named_path("zigzag").points.shape == (11, 2)
    np.testing.assert_allclose(named_path("zigzag").points[:4], [[0, 0], [10, 5], [20, 0], [30, 5]])
    np.testing.assert_allclose(named_path("sencer2015_fig4").lengths, [2.5, 2.5])
    np.testing.assert_allclose(np.degrees(named_path("diamond").turning_angles), [90, 90, 90])


def test_turning_angles_accurate_near_0_and_180():
    tiny = 1e-9
    p = Polyline([[0, 0], [1, 0], [2, tiny], [0, tiny]])
    np.testing.assert_allclose(p.turning_angles, [tiny, np.pi - tiny], rtol=1e-6)


@pytest.mark.parametrize("dim", [2, 3])
def test_distance_exact_against_brute_force(dim):
    rng = np.random.default_rng(7)
    lengths = np.exp(rng.uniform(np.log(0.01), np.log(20), 400))
    dirs = rng.normal(size=(400, dim))
    pts = np.vstack([np.zeros(dim), np.cumsum(dirs / np.linalg.norm(dirs, axis=1)[:, None] * lengths[:, None], axis=0)])
    path = Polyline(pts)
    q = pts[rng.integers(0, 401, 300)] + rng.normal(scale=2.0, size=(300, dim))
    np.testing.assert_allclose(path.distance(q), brute_distance(path, q), atol=1e-12)
    d, seg, u = path.project(q)
    closest = path.points[seg] + u[:, None] * (path.points[seg + 1] - path.points[seg])
    np.testing.assert_allclose(np.linalg.norm(q - closest, axis=1), d, atol=1e-12)


@pytest.mark.parametrize("nearest", [1, 3, 8])
def test_distance_exact_with_few_or_many_candidates_per_query(monkeypatch, nearest):
    """``project`` takes the ``_NEAREST_CENTRES`` nearest sub-segment centres of each point in one
    query and a ball query where more lie within its search radius: exact either way (brute force
    over every segment). Here a fan of 40 short spokes out of one point (each query near the hub
    has dozens of centres within its radius) and a waterline-like stack of 0.2 mm-apart rings."""
    import research.paths.polyline as polyline

    monkeypatch.setattr(polyline, "_NEAREST_CENTRES", nearest)
    monkeypatch.setattr(polyline, "_CHUNK", 97)  # and in chunks (400 points: four and a remainder)
    rng = np.random.default_rng(3)
    ang = np.sort(rng.uniform(0.0, 2 * np.pi, 40))
    fan = np.concatenate([[[0.0, 0.0, 0.0], [np.cos(a), np.sin(a), 0.0]] for a in ang] + [[[0.0, 0.0, 0.0]]])
    s = np.linspace(0.0, 2 * np.pi, 400)
    rings = np.concatenate([np.stack([(5 + 0.01 * k) * np.cos(s), (5 + 0.01 * k) * np.sin(s), np.full(s.size, -0.2 * k)],
                                     axis=1) for k in range(4)])
    for pts, scale in ((fan, 0.3), (rings, 0.15)):
        path = Polyline(pts)
        q = pts[rng.integers(0, len(pts), 400)] + rng.normal(scale=scale, size=(400, 3))
        np.testing.assert_allclose(path.distance(q), brute_distance(path, q), atol=1e-12)


def test_one_dimensional_path():
    p = Polyline([[0.0], [10.0], [4.0]], axes=("x",))
    np.testing.assert_allclose(p.turning_angles, [np.pi])
    np.testing.assert_allclose(p.distance([[12.0], [5.0]]), [2.0, 0.0])
