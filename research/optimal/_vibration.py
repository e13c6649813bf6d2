"""Structural modes in the time-optimal OCP: exact flow of a base-excited mode, residual vibration.

A mode on axis ``i`` (the beams of Sencer 2015 §4: 11.4 Hz on X, 6.8 Hz on Y) is the base-excited
oscillator of :mod:`research.drives` (``FlexibleMode``) and of the residual-vibration model of
:mod:`research.experiments.fir_model`::

    delta'' + 2 zeta wn delta' + wn^2 delta = -a_i(t)                                   (V1)

On an OCP interval the axis acceleration is linear, ``a_i(t) = a0 + j t`` (constant jerk), so (V1)
has the particular solution ``c0 + c1 t`` with ``c1 = -j / wn^2`` and
``c0 = (-a0 + 2 zeta j / wn) / wn^2``; the rest ``e = delta - c0 - c1 t`` is the free damped
oscillation, so with ``s = zeta wn``, ``wd = wn sqrt(1 - zeta^2)``::

    e(h)  = exp(-s h) [e0 cos(wd h) + (e0' + s e0) / wd sin(wd h)]                    (V2)
    e'(h) = exp(-s h) [e0' cos(wd h) - (wn^2 e0 + s e0') / wd sin(wd h)]

exact for any interval length ``h`` (no integration error, smooth in ``h``, so the free phase
durations of the OCP stay decision variables). Once the motion has stopped (``a = 0``) the mode
rings freely with the envelope ``|B| / wd`` of ``fir_model``::

    A = sqrt(delta^2 + ((delta' + s delta) / wd)^2)   [mm]                              (V3)

which is the *residual vibration* of a motion: the OCP bounds it at the end (``A <= r``; ``r = 0``
imposes ``delta = delta' = 0``), and optionally bounds the in-motion deflection ``|delta| <= D``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from research.errors import ParameterError


@dataclass(frozen=True)
class StructuralMode:
    """A lightly damped structural mode driven by one axis' acceleration (eq V1).

    Attributes:
        axis: index of the exciting axis (0 = x, 1 = y, 2 = z).
        frequency_hz: natural frequency ``f`` [Hz], > 0.
        damping: damping ratio ``zeta`` [-], in (0, 1).
    """

    axis: int
    frequency_hz: float
    damping: float

    def __post_init__(self):
        if not (isinstance(self.axis, (int, np.integer)) and self.axis >= 0):
            raise ParameterError(f"StructuralMode.axis must be an axis index >= 0, got {self.axis!r}")
        if not (np.isfinite(self.frequency_hz) and self.frequency_hz > 0):
            raise ParameterError(f"StructuralMode.frequency_hz must be finite and > 0 Hz, got {self.frequency_hz!r}")
        if not (np.isfinite(self.damping) and 0 < self.damping < 1):
            raise ParameterError(f"StructuralMode.damping must be in (0, 1), got {self.damping!r}")

    @property
    def wn(self) -> float:
        """Natural frequency [rad/s]."""
        return 2 * math.pi * float(self.frequency_hz)


def mode_flow(delta, rate, a0, jerk, h, wn: float, zeta: float, math_module=np):
    """State ``(delta, delta')`` of a mode after ``h`` [s] under ``a = a0 + jerk t`` (eq V2).

    Args:
        delta, rate: deflection [mm] and its rate [mm/s] at the start of the interval.
        a0, jerk: axis acceleration at the start [mm/s^2] and its constant jerk [mm/s^3].
        h: interval length [s] (array or CasADi expression; broadcast with the others).
        wn, zeta: the mode's natural frequency [rad/s] and damping ratio.
        math_module: provides ``exp``, ``sin``, ``cos`` (``numpy`` or ``casadi``).

    Returns:
        ``(delta(h), delta'(h))``.
    """
    s, wd = zeta * wn, wn * math.sqrt(1.0 - zeta * zeta)
    c1 = -jerk / wn**2
    c0 = (-a0 + 2 * zeta * jerk / wn) / wn**2
    e0, r0 = delta - c0, rate - c1
    decay, cs, sn = math_module.exp(-s * h), math_module.cos(wd * h), math_module.sin(wd * h)
    e = decay * (e0 * cs + (r0 + s * e0) / wd * sn)
    r = decay * (r0 * cs - (wn**2 * e0 + s * r0) / wd * sn)
    return e + c0 + c1 * h, r + c1


def residual_amplitude(delta, rate, wn: float, zeta: float, math_module=np):
    """Envelope of the free vibration left by the state ``(delta, delta')`` at rest (eq V3) [mm]."""
    s, wd = zeta * wn, wn * math.sqrt(1.0 - zeta * zeta)
    return math_module.sqrt(delta**2 + ((rate + s * delta) / wd) ** 2)


def mode_states(states: np.ndarray, jerks: np.ndarray, h: np.ndarray, modes, initial=None) -> np.ndarray:
    """Exact mode states at the nodes of a piecewise-constant-jerk motion (eq V2, interval by interval).

    Args:
        states: ``(K + 1, 3, d)`` node states ``[p, v, a]``.
        jerks: ``(K, d)`` jerk of each interval [mm/s^3].
        h: ``(K,)`` interval lengths [s].
        modes: sequence of :class:`StructuralMode`.
        initial: ``(2, m)`` mode states at the first node (default: at rest).

    Returns:
        ``(K + 1, 2, m)`` ``(delta, delta')`` [mm, mm/s] at every node.
    """
    m = len(modes)
    out = np.zeros((states.shape[0], 2, m))
    if initial is not None:
        out[0] = initial
    for k, mode in enumerate(modes):
        a0, j = states[:-1, 2, mode.axis], jerks[:, mode.axis]
        for i in range(h.size):
            out[i + 1, :, k] = mode_flow(out[i, 0, k], out[i, 1, k], a0[i], j[i], h[i], mode.wn, mode.damping)
    return out


def grid_vibration(states: np.ndarray, jerks: np.ndarray, h: np.ndarray, modes, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Residual envelope (eq V3) and peak in-motion ``|delta|`` [mm] of each mode, simulated from
    rest on a piecewise-constant-jerk motion (arguments as :func:`mode_states`) and resampled at the
    fractions ``theta`` of every interval; empty arrays without modes."""
    if not modes:
        return np.zeros(0), np.zeros(0)
    nodes = mode_states(states, jerks, h, modes)
    residual, deflection = np.empty(len(modes)), np.empty(len(modes))
    for k, md in enumerate(modes):
        d, r = nodes[:-1, 0, k, None], nodes[:-1, 1, k, None]
        a0, j = states[:-1, 2, md.axis, None], jerks[:, md.axis, None]
        dense, _ = mode_flow(d, r, a0, j, h[:, None] * theta[None, :], md.wn, md.damping)
        deflection[k] = np.abs(dense).max()
        residual[k] = residual_amplitude(nodes[-1, 0, k], nodes[-1, 1, k], md.wn, md.damping)
    return residual, deflection


def check_modes(modes, dim: int) -> tuple[StructuralMode, ...]:
    """Validate ``modes`` against a ``dim``-axis path; returns them as a tuple."""
    modes = tuple(modes or ())
    for k, mode in enumerate(modes):
        if not isinstance(mode, StructuralMode):
            raise ParameterError(f"modes[{k}] must be a StructuralMode, got {type(mode).__name__}")
        if mode.axis >= dim:
            raise ParameterError(f"modes[{k}] is on axis {mode.axis} but the path has {dim} axes")
    return modes


def trajectory_vibration(traj, modes, step: float = 1e-4) -> tuple[np.ndarray, np.ndarray]:
    """Residual vibration (eq V3) and peak in-motion deflection of ``modes`` driven by any motion.

    The axis acceleration is evaluated on the break points of the trajectory's exact profile (when
    it has one) merged with a grid of ``step``, and taken as linear between them; eq V2 is then
    exact on every interval, so the result is exact for profiles of degree <= 3 (FIR overlap with
    two filters, the OCP) and within ``O((wn step)^2)`` otherwise.

    Args:
        traj: a :class:`~research.trajectory.Trajectory` that starts and ends at rest.
        modes: sequence of :class:`StructuralMode` (axes index ``traj``'s axes).
        step: grid spacing [s].

    Returns:
        ``(residual, peak)``: ``(m,)`` residual envelopes and ``(m,)`` peak ``|delta|`` during the
        motion [mm]; the modes start at rest.
    """
    modes = check_modes(modes, traj.n_axes)
    T = float(traj.duration)
    t = np.arange(0.0, T, step)
    if traj.exact is not None:
        b = np.asarray(traj.exact.breaks, dtype=np.float64)
        t = np.concatenate([t, b[(b > 0) & (b < T)]])
    t = np.unique(np.concatenate([t, [0.0, T]]))
    t = t[np.concatenate([[True], np.diff(t) > 1e-12])]
    a = np.asarray(traj.evaluate(t, 2), dtype=np.float64)
    h = np.diff(t)
    residual, peak = np.empty(len(modes)), np.empty(len(modes))
    for k, md in enumerate(modes):
        ax = a[:, md.axis]
        j = np.diff(ax) / h
        d = r = 0.0
        top = 0.0
        wn, z = md.wn, float(md.damping)
        for i in range(h.size):
            d, r = mode_flow(d, r, float(ax[i]), float(j[i]), float(h[i]), wn, z, math)
            top = max(top, abs(d))
        residual[k] = residual_amplitude(d, r, wn, z, math)
        peak[k] = top
    return residual, peak
