"""Shared, session-scoped data for the identification tests (logs are simulated once)."""

import numpy as np
import pytest

from research.drives import (
    ClosedLoopModel,
    Encoder,
    table_6_1_closed_loop,
    table_6_2_closed_loop,
)
from research.identification import THESIS_LS_DC, identification_program, synthetic_log

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
    """Thesis Table 6.1 / 6.2 drives (eq 6.3 coefficients as printed) with the friction in its eq 6.3 unit,
    dc = 585.30 mm/s^2 (see research.identification._virtual), logged by a 0.05 um encoder."""
    out = {}
    for name, base in (("6.1", table_6_1_closed_loop()), ("6.2", table_6_2_closed_loop())):
        truth = with_friction(base, THESIS_LS_DC)
        out[name] = (truth, synthetic_log(truth, reference, encoder=FINE_ENCODER, seed=1, source=f"table {name}"))
    return out


def relative_errors(result, truth):
    """|estimate / truth - 1| of (wn, zeta, p)."""
    return np.abs(np.array(result.pole_parameters()) / np.array(truth.pole_parameters()) - 1)
