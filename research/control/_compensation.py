"""Feedback against feed-forward on the same path and drives (issue 17 item 6; not in the thesis):
the SISO SMC and the contour controller, each alone and with mirror compensation of its reference.

Mirror compensation here is the time-indexed form of Prévost et al.'s eq 4 (``R' = R - e``), applied
to what each controller tracks: the correction ``D`` is updated by ``D <- D + (target - actual)`` after
each simulated pass, in joint space ``q`` for the SISO drives and in tip space ``P`` (plus the A, C
joints) for the contour controller, whose reference is the tool-tip pose (Fig 5.2). The derivatives
the laws feed forward, ``D'`` and ``D''``, are central finite differences at the control period (as
:func:`research.contour.corrected_setpoint` does), so the corrected command is what a CNC would send
from corrected position samples. Difference from :func:`research.contour.mirror_compensation`: that
one projects the actual tip on the CAM path (contour, not tracking, error) and runs the
:mod:`research.drives` models, whose interface has no place for these closed-loop controllers; the
Frenet frame and the rotary direction ``v`` stay those of the CAM path (the correction is microns).
Metrics are always measured against the uncorrected CAM reference.
"""

from __future__ import annotations

from dataclasses import dataclass

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from research.control._gains import AxisSMC, ContourGains
from research.control._loop import simulate_closed_loop
from research.control._plant import FiveAxisPlant, thesis_plant
from research.control._reference import ContourReference, eq436_reference
from research.control._study import CONTROL_PERIOD, CaseResult, check_controller, identify_coulomb, measure
from research.errors import ParameterError
from research.paths.kinematics5 import TableTiltingAC


def _derivatives(D: np.ndarray, T: float):
    d1 = np.gradient(D, T, axis=0)
    return d1, np.gradient(d1, T, axis=0)


def corrected_reference(ref: ContourReference, Dq: np.ndarray, DP: np.ndarray) -> ContourReference:
    """``ref`` with joint correction ``Dq`` ``(N, 5)`` and tip correction ``DP`` ``(N, 3)`` added to the
    positions and their central-difference derivatives added to the velocities and accelerations."""
    T = ref.sample_period
    dq1, dq2 = _derivatives(Dq, T)
    dP1, dP2 = _derivatives(DP, T)
    new = (ref.q + Dq, ref.qd + dq1, ref.qdd + dq2, ref.P + DP, ref.Pd + dP1, ref.Pdd + dP2)
    return eqx.tree_at(lambda r: (r.q, r.qd, r.qdd, r.P, r.Pd, r.Pdd), ref, tuple(jnp.asarray(x) for x in new))


def tracking_mirror_passes(plant: FiveAxisPlant, ref: ContourReference, controller: AxisSMC | ContourGains, passes: int,
                  machine: TableTiltingAC | None = None):
    """Run ``passes`` mirror updates; returns the closed-loop results of pass 0 (uncompensated) .. ``passes``."""
    machine = TableTiltingAC() if machine is None else machine
    if not (isinstance(passes, (int, np.integer)) and passes >= 0):
        raise ParameterError(f"passes must be an integer >= 0, got {passes!r}")
    Dq = np.zeros(np.shape(ref.q))
    DP = np.zeros(np.shape(ref.P))
    out = [simulate_closed_loop(plant, ref, controller, machine)]
    for _ in range(passes):
        q = np.asarray(out[-1].q)
        Dq = Dq + (np.asarray(ref.q) - q)
        DP = DP + (np.asarray(ref.P) - np.asarray(machine.forward(jnp.asarray(q))[0]))
        out.append(simulate_closed_loop(plant, corrected_reference(ref, Dq, DP), controller, machine))
    return out


@dataclass(frozen=True)
class SchemeResult:
    """One row of the feedback / feed-forward comparison: ``name`` and the measured :class:`CaseResult`."""

    name: str
    case: CaseResult


def feedback_vs_feedforward(*, feed: float = 50.0, passes: int = 3, coulomb=None, T: float = CONTROL_PERIOD,
                            plant: FiveAxisPlant | None = None) -> list[SchemeResult]:
    """SISO SMC, contour controller, SISO + mirror and contour controller + mirror on the Fig 5.5 path.

    Returns:
        rows ``"SISO SMC"``, ``"contour controller"``, ``"SISO SMC + mirror (k passes)"``,
        ``"contour controller + mirror (k passes)"`` for k = 1 and ``passes``.
    """
    from research.control._gains import table_5_2, table_5_3

    plant = thesis_plant() if plant is None else plant
    coulomb = identify_coulomb(plant, T=T) if coulomb is None else coulomb
    plant = plant.with_coulomb(coulomb)
    ref, traj = eq436_reference(feed=feed, sample_period=T)
    rows = []
    for name, g in (("SISO SMC", table_5_2()), ("contour controller", table_5_3())):
        check_controller(g, plant, T)
        runs = tracking_mirror_passes(plant, ref, g, passes)
        rows.append(SchemeResult(name, measure(ref, traj, runs[0])))
        for k in sorted({1, passes} - {0}):
            rows.append(SchemeResult(f"{name} + mirror ({k} pass{'es' if k > 1 else ''})", measure(ref, traj, runs[k])))
    return rows
