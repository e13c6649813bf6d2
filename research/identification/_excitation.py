"""The identification NC program of thesis §6.5 (Fig 6.6), seeded, as G-code and as a reference Trajectory.

Thesis §6.5: "70 random linear movements commanded within the range of ±50 mm with a maximum feedrate of
250 mm/s and 2500 mm/s^2 acceleration", trapezoidal velocity profiling with unbounded jerk (§6.3: S-curve
disabled for a high-frequency excitation).

The trapezoids come from the FIR interpolator with a single moving-average filter of length
``T1 = F / A`` (Sencer 2015 eq 1-6 with n = 1), which turns every block's velocity pulse into a trapezoid
with acceleration ``A``; blocks shorter than ``F T1`` do not reach ``F`` (the thesis: "the desired velocity
is not necessarily reached"). Every vertex stops exactly (cornering tolerance 0). Targets are rounded to
multiples of ``F Ts``, so every pulse length ``L / F`` and ``T1`` are whole numbers of periods: the
trapezoid then switches exactly on the sample grid and a simulation with the cubic hold of
:func:`research.drives.simulate` is exact at the samples.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from research.errors import ParameterError
from research.interpolators import fir_interpolate
from research.paths import Polyline, to_gcode
from research.trajectory import Trajectory

#: Thesis §6.5 program: moves, range [mm], feed [mm/s], acceleration [mm/s^2], period [s]
THESIS_PROGRAM = {"n_moves": 70, "travel": 50.0, "feed": 250.0, "acceleration": 2500.0, "sample_period": 1e-3}


@dataclasses.dataclass(frozen=True)
class ExcitationProgram:
    """A single-axis program of random linear moves with trapezoidal velocity (thesis §6.5).

    Attributes:
        targets: ``(M + 1,)`` block end points [mm], starting at ``targets[0]``.
        feed: commanded feed ``F`` [mm/s].
        acceleration: trapezoid acceleration ``A`` [mm/s^2].
        sample_period: interpolation / control period ``Ts`` [s].
        seed: the seed that drew the targets.
        axis: axis letter used in the G-code.
    """

    targets: tuple
    feed: float
    acceleration: float
    sample_period: float
    seed: int
    axis: str = "x"

    @property
    def n_moves(self) -> int:
        return len(self.targets) - 1

    @property
    def filter_time(self) -> float:
        """``T1 = F / A`` [s]: the single FIR filter that makes the velocity trapezoidal."""
        return self.feed / self.acceleration

    def polyline(self) -> Polyline:
        """The moves as a 1-D :class:`Polyline` [mm]."""
        return Polyline(np.asarray(self.targets, dtype=np.float64)[:, None], axes=(self.axis,))

    def gcode(self) -> str:
        """The program as G-code: ``G1`` moves at ``F = 60 feed`` [mm/min] (start point in the header comment)."""
        return to_gcode(self.polyline(), self.feed * 60.0)

    def trajectory(self) -> Trajectory:
        """The reference ``x_r(t)`` sampled at ``Ts``: trapezoidal velocity, exact stop at every vertex.

        The phase switches sit on the grid up to rounding; samples there take the new phase's
        acceleration and jerk (see :meth:`research.piecewise.PiecewisePolynomial.sample`).
        """
        return fir_interpolate(self.polyline(), self.feed, [self.filter_time], 0.0, self.sample_period)


def identification_program(
    seed: int,
    *,
    n_moves: int = 70,
    travel: float = 50.0,
    feed: float = 250.0,
    acceleration: float = 2500.0,
    sample_period: float = 1e-3,
    axis: str = "x",
) -> ExcitationProgram:
    """Draw the thesis §6.5 identification program.

    Args:
        seed: seed of ``numpy.random.default_rng``; the same seed gives the same program.
        n_moves: number of linear moves (thesis: 70).
        travel: targets uniform in ``[-travel, travel]`` [mm] (thesis: 50).
        feed: maximum feed [mm/s] (thesis: 250).
        acceleration: trapezoid acceleration [mm/s^2] (thesis: 2500).
        sample_period: ``Ts`` [s] (thesis: 1 ms).
        axis: axis letter of the G-code.
    Raises:
        ParameterError: a negative or non-int seed or ``n_moves``, a non-finite or non-positive number, or
            ``feed / acceleration`` not a whole number of periods.
    Returns:
        :class:`ExcitationProgram` starting at 0 mm. Targets are multiples of ``feed * Ts`` (module
        docstring); a draw closer than one grid step to the previous target is redrawn.
    """
    if not isinstance(seed, (int, np.integer)) or isinstance(seed, bool) or seed < 0:
        raise ParameterError(f"identification_program: seed must be an int >= 0 (numpy.random.default_rng), got {seed!r}")
    for name, v in {"travel": travel, "feed": feed, "acceleration": acceleration, "sample_period": sample_period}.items():
        if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)) or not (np.isfinite(v) and v > 0):
            raise ParameterError(f"identification_program: {name} must be a finite number > 0, got {v!r}")
    if not isinstance(n_moves, (int, np.integer)) or isinstance(n_moves, bool) or n_moves < 1:
        raise ParameterError(f"identification_program: n_moves must be an int >= 1, got {n_moves!r}")
    step = feed * sample_period
    t1 = feed / acceleration
    if abs(t1 / sample_period - round(t1 / sample_period)) > 1e-9:
        raise ParameterError(
            f"identification_program: feed/acceleration = {t1!r} s must be a whole number of periods Ts = {sample_period!r} s"
        )
    rng = np.random.default_rng(int(seed))
    targets = [0.0]
    while len(targets) <= n_moves:
        x = float(np.round(rng.uniform(-travel, travel) / step) * step)
        if abs(x - targets[-1]) >= step:
            targets.append(x)
    return ExcitationProgram(tuple(targets), float(feed), float(acceleration), float(sample_period), int(seed), axis)
