"""The discrete reference implementation of an FIR plan: sampled pulses through ``np.convolve``."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from research.errors import ParameterError, PathError
from research.paths.polyline import Polyline

if TYPE_CHECKING:
    from research.interpolators.fir import FIRPlan


def fir_by_convolution(plan: "FIRPlan", path: Polyline, sample_period: float) -> tuple[np.ndarray, np.ndarray]:
    """Straightforward discrete implementation of the same schedule, as a reference (lines only).

    The unfiltered pulse train is sampled as exact cell averages over ``[i Ts, (i+1) Ts)``; each
    filter is an ``np.convolve`` with the ``m + 1`` taps ``[1/2, 1, ..., 1, 1/2] / m``,
    ``m = T_i / Ts`` (the moving average acting on cell averages: exact for cell-wise constant
    input, delay ``T_i / 2``); positions are the cumulative sum. Accurate to O(Ts^2) at the grid
    points when every ``T_i`` is a multiple of ``Ts``; costs O(samples * sum T_i / Ts).

    Returns:
        ``(t, q)``: grid times [s] and positions ``(N, d)`` [mm].
    """
    if not isinstance(path, Polyline):
        raise PathError("fir_by_convolution takes a Polyline (G01 blocks only)")
    taps = np.asarray(plan.delays) / sample_period
    if not np.allclose(taps, np.round(taps), rtol=0, atol=1e-6):
        raise ParameterError(f"fir_by_convolution needs delays that are multiples of Ts = {sample_period} s")
    taps = np.round(taps).astype(int)
    starts = np.asarray(plan.start_times)
    ends = starts + np.asarray(plan.pulse_times)
    knots = np.stack([starts, ends], axis=1).reshape(-1)
    knot_pos = np.repeat(path.points, 2, axis=0)[1:-1]  # P0, P1, P1, P2, ..., PM
    n = int(np.ceil(ends[-1] / sample_period)) + 1
    grid = np.arange(n + 1) * sample_period
    unfiltered = np.column_stack([np.interp(grid, knots, knot_pos[:, k]) for k in range(path.dim)])
    velocity = np.diff(unfiltered, axis=0) / sample_period  # cell averages
    for m in taps:
        kernel = np.full(m + 1, 1.0 / m)
        kernel[[0, -1]] *= 0.5
        velocity = np.column_stack([np.convolve(velocity[:, k], kernel) for k in range(path.dim)])
    q = path.points[0] + np.vstack([np.zeros((1, path.dim)), np.cumsum(velocity, axis=0) * sample_period])
    return np.arange(q.shape[0]) * sample_period, q
