"""Reproducible synthetic accelerometer logs with known modes (the truth the estimator is scored on).

The machine: an ideal drive (the axis follows the commanded acceleration ``x''``, the config's
``drive.model = "ideal"``) carrying light structural modes (:class:`~research.drives.FlexibleMode`,
``delta_m'' + 2 zeta_m wn_m delta_m' + wn_m^2 delta_m = -x''``). The accelerometer on the tool head reads

    a = x'' + sum_m p_m delta_m'' = x'' - sum_m p_m (2 zeta_m wn_m delta_m' + wn_m^2 delta_m),

(participation ``p_m``, 1 for a single mode), simulated with ``scipy.signal.lsim`` on the mode's state
matrices (exact matrix exponential of the mode, first-order hold of ``x''`` between samples), plus
white Gaussian sensor noise at a stated SNR (``10 log10`` of the mean-square signal of the strongest
excited column over the noise variance; every column gets that same noise variance, as one sensor's) and, optionally, gravity
on z. Excitation along a direction ``u`` (default the X-Y diagonal, so one log holds both axes):

* :func:`sine_sweep`: ``x''(t) = A sin(2 pi (f0 t + (f1 - f0) t^2 / (2 D)))``, a linear chirp of constant
  acceleration amplitude (flat spectrum over ``[f0, f1]``);
* :func:`tone_series`: ``n`` tones ``f0 .. f1`` held ``D / n`` each, phase-continuous; dense enough
  (``(f1 - f0) D / n^2 <= 1``: neighbouring tones closer than a tone's line width ``n / D``) that its
  spectrum is flat like the sweep's.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy import signal

from research.drives import FlexibleMode
from research.errors import ParameterError
from research.vibration._accel_log import STANDARD_GRAVITY_MM_S2, AccelLog


@dataclasses.dataclass(frozen=True)
class TrueMode:
    """A structural mode of the synthetic machine: axis letter, ``frequency_hz`` [Hz], ``damping`` [-],
    ``participation`` [-] (its share of the tool-head deflection)."""

    axis: str
    frequency_hz: float
    damping: float
    participation: float = 1.0


def _check(f0, f1, duration, rate, amplitude):
    if not (0 < f0 < f1 < rate / 2):
        raise ParameterError(f"excitation band needs 0 < f0 < f1 < fs/2 = {rate / 2:g} Hz, got f0 = {f0!r}, f1 = {f1!r}")
    if not (duration > 0 and amplitude > 0):
        raise ParameterError(f"duration [s] and amplitude [mm/s^2] must be > 0, got {duration!r}, {amplitude!r}")


def sine_sweep(f0: float, f1: float, duration: float, rate: float, amplitude: float,
               per_hz: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """``(t, x'')``: linear chirp of the commanded axis acceleration [s, mm/s^2] (module docstring);
    ``per_hz``: amplitude ``amplitude * f(t)`` (Klipper's ``accel_per_hz``, mm/s^2/Hz) instead of constant."""
    _check(f0, f1, duration, rate, amplitude)
    t = np.arange(int(round(duration * rate))) / rate
    phase = 2 * np.pi * (f0 * t + 0.5 * (f1 - f0) / duration * t**2)
    scale = f0 + (f1 - f0) * t / duration if per_hz else 1.0
    return t, amplitude * scale * np.sin(phase)


def tone_series(f0: float, f1: float, n_tones: int, duration: float, rate: float,
                amplitude: float) -> tuple[np.ndarray, np.ndarray]:
    """``(t, x'')``: ``n_tones`` phase-continuous tones from ``f0`` to ``f1``, ``duration / n_tones`` each."""
    _check(f0, f1, duration, rate, amplitude)
    if n_tones < 2:
        raise ParameterError(f"a tone series needs at least 2 tones, got {n_tones!r}")
    t = np.arange(int(round(duration * rate))) / rate
    freqs = np.linspace(f0, f1, n_tones)
    idx = np.minimum((t / (duration / n_tones)).astype(int), n_tones - 1)
    phase = 2 * np.pi * np.cumsum(freqs[idx]) / rate
    return t, amplitude * np.sin(phase - phase[0])


def tip_acceleration(t: np.ndarray, axis_accel: np.ndarray, modes: list[TrueMode]) -> np.ndarray:
    """Tool-head acceleration [mm/s^2] of one axis carrying ``modes`` (module docstring)."""
    out = np.array(axis_accel, dtype=np.float64)
    for m in modes:
        fm = FlexibleMode.from_hz(m.frequency_hz, m.damping)
        A, e = (np.asarray(x, dtype=np.float64) for x in fm.state_matrices())
        w, z = float(fm.natural_frequency), float(fm.damping)
        sys = signal.StateSpace(A, e[:, None], np.array([[-w * w, -2 * z * w]]), np.zeros((1, 1)))
        _, y, _ = signal.lsim(sys, axis_accel, t, interp=True)  # y = x'' + delta_m'' (the mode's tip)
        out = out + m.participation * (y - axis_accel)
    return out


def synthetic_accel_log(modes: list[TrueMode], *, excitation: str = "sweep", f0: float = 2.0, f1: float = 40.0,
                        duration: float = 10.0, rate: float = 3200.0, amplitude: float = 1000.0,
                        direction=(1.0, 1.0, 0.0), snr_db: float | None = 20.0, seed: int = 0,
                        n_tones: int | None = None, gravity: bool = True, per_hz: bool = False) -> AccelLog:
    """A resonance-test log of a machine with known ``modes`` (module docstring).

    Args:
        modes: the truth; each on axis ``x``, ``y`` or ``z``.
        excitation: ``"sweep"`` or ``"tones"``.
        f0, f1: excitation band [Hz]; duration [s]; rate: sample rate [Hz]; amplitude: commanded
            acceleration amplitude along ``direction`` [mm/s^2].
        direction: excitation direction (normalized here); an axis with component 0 is not excited.
        snr_db: signal-to-noise ratio [dB] of the strongest excited column; ``None``: no noise.
        seed: seed of the noise (``numpy.random.default_rng``).
        n_tones: tones of the series; default ``ceil(2 sqrt((f1 - f0) duration))`` (dense, see above).
        per_hz: sweep amplitude ``amplitude * f(t)`` [mm/s^2/Hz] (Klipper's ``accel_per_hz``), not constant.
        gravity: add ``-1 g`` on z (a sensor at rest reads +1 g up; sign irrelevant to the PSD).
    Returns:
        :class:`AccelLog` with columns x, y, z [mm/s^2], source ``"synthetic ..."``.
    """
    u = np.asarray(direction, dtype=np.float64)
    if u.shape != (3,) or not np.linalg.norm(u) > 0:
        raise ParameterError(f"direction must be a non-zero 3-vector, got {direction!r}")
    u = u / np.linalg.norm(u)
    for m in modes:
        if m.axis not in ("x", "y", "z"):
            raise ParameterError(f"TrueMode.axis must be 'x', 'y' or 'z', got {m.axis!r}")
    if excitation == "sweep":
        t, a = sine_sweep(f0, f1, duration, rate, amplitude, per_hz)
    elif excitation == "tones":
        n = n_tones if n_tones is not None else int(np.ceil(2 * np.sqrt((f1 - f0) * duration)))
        t, a = tone_series(f0, f1, n, duration, rate, amplitude)
    else:
        raise ParameterError(f"excitation must be 'sweep' or 'tones', got {excitation!r}")
    clean = np.column_stack([tip_acceleration(t, u[j] * a, [m for m in modes if m.axis == ax]) if u[j] else
                             np.zeros_like(t) for j, ax in enumerate("xyz")])
    rng = np.random.default_rng(seed)
    out = clean.copy()
    if snr_db is not None:
        excited = [j for j in range(3) if u[j]]
        power = max(float(np.mean(clean[:, j] ** 2)) for j in excited)
        sigma = np.sqrt(power / 10 ** (snr_db / 10))
        out = out + rng.normal(0.0, sigma, out.shape)
    if gravity:
        out[:, 2] -= STANDARD_GRAVITY_MM_S2
    truth = ", ".join(f"{m.axis} {m.frequency_hz:g} Hz z={m.damping:g}" for m in modes)
    return AccelLog(t=t, accel=out, axes=("x", "y", "z"), source=f"synthetic {excitation} ({truth}; SNR {snr_db} dB, "
                    f"seed {seed})", columns={"t": "t", "x": "x", "y": "y", "z": "z"})
