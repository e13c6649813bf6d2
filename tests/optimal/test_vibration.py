"""Vibration-aware time-optimal reference and the N-convergence check (issue 19, items 1 and 3).

The residual vibration of a solution is measured here by an independent simulation: the mode's
state space driven by the OCP's acceleration sampled at 0.1 ms (``scipy.signal.lsim``), then left
to ring out for two periods at rest; its peak ``|delta|`` there is the residual (the Fig 6
definition: peak deflection after the motion ends, which is at most the eq V3 envelope).
"""

import numpy as np
import pytest
from scipy import signal

from research.errors import ParameterError
from research.drives import residual_vibration_sampled
from research.interpolators import scurve_profile
from research.limits import AxisLimits
from research.optimal import StructuralMode, converged_time_optimal, time_optimal, trajectory_vibration
from research.paths.library import corner90
from research.paths.polyline import Polyline

# Sencer 2015 §4: F = 250 mm/s, eps = 500 um, T1/T2 = 148/89 ms; beams 11.4 Hz on X, 6.8 Hz on Y
# (2 % damping: assumed, the paper gives none)
F, DELAYS, EPS = 250.0, (0.148, 0.089), 0.5
LIMITS = AxisLimits.fir_envelope(2, F, DELAYS)
BEAMS = (StructuralMode(0, 11.4, 0.02), StructuralMode(1, 6.8, 0.02))
N = 12
DT = 1e-4
# lsim interpolates the input linearly between 0.1 ms samples; the acceleration is continuous and
# piecewise linear with jerk jumps of at most 2 j_max (j_max = F/(T1 T2) = 1.9e4 mm/s^3), so each
# kink between samples perturbs the mode's rate by at most 2 j_max DT^2 / 8 and the deflection by
# that / wd: 1.1e-6 mm at 6.8 Hz. 2 N + 1 kinks per segment on 2 segments: below 5.5e-5 mm.
SIM_TOL = 1e-4


def lsim_vibration(traj, mode: StructuralMode) -> tuple[float, float]:
    """``(residual, in-motion peak)`` [mm] of ``mode`` driven by ``traj``'s acceleration (independent
    simulation: scipy's state-space solver on 0.1 ms samples, two periods of ring-out at rest)."""
    wn, z = 2 * np.pi * mode.frequency_hz, mode.damping
    sys = signal.StateSpace([[0.0, 1.0], [-wn * wn, -2 * z * wn]], [[0.0], [-1.0]], [[1.0, 0.0]], [[0.0]])
    T = float(traj.duration)
    n_move = int(np.ceil(T / DT))
    t = np.arange(n_move + int(np.ceil(2 / mode.frequency_hz / DT)) + 1) * DT
    a = np.where(t <= T, traj.evaluate(np.minimum(t, T), 2)[:, mode.axis], 0.0)
    _, y, _ = signal.lsim(sys, a, t)
    return float(np.abs(y[t > T]).max()), float(np.abs(y[t <= T]).max())


@pytest.fixture(scope="module")
def plain():
    return time_optimal(corner90(), LIMITS, EPS, feed=F, intervals_per_segment=N)


@pytest.mark.parametrize("bound", [0.0, (0.002, 0.0005)])
def test_residual_vibration_within_the_bound_by_independent_simulation(plain, bound):
    res = time_optimal(corner90(), LIMITS, EPS, feed=F, intervals_per_segment=N, modes=BEAMS, residual_vibration=bound)
    bounds = np.broadcast_to(bound, (len(BEAMS),))
    for mode, b in zip(BEAMS, bounds):
        residual, _ = lsim_vibration(res.trajectory, mode)
        assert residual <= b + SIM_TOL
        # the plain OCP leaves far more: the bound is what changed the motion
        assert lsim_vibration(plain.trajectory, mode)[0] > 10 * max(b, 1e-3)
    # the result's own re-simulated envelope (eq V3) agrees
    assert np.all(res.verification.residual_vibration <= bounds + 1e-7)
    # the residual bound is an extra constraint on the same NLP: never faster than the plain OCP
    assert res.cycle_time >= plain.cycle_time * (1 - 1e-7)
    assert res.verification.worst_ratio <= 1.01  # tube and limits still hold between grid points


