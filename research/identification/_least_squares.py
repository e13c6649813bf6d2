"""Unconstrained least squares, thesis eq 6.10-6.12."""

from __future__ import annotations

import time

import numpy as np

from research.identification._log import DriveLog
from research.identification._regression import (
    DEFAULT_OPTIONS,
    Regression,
    RegressionOptions,
    build_regression,
)
from research.identification._result import IdentifiedDrive


def least_squares(data: DriveLog | Regression, options: RegressionOptions = DEFAULT_OPTIONS) -> IdentifiedDrive:
    """Eq 6.12 ``theta = (Phi^T Phi)^-1 Phi^T Y`` (solved by an SVD-based ``lstsq`` on the column-scaled
    regressor, not by forming the normal equations), de-normalized by eq 6.8.

    Args:
        data: a :class:`DriveLog` (the regression is built with ``options``) or a ready :class:`Regression`.
        options: :class:`RegressionOptions` used when ``data`` is a log.
    Returns:
        :class:`IdentifiedDrive` with ``method="ls"``; its poles may be unstable (no constraint, §6.4).
    Raises:
        DriveLogError: log too short or regressor rank deficient (from :func:`build_regression`, with the
            condition number), so no garbage parameters are returned.
    """
    reg = data if isinstance(data, Regression) else build_regression(data, options)
    t0 = time.perf_counter()
    sol, *_ = np.linalg.lstsq(reg.Phi / reg.column_scale, reg.Y, rcond=None)
    theta = sol / reg.column_scale
    wall = time.perf_counter() - t0
    return IdentifiedDrive.from_theta(
        theta, method="ls", loss=reg.loss(theta), loss_kind="equation error, eq 6.10", wall_time_s=wall,
        iterations=0, source=reg.source, info={"condition_number": reg.condition},
    )
