"""Synthetic drive logs: a drive model run on a reference, then measured by an encoder (seeded)."""

from __future__ import annotations

import numpy as np

from research.drives import Encoder, measure, simulate
from research.errors import DriveLogError
from research.identification._log import DriveLog
from research.trajectory import Trajectory


def synthetic_log(
    drive,
    reference: Trajectory,
    *,
    encoder: Encoder | None = None,
    seed: int = 0,
    source: str = "synthetic",
) -> DriveLog:
    """Simulate ``drive`` on a one-axis ``reference`` and log ``(t, x_r, x)`` as a real CNC would.

    Args:
        drive: any model :func:`research.drives.simulate` accepts (``ClosedLoopModel``, ``PPICascade``,
            ``PIDController``); Coulomb friction uses the exact sign of eq 6.2.
        reference: one-axis reference ``Trajectory`` (e.g. :meth:`ExcitationProgram.trajectory`) [mm].
        encoder: measurement of the actual position (Gaussian noise, then quantization, see
            :func:`research.drives.measure`); ``None`` logs the exact simulated position.
        seed: seed of the encoder noise.
        source: label used in error messages and reports.
    Returns:
        :class:`DriveLog` [s, mm]; the reference column is the commanded position itself (a CNC logs its
        interpolator output exactly).
    Raises:
        DriveLogError: ``reference`` has more than one axis (a drive log holds one; pass one axis, e.g.
            ``Trajectory.from_positions(t, traj.q[:, [k]], axes=("x",))``).
    """
    if reference.n_axes != 1:
        raise DriveLogError(f"{source}: synthetic_log logs one axis but the reference has {reference.n_axes} "
                            f"axes {tuple(reference.axes)}; pass a one-axis reference (one DriveLog per axis)")
    resp = simulate(drive, reference)
    x = np.asarray(resp.position[:, 0], dtype=np.float64)
    if encoder is not None:
        x = np.asarray(measure(encoder, x, int(seed)), dtype=np.float64)
    units = {"t": "s", "reference": "mm", "actual": "mm"}
    return DriveLog(
        t=np.asarray(reference.t, dtype=np.float64), reference=np.asarray(reference.q[:, 0], dtype=np.float64),
        actual=x, source=source, units=units,
    )
