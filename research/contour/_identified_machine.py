"""Thesis §6.5.3 and Fig 6.13: identify every axis of the Table 6.3 virtual 5-axis machine with LS
(eq 6.12) and PSO (§6.4), then predict the tool-tip contour error of the Chapter 4 spiral path at
75 mm/s with the identified models against the true machine.

Thesis §6.5.3: "The 5-axis spiral contour toolpath shown in Chapter 4 was interpolated with tangential
velocity of 75 [mm/sec] and acceleration of 1500 [mm/sec^2] ... The discrepancy between the estimated
and true contour errors is observed to be less than 10 [micron]". Table 6.3 prints the true
(wn, zeta, p) and zeros of each axis and one PSO column; the thesis used PSO only because "the LS
algorithm produces unstable poles with increased feedforward dynamic compensation".

What is built, and the choices the thesis leaves open (each stated):

- **True machine**: :func:`research.drives.table_6_3_closed_loop` per axis (Table 6.3 "Actual": poles from
  (wn, zeta, p) by eq 6.13, numerator from the listed zeros with unity DC gain, ``dc`` as printed, read
  in eq 6.3 units [mm/s^2] or [rad/s^2]).
- **Excitation**: the §6.5 program (:func:`research.identification.identification_program`: 70 random
  moves in +-50, 250 /s, 2500 /s^2, 1 ms) for every axis. A G-code's A / C words are degrees, so the
  rotary axes run the same numbers in degrees (+-50 deg, 250 deg/s): the eq 6.3 coefficients a, b do
  not depend on the length unit, and ``dc`` is converted (deg/s^2 <-> rad/s^2) on the way in and out.
  The thesis does not say which program its rotary axes ran.
- **Log**: the simulated actual position without encoder noise (a virtual drive; the thesis mentions no
  noise for its simulations). :func:`identify_table_6_3` takes an encoder for a sensitivity run.
- **Regression**: eq 6.9 as printed (:meth:`RegressionOptions.thesis`), LS by eq 6.12, PSO with the
  thesis' settings (§6.5: 200 particles, 100 iterations, w = 0.6, eta = 0.103 / 2.897, bounds
  0.2-500 Hz, zeta 0.2-2), one swarm, seeded.
- **Prediction**: :func:`research.contour.eq436_trajectory` at 75 mm/s, 1500 mm/s^2, 1 ms, simulated
  through the five true and the five identified eq 6.3 models (exact Coulomb sign), exact tool-tip
  contour error of each (:func:`research.contour.exact_tip_contour_error`), machine offsets zero as
  in the ch 4 study.
"""

from __future__ import annotations

from dataclasses import dataclass

import jax.numpy as jnp
import numpy as np

from research.contour._cec import simulate_setpoint
from research.contour._five_axis import eq436_trajectory
from research.contour._frenet import exact_tip_contour_error, tip_reference
from research.drives import ClosedLoopModel, Encoder, table_6_3_closed_loop
from research.errors import ParameterError
from research.paths.kinematics5 import TableTiltingAC

AXES = ("x", "y", "z", "a", "c")
ROTARY = ("a", "c")
#: thesis §6.5.3: feed [mm/s] and acceleration [mm/s^2] of the Fig 6.13 run
FIG6_13_FEED = 75.0
FIG6_13_ACCELERATION = 1500.0
#: thesis §6.5.3: largest discrepancy between predicted and true contour error [mm]
FIG6_13_BOUND = 0.010
#: thesis Table 6.3, "PSO Estimated" search variables: axis -> (wn [Hz], zeta, p [Hz]) and dc as printed
TABLE_6_3_PSO = {"x": (58.0, 0.27, 20.12, 533.0), "y": (90.9, 0.2, 24.5, 415.0), "z": (138.5, 2.0, -138.5, 5551.0),
                 "a": (24.19, 1.53, 24.19, -8.642), "c": (68.9, 2.0, 68.9, 366.3)}
HZ = 2 * np.pi


def _unit_scale(axis: str) -> float:
    """Program units per model unit: degrees per radian for A, C (module docstring), 1 for X, Y, Z."""
    return 180.0 / np.pi if axis in ROTARY else 1.0


@dataclass(frozen=True)
class AxisIdentification:
    """One axis of Table 6.3: the true model and the LS and PSO fits (``IdentifiedDrive``), in model units
    (mm or rad; ``dc`` in mm/s^2 or rad/s^2)."""

    axis: str
    truth: ClosedLoopModel
    ls: object
    pso: object

    def columns(self) -> dict:
        """``{"actual" | "ls" | "pso" | "thesis_pso": (wn [Hz], zeta, p [Hz], dc, stable)}`` (Table 6.3 layout)."""
        wn, z, p = self.truth.pole_parameters()
        out = {"actual": (wn / HZ, z, p / HZ, float(self.truth.dc), True)}
        for name in ("ls", "pso"):
            fit = getattr(self, name)
            wn, z, p = fit.pole_parameters()
            out[name] = (wn / HZ, z, p / HZ, fit.dc / _unit_scale(self.axis), fit.stable)
        out["thesis_pso"] = TABLE_6_3_PSO[self.axis] + (None,)
        return out

    def model(self, method: str) -> ClosedLoopModel:
        """The identified eq 6.3 model of ``method`` (``"ls"`` or ``"pso"``) in model units.

        Raises:
            ParameterError: unknown method, an unstable fit (it cannot predict a contour error), or a
                negative friction (see :meth:`IdentifiedDrive.model`).
        """
        if method not in ("ls", "pso"):
            raise ParameterError(f"method must be 'ls' or 'pso', got {method!r}")
        fit = getattr(self, method)
        if not fit.stable:
            raise ParameterError(f"{method} fit of axis {self.axis!r} has unstable poles {fit.poles()} rad/s; "
                                 "it cannot be simulated for a contour-error prediction")
        m = fit.model()
        return ClosedLoopModel(m.a1, m.a2, m.a3, m.b0, m.b1, m.b2, m.dc / _unit_scale(self.axis))


