"""Seeded random 2-D test paths shared by the FIR tests."""

import numpy as np

from research.paths import Polyline


def turning_path(seed: int, n: int, lengths: tuple[float, float], max_turn_deg: float) -> Polyline:
    """Seeded 2-D polyline from the origin: ``n`` blocks of uniform length in ``lengths`` [mm], each
    turning by a uniform angle in ``+-max_turn_deg`` [deg] from the previous heading."""
    rng = np.random.default_rng(seed)
    heading = np.cumsum(rng.uniform(-np.radians(max_turn_deg), np.radians(max_turn_deg), n))
    steps = rng.uniform(*lengths, n)[:, None] * np.column_stack([np.cos(heading), np.sin(heading)])
    return Polyline(np.vstack([[0.0, 0.0], np.cumsum(steps, axis=0)]))
