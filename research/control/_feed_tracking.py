"""Thesis ch 3, Fig 3.13: axis tracking errors of the optimized feed against constant feeds, simulated
through the SISO sliding-mode drives with an amplifier limit.

Thesis §3.6: "the drive system is controlled by robust sliding mode controllers with feed-forward
friction compensation [35]"; "If the user imposed feed (150 [mm/sec]) had used, the drives would have
become excessively saturated ... A relatively conservative feed of 40 [mm/sec] was tested, leading to the
violation of drive limits (Figure 3.13), and the tracking errors were amplified at the saturation
regions. However, when the feed is optimized ... the drive limits were never violated."

Model (choices stated):

- Drives and controller: the ch 5 machine (Table 5.1 = Table 4.1, the same 5-axis machine) under the
  SISO SMC of Table 5.2 with the Coulomb friction identified from Fig 5.7
  (:func:`research.control.identify_coulomb`), at the 0.1 ms control period of
  :data:`research.control.CONTROL_PERIOD` (see :mod:`research.control._study`). The loop's adaptive
  ``d_hat`` is the friction compensation.
- Saturation: the thesis prints no amplifier limit. The Table 3.1 limits are what the optimization
  keeps the drives within so that they stay "in a linear control region", so the amplifier limit of
  axis i is read as the voltage that holds the Table 3.1 acceleration at the Table 3.1 velocity against
  the friction: ``u_max,i = m_i A_i + c_i V_i + d_c,i`` (eq 4.11). A command beyond the acceleration
  limit then saturates; the jerk limit has no actuator counterpart.
- The reference is the feed schedule's axis trajectory evaluated at the control period
  (:func:`research.control.joint_reference`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from research.control._gains import AxisSMC, check_axis_gains, table_5_2
from research.control._loop import simulate_closed_loop
from research.control._plant import FiveAxisPlant
from research.control._reference import joint_reference
from research.control._study import CONTROL_PERIOD, LOG_PERIOD
from research.errors import ParameterError
from research.limits import AxisLimits
from research.trajectory import Trajectory


def amplifier_limits(plant: FiveAxisPlant, limits: AxisLimits) -> np.ndarray:
    """``u_max,i = m_i A_i + c_i V_i + d_c,i`` [V] (module docstring) from the plant (eq 4.11, with its
    Coulomb friction) and the axis velocity / acceleration limits (Table 3.1 in package units)."""
    V, A = np.asarray(limits.velocity, dtype=np.float64), np.asarray(limits.acceleration, dtype=np.float64)
    if V.shape != (5,) or A.shape != (5,):
        raise ParameterError(f"limits must hold 5 axes (x, y, z, a, c), got velocity {V.shape}, acceleration {A.shape}")
    return np.asarray(plant.m) * A + np.asarray(plant.c) * V + np.asarray(plant.coulomb)


@dataclass(frozen=True)
class FeedTracking:
    """One feed schedule through the drives, read every :data:`LOG_PERIOD`.

    Attributes:
        t: ``(M,)`` [s]; axis_error: ``(M, 5)`` ``q_ref - q`` [mm, rad]; u: ``(M, 5)`` [V];
        saturated: ``(M, 5)`` bool, the axis at its amplifier limit; u_max: ``(5,)`` [V];
        saturated_fraction: ``(5,)`` share of all control periods at the limit per axis;
        diverged: the loop was flagged (an axis error beyond the divergence limit); diverged_at: time [s]
        of the flag (``nan`` if none).
    """

    t: np.ndarray
    axis_error: np.ndarray
    u: np.ndarray
    saturated: np.ndarray
    u_max: np.ndarray
    saturated_fraction: np.ndarray
    diverged: bool
    diverged_at: float

    def max_error(self) -> np.ndarray:
        """``(5,)`` largest ``|q_ref - q|`` per axis [mm, rad] (up to the divergence flag, if any)."""
        return np.abs(self.axis_error).max(axis=0)


def feed_tracking(trajectory: Trajectory, plant: FiveAxisPlant, u_max, *, gains: AxisSMC | None = None,
                  T: float = CONTROL_PERIOD, divergence_limit: float = 10.0) -> FeedTracking:
    """Simulate ``trajectory`` (axes x, y, z, a, c) through the SISO SMC drives with amplifier limits.

    Args:
        trajectory: the axis motion of a feed schedule (e.g. ``optimize_feedrate(...).trajectory``).
        plant: drives with their Coulomb friction; u_max: ``(5,)`` or scalar amplifier limit [V]
        (e.g. :func:`amplifier_limits`); gains: SISO gains (default Table 5.2); T: control period [s];
        divergence_limit: axis error [mm or rad] beyond which the run is flagged diverged.
    Raises:
        UnstableGainsError: the gains are unstable at ``T``; ParameterError: bad axes or limits.
    """
    gains = table_5_2() if gains is None else gains
    check_axis_gains(gains, plant.m, plant.c, T)
    ref = joint_reference(trajectory, T)
    res = simulate_closed_loop(plant, ref, gains, u_max=u_max, divergence_limit=divergence_limit)
    u_lim = np.broadcast_to(np.asarray(u_max, dtype=np.float64), (5,))
    u_all = np.asarray(res.u)
    sat_all = np.abs(u_all) >= u_lim
    k = int(np.asarray(res.diverged_at))
    n = int(ref.t.shape[0])
    every = max(1, int(round(LOG_PERIOD / T)))
    stop = min(k, n)  # after the flag the state is frozen: keep the log up to it
    sl = slice(0, stop, every)
    e = (np.asarray(ref.q) - np.asarray(res.q))[sl]
    return FeedTracking(np.asarray(ref.t)[sl], e, u_all[sl], sat_all[sl], u_lim.copy(),
                        sat_all[:stop].mean(axis=0) if stop else np.zeros(5), bool(res.diverged),
                        float(np.asarray(ref.t)[k]) if k < n else float("nan"))