def test_in_motion_deflection_bound(plain):
    mode = BEAMS[1]
    D = 0.8 * lsim_vibration(plain.trajectory, mode)[1]
    res = time_optimal(corner90(), LIMITS, EPS, feed=F, intervals_per_segment=N, modes=BEAMS,
                       residual_vibration=None, max_deflection=D)
    # imposed at the nodes and 3 check points per interval, i.e. every s = h / 4: near a peak the
    # deflection is a sinusoid of wd, which between two points s apart rises at most by
    # 1 / cos(wd s / 2) over them
    s = float(np.max(res.phase_durations)) / N / 4
    wd = 2 * np.pi * mode.frequency_hz * np.sqrt(1 - mode.damping**2)
    peak = lsim_vibration(res.trajectory, mode)[1]
    assert peak <= D / np.cos(wd * s / 2) + SIM_TOL
    assert peak < 0.9 * lsim_vibration(plain.trajectory, mode)[1]
    assert res.cycle_time >= plain.cycle_time * (1 - 1e-7)


def test_trajectory_vibration_matches_the_convolution_integral(plain):
    """``trajectory_vibration`` (eq V2 interval by interval) against ``fir_model``'s envelope
    ``|B| / wd`` with ``B = int a(tau) exp(lam (t_e - tau)) d tau`` by the trapezoid rule on 10 us
    samples (an independent formula; its error is O((wn dt)^2 / 12) = 4e-8 relative at 11.4 Hz)."""
    traj = plain.trajectory
    t = np.linspace(0.0, float(traj.duration), int(float(traj.duration) / 1e-5) + 1)
    a = traj.evaluate(t, 2)
    residual, _ = trajectory_vibration(traj, BEAMS)
    for k, mode in enumerate(BEAMS):
        expected = residual_vibration_sampled(t, a[:, mode.axis], mode.frequency_hz, mode.damping)
        assert residual[k] == pytest.approx(expected, rel=1e-5)


def test_n_convergence_on_a_line_approaches_the_scurve_optimum():
    """1-D: the rest-to-rest optimum is the seven-phase S-curve (Biagiotti & Melchiorri 2008 §3.4).
    The grid error falls at least like 1/N (``C / N``), so a refinement N -> g N that changes the
    cycle time by ``c = (g - 1) C / (g N)`` leaves at most ``C / (g N) = c / (g - 1)``: 2c for g = 1.5."""
    v, a, j = 250.0, F / DELAYS[0], F / (DELAYS[0] * DELAYS[1])
    optimum = float(scurve_profile(100.0, v, a, j).end)
    conv = converged_time_optimal(Polyline([[0.0], [100.0]]), AxisLimits.uniform(1, v, a, j), EPS,
                                  start_intervals=8, rel_change=1e-3)
    Ns = [h[0] for h in conv.history]
    assert conv.converged and conv.relative_change < 1e-3
    assert Ns == sorted(Ns) and Ns[0] == 8 and Ns[-1] == conv.intervals
    assert optimum <= conv.cycle_time * (1 + 1e-7)
    assert conv.cycle_time <= optimum * (1 + 2 * conv.relative_change)
    assert conv.history[0][1] > conv.cycle_time  # the coarsest grid was the slowest


def test_n_convergence_stops_at_max_intervals_unconverged():
    conv = converged_time_optimal(corner90(), LIMITS, EPS, feed=F, start_intervals=4, max_intervals=6,
                                  rel_change=1e-12)
    assert not conv.converged and conv.intervals == 6


@pytest.mark.parametrize("mode_args, match", [
    ((-1, 11.4, 0.02), "axis"), ((0, 0.0, 0.02), "frequency_hz"), ((0, 11.4, 1.0), "damping"),
])
def test_bad_mode_raises(mode_args, match):
    with pytest.raises(ParameterError, match=match):
        StructuralMode(*mode_args)


def test_mode_on_a_missing_axis_and_bad_bounds_raise():
    with pytest.raises(ParameterError, match="axis 2"):
        time_optimal(corner90(), LIMITS, EPS, modes=(StructuralMode(2, 10.0, 0.02),))
    with pytest.raises(ParameterError, match="residual_vibration"):
        time_optimal(corner90(), LIMITS, EPS, modes=BEAMS, residual_vibration=-1.0)
    with pytest.raises(ParameterError, match="one per mode"):
        time_optimal(corner90(), LIMITS, EPS, modes=BEAMS, residual_vibration=(0.1, 0.1, 0.1))
    with pytest.raises(ParameterError, match="tolerance > 0"):
        time_optimal(corner90(), LIMITS, 0.0, modes=BEAMS)
    with pytest.raises(ParameterError, match="growth"):
        converged_time_optimal(corner90(), LIMITS, EPS, growth=1.0)