def identify_table_6_3(*, seed: int = 0, encoder: Encoder | None = None, regression=None, pso_settings=None) -> dict:
    """Identify each axis of the Table 6.3 virtual machine with LS and PSO on the §6.5 program.

    Args:
        seed: seed of the program (and of the encoder noise and the swarm).
        encoder: encoder of the logged position (None: exact, the default; module docstring).
        regression: :class:`research.identification.RegressionOptions` (default: eq 6.9 as printed).
        pso_settings: :class:`research.identification.PSOSettings` (default: the thesis' §6.5 values).
    Returns:
        ``{axis: AxisIdentification}`` for x, y, z, a, c.
    """
    from research.identification import (
        PSOSettings,
        ProjectedProblem,
        RegressionOptions,
        build_regression,
        identification_program,
        least_squares,
        particle_swarm,
        synthetic_log,
    )

    regression = RegressionOptions.thesis() if regression is None else regression
    pso_settings = PSOSettings() if pso_settings is None else pso_settings
    program = identification_program(seed).trajectory()
    out = {}
    for axis in AXES:
        truth = table_6_3_closed_loop(axis)
        k = _unit_scale(axis)
        in_program_units = ClosedLoopModel(truth.a1, truth.a2, truth.a3, truth.b0, truth.b1, truth.b2, truth.dc * k)
        log = synthetic_log(in_program_units, program, encoder=encoder, seed=seed + 1, source=f"Table 6.3 {axis}")
        reg = build_regression(log, regression)
        out[axis] = AxisIdentification(axis, truth, least_squares(reg),
                                       particle_swarm(ProjectedProblem.from_regression(reg), seed=seed, settings=pso_settings))
    return out


@dataclass(frozen=True)
class ContourPrediction:
    """Fig 6.13: exact tool-tip contour error [mm] of the true and of the identified machines.

    Attributes:
        t: ``(N,)`` [s]; true: ``(N,)``; predicted: ``{method: (N,)}``; excluded: ``{method: reason}`` for
        model sets that could not be simulated (an unstable fit or a negative friction).
    """

    t: np.ndarray
    true: np.ndarray
    predicted: dict
    excluded: dict = None

    def discrepancy(self, method: str) -> np.ndarray:
        """``|predicted - true|`` [mm]."""
        return np.abs(self.predicted[method] - self.true)


def predict_contour_error(models: dict, *, feed: float = FIG6_13_FEED, acceleration: float = FIG6_13_ACCELERATION,
                          machine: TableTiltingAC | None = None, sample_period: float = 1e-3) -> ContourPrediction:
    """Simulate the eq 4.36 path through the true Table 6.3 axes and through each set in ``models``.

    Args:
        models: ``{name: (5 ClosedLoopModel in x, y, z, a, c order)}``.
        feed, acceleration: of the tip motion [mm/s], [mm/s^2] (default thesis §6.5.3: 75, 1500).
        machine: kinematics (default offsets zero); sample_period: [s].
    Raises:
        ParameterError: a model set without 5 axes.
    """
    machine = TableTiltingAC() if machine is None else machine
    for name, drives in models.items():
        if len(drives) != 5:
            raise ParameterError(f"model set {name!r} must hold 5 axes (x, y, z, a, c), got {len(drives)}")
    ref = eq436_trajectory(machine, feed=feed, acceleration=acceleration, sample_period=sample_period)
    reference = tip_reference(ref, machine)
    t = np.asarray(ref.t)

    def contour(drives):
        resp = simulate_setpoint(ref, tuple(drives), "exact")
        P = np.asarray(machine.forward(jnp.asarray(resp.position))[0])
        return exact_tip_contour_error(reference, float(t[0]), float(t[-1]), P)

    true = contour(tuple(table_6_3_closed_loop(a) for a in AXES))
    return ContourPrediction(t, true, {name: contour(drives) for name, drives in models.items()}, {})


def fig6_13(*, seed: int = 0, encoder: Encoder | None = None, pso_settings=None, feed: float = FIG6_13_FEED,
            acceleration: float = FIG6_13_ACCELERATION, sample_period: float = 1e-3) -> tuple[dict, ContourPrediction]:
    """Identify (:func:`identify_table_6_3`) and predict (:func:`predict_contour_error`) with every
    method whose five fits are stable with non-negative friction; returns ``(identification, prediction)``.
    ``pso_settings``, ``feed``, ``acceleration`` and ``sample_period`` are passed on (defaults: the thesis')."""
    ident = identify_table_6_3(seed=seed, encoder=encoder, pso_settings=pso_settings)
    models, excluded = {}, {}
    for method in ("ls", "pso"):
        try:
            models[method] = tuple(ident[a].model(method) for a in AXES)
        except ParameterError as exc:
            excluded[method] = str(exc)
    pred = predict_contour_error(models, feed=feed, acceleration=acceleration, sample_period=sample_period)
    return ident, ContourPrediction(pred.t, pred.true, pred.predicted, excluded)

