"""Read-only float64 copies for the result records of :mod:`research.optimal` (immutable results)."""

from __future__ import annotations

import numpy as np


def frozen(x) -> np.ndarray:
    """``x`` as a new float64 array that cannot be written to."""
    x = np.array(x, dtype=np.float64)
    x.setflags(write=False)
    return x
