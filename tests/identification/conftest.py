"""Shared, session-scoped data for the identification tests (logs are simulated once)."""

import os
from pathlib import Path

import numpy as np
import pytest

from research.drives import (
    ClosedLoopModel,
    Encoder,
    table_6_1_closed_loop,
    table_6_2_closed_loop,
)
from research.identification import ASSUMED_FRICTION, identification_program, synthetic_log

#: third-party data beside the checkout (``../shared``, as in CI); RESEARCH_SHARED_DIR points elsewhere
SHARED = Path(os.environ.get("RESEARCH_SHARED_DIR", Path(__file__).resolve().parents[3] / "shared"))
#: the EMPS estimation excerpt (see ../shared/data/README.md)
EMPS = SHARED / "data" / "emps" / "emps_estimation_first15s.mat"

#: fine encoder of the reproduction tests: 0.05 um counts (the EMPS benchmark's resolution)
FINE_ENCODER = Encoder(resolution=5e-5)


@pytest.fixture(scope="session")
def program():
    return identification_program(0)


@pytest.fixture(scope="session")
def reference(program):
    return program.trajectory()


def with_friction(model, dc):
    return ClosedLoopModel(model.a1, model.a2, model.a3, model.b0, model.b1, model.b2, dc)


@pytest.fixture(scope="session")
def table_logs(reference):
    """Thesis Table 6.1 / 6.2 drives (eq 6.3 coefficients as printed, "Actual" column) with an assumed eq 6.3
    friction dc = ASSUMED_FRICTION = 300 mm/s^2 (the thesis prints the friction only as a torque, 2.6815 N m,
    and its LS estimate 585.30 is an output, not a truth: see research.identification._virtual), logged by a
    0.05 um encoder."""
    out = {}
    for name, base in (("6.1", table_6_1_closed_loop()), ("6.2", table_6_2_closed_loop())):
        truth = with_friction(base, ASSUMED_FRICTION)
        out[name] = (truth, synthetic_log(truth, reference, encoder=FINE_ENCODER, seed=1, source=f"table {name}"))
    return out


def relative_errors(result, truth):
    """|estimate / truth - 1| of (wn, zeta, p)."""
    return np.abs(np.array(result.pole_parameters()) / np.array(truth.pole_parameters()) - 1)


def at_rest(traj):
    """``traj`` with its first velocity sample exactly 0. The §6.5 program's first sample carries a
    -2.6e-16 mm/s rounding residue, and research.drives.simulate starts the axis at the reference velocity
    and applies Coulomb friction by its sign: one period of -dc at rest, which with large friction
    (> 1000 mm/s^2) moves the simulated axis backwards by microns before the program starts."""
    from research.trajectory import Trajectory

    v = np.asarray(traj.v).copy()
    v[0] = 0.0
    return Trajectory(traj.t, traj.q, v, traj.a, traj.j, traj.duration, None, traj.axes, traj.sample_period)
