"""Limit check of a (compensated) setpoint: axis velocity, acceleration, jerk and control effort.

Prévost 2012 §3: after compensation "the trajectory execution has to be checked in terms of velocity,
acceleration, jerk and current, in order to be sure that physical limits of the machine are
respected". Peaks are taken over the setpoint samples fed to the drive (v, a, j of the
:class:`~research.trajectory.Trajectory`) and over the simulated control signal.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from research.drives import DriveResponse
from research.errors import ParameterError
from research.limits import AxisLimits
from research.trajectory import Trajectory


@dataclass(frozen=True)
class LimitCheck:
    """Peaks of a setpoint and its control effort against limits.

    Attributes:
        axes: axis names.
        velocity, acceleration, jerk: ``(A,)`` peak ``|v|`` [mm/s], ``|a|`` [mm/s^2], ``|j|`` [mm/s^3].
        control: ``(A,)`` peak ``|u|`` [V] of the simulated control signal, ``None`` when the drive
            model has no control output (eq 6.3 closed-loop models).
        limits: the axis limits checked against.
        control_limit: ``(A,)`` bound on ``|u|`` [V] or ``None``.
        ratios: ``{"velocity": (A,), ...}`` peak / limit (above 1: violated), plus ``"control"``
            when both the control signal and its limit are known.
    """

    axes: tuple[str, ...]
    velocity: np.ndarray
    acceleration: np.ndarray
    jerk: np.ndarray
    control: np.ndarray | None
    limits: AxisLimits
    control_limit: np.ndarray | None
    ratios: dict

    @property
    def violations(self) -> list[str]:
        """One line per violated quantity and axis, e.g. ``"jerk on x: 6.1e5 > 5.8e5 (x1.05)"``."""
        units = {"velocity": "mm/s", "acceleration": "mm/s^2", "jerk": "mm/s^3", "control": "V"}
        out = []
        for name, ratio in self.ratios.items():
            peak = getattr(self, name)
            lim = self.control_limit if name == "control" else getattr(self.limits, name)
            for k, r in enumerate(np.atleast_1d(ratio)):
                if r > 1.0:
                    out.append(f"{name} on {self.axes[k]}: {peak[k]:.4g} > {lim[k]:.4g} {units[name]} (x{r:.3f})")
        return out

    @property
    def ok(self) -> bool:
        """True when no limit is exceeded."""
        return not self.violations

    def summary(self) -> str:
        """The violations joined, or ``"within limits"``."""
        return "; ".join(self.violations) or "within limits"


def check_setpoint(setpoint: Trajectory, response: DriveResponse | None, limits: AxisLimits,
                   control_limit=None) -> LimitCheck:
    """Check a setpoint's peak axis velocity, acceleration and jerk, and the control effort of its
    simulated response, against limits.

    Args:
        setpoint: the setpoint sent to the drives.
        response: its simulated response (for the control signal) or ``None``.
        limits: per-axis v/a/j limits [mm/s, mm/s^2, mm/s^3].
        control_limit: scalar or ``(A,)`` bound on ``|u|`` [V]; ignored (no ratio) when the model has
            no control output.
    Returns:
        :class:`LimitCheck`.
    Raises:
        ParameterError: axis-count mismatch or a control limit that is not > 0.
    """
    if not isinstance(limits, AxisLimits):
        raise ParameterError(f"limits must be an AxisLimits, got {type(limits).__name__}")
    A = setpoint.n_axes
    if limits.n_axes != A:
        raise ParameterError(f"limits are for {limits.n_axes} axes but the setpoint has {A} axes {setpoint.axes}")
    v, a, j = (np.max(np.abs(np.asarray(x)), axis=0) for x in (setpoint.v, setpoint.a, setpoint.j))
    ratios = limits.ratios(v, a, j)
    control = None
    if response is not None and response.control is not None:
        control = np.max(np.abs(np.asarray(response.control)), axis=0)
    cl = None
    if control_limit is not None:
        cl = np.broadcast_to(np.asarray(control_limit, dtype=np.float64), (A,)).copy()
        if not np.all(cl > 0):
            raise ParameterError(f"control_limit must be > 0 V on every axis, got {cl.tolist()}")
        if control is not None:
            ratios["control"] = control / cl
    return LimitCheck(setpoint.axes, v, a, j, control, limits, cl, ratios)
