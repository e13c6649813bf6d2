"""Prévost 2012 §2.2 decomposition of the execution error: ``e1`` interpolation error (CAM path ->
position setpoint), ``e2`` feed-drive error (setpoint -> actual), ``eT`` total (CAM path -> actual);
each a contour error, signed on planar paths (positive to the left of travel), so that the algebraic
sum ``e1 + e2`` approximates ``eT`` (Prévost §4.1, Fig 5)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from research.contour._exact import check_same_grid, contour_error
from research.errors import ParameterError
from research.trajectory import Trajectory


@dataclass(frozen=True)
class ExecutionErrors:
    """Per-sample execution errors [mm], ``(N,)`` each (signed on planar paths, else distances).

    Attributes:
        t: sample times [s].
        e1: setpoint sample -> CAM path (interpolation error).
        e2: actual sample -> curve traced by the setpoint (feed-drive error).
        eT: actual sample -> CAM path (total error).
    """

    t: np.ndarray
    e1: np.ndarray
    e2: np.ndarray
    eT: np.ndarray

    def max_abs(self) -> dict[str, float]:
        """``{"e1": ..., "e2": ..., "eT": ...}`` largest magnitudes [mm]."""
        return {k: float(np.max(np.abs(getattr(self, k)))) for k in ("e1", "e2", "eT")}


def execution_errors(cam_path, setpoint: Trajectory, actual) -> ExecutionErrors:
    """Prévost's e1, e2, eT for a setpoint and the actual motion on the same time grid.

    Args:
        cam_path: the CAM path (Polyline, BSplinePath, or (M, d) points) [mm].
        setpoint: the position setpoint (interpolator output or compensated setpoint).
        actual: the actual motion (DriveResponse, Trajectory or (t, positions)) on the setpoint's grid.
    Raises:
        ParameterError: different lengths or time grids, or a setpoint that is not a Trajectory.
    """
    if not isinstance(setpoint, Trajectory):
        raise ParameterError(f"setpoint must be a Trajectory, got {type(setpoint).__name__}")
    t, R, P = check_same_grid(setpoint, actual)
    c1, c2, cT = contour_error(cam_path, R), contour_error(setpoint, P), contour_error(cam_path, P)
    pick = (lambda c: c.signed) if R.shape[1] == 2 else (lambda c: c.distance)
    return ExecutionErrors(t, pick(c1), pick(c2), pick(cT))
