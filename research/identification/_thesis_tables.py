"""Thesis Tables 6.1 and 6.2 as printed, checked against themselves, and the estimate columns as we obtain them.

Printed (Sencer 2009, §6.5.1, Tables 6.1 / 6.2): the "Actual", "LS Estimate" and "PSO Estimate" columns, both
as search variables ``(wn [Hz], zeta, p [Hz])`` and as eq 6.3 coefficients. The coefficients determine the
search variables through eq 6.13, which gives an internal check of every column:

* Table 6.1: every column is consistent (LS 31.35 Hz / 0.394 / 11.40 Hz from its coefficients, printed
  31.3 / 0.39 / 11.4).
* Table 6.2 LS prints ``a3 = 521019.0346``: with it the real pole is at 0.65 Hz, not the printed 7.63 Hz;
  ``a3 = 5210190.346`` (the decimal point one place right) gives 52.55 Hz / 0.6243 / 7.61 Hz, the printed
  52.53 / 0.62433 / 7.63. The printed value is a typo (:func:`check_table_6_2_a3_typo`).

Obtained: :func:`obtained_estimates` runs the thesis-faithful LS (eq 6.9 as printed) and PSO (§6.4, thesis
settings) and the default simulation-error fit on the §6.5 program through the Table 6.1 / 6.2 "Actual" drive.
The drive's eq 6.3 friction is not printed in eq 6.3 units (module :mod:`research.identification._virtual`),
so it is an argument (an assumption, swept in the README table).
"""

from __future__ import annotations

import numpy as np

from research.drives import ClosedLoopModel, Encoder, table_6_1_closed_loop, table_6_2_closed_loop
from research.errors import ParameterError

HZ = 2 * np.pi

#: Table 6.1 / 6.2 as printed: column -> (search variables (wn [Hz], zeta, p [Hz]), coefficients a1, a2, a3, b0,
#: b1, b2, dc). Table 6.2 LS a3 is the printed (typo) value; see :data:`TABLE_6_2_LS_A3_CORRECTED`.
PRINTED = {
    "6.1": {
        "actual": ((30.6, 0.45, 10.8), (238.4335, 48421.5859, 2487140.30, 0.0, 117.5424, 37258.9796, 2.6815)),
        "ls": ((31.3, 0.39, 11.4), (226.9455, 49915.08, 2778133.78, -0.05340, 104.3654, 37446.2493, 585.30)),
        "pso": ((31.3, 0.39, 11.4), (226.94681, 49915.0545, 2778130.868, -0.05340, 104.366781, 37446.2295, 585.31)),
    },
    "6.2": {
        "actual": ((49.1, 0.707, 7.4), (475.31142, 111794.743, 4263669.10, 0.0, 286.861167, 76074.4037, 2.6815)),
        "ls": ((52.53, 0.62433, 7.63), (460.073072, 128718.4765, 521019.0346, -0.13066504, 273.9933732, 85069.40516,
                                        626.397)),
        "pso": ((53.1, 0.688, 7.62), (506.254774, 133200.5673, 5327596.9951, -0.1758883, 302.7291668, 88568.0002,
                                      646.906)),
    },
}
#: the Table 6.2 LS a3 that matches the printed search variables
TABLE_6_2_LS_A3_CORRECTED = 5210190.346


def pole_parameters_hz(a1, a2, a3) -> tuple[float, float, float]:
    """Eq 6.13 inverted from the roots of ``s^3 + a1 s^2 + a2 s + a3``: ``(wn [Hz], zeta, p [Hz])``."""
    return tuple(float(v) for v in _pp(a1, a2, a3))


def _pp(a1, a2, a3):
    wn, z, p = ClosedLoopModel(a1, a2, a3, 0.0, 0.0, 1.0).pole_parameters()
    return wn / HZ, z, p / HZ


def check_table_6_2_a3_typo() -> dict:
    """Pole parameters of the Table 6.2 LS column with the printed and with the corrected ``a3``."""
    a1, a2, a3 = PRINTED["6.2"]["ls"][1][:3]
    return {"printed_a3": a3, "printed": pole_parameters_hz(a1, a2, a3),
            "corrected_a3": TABLE_6_2_LS_A3_CORRECTED, "corrected": pole_parameters_hz(a1, a2, TABLE_6_2_LS_A3_CORRECTED),
            "table": PRINTED["6.2"]["ls"][0]}


def obtained_estimates(table: str, dc: float, *, seed: int = 0, encoder_resolution_mm: float = 5e-5) -> dict:
    """The estimate columns of Table 6.1 / 6.2 as this code obtains them.

    Args:
        table: ``"6.1"`` or ``"6.2"``.
        dc: eq 6.3 friction of the virtual drive [mm/s^2] (an assumption: the thesis prints 2.6815 N m).
        seed: seed of the §6.5 program (70 moves) and of the encoder.
        encoder_resolution_mm: encoder count [mm] (default 0.05 um).
    Returns:
        method -> ``(wn [Hz], zeta, p [Hz], dc [mm/s^2])`` for ``"ls_thesis"`` (eq 6.9 as printed, eq 6.12),
        ``"pso_thesis"`` (§6.4 on the same regression, one swarm of the thesis' settings) and
        ``"simulation_error"``, plus ``"truth"``.
    """
    from research.identification._excitation import identification_program
    from research.identification._least_squares import least_squares
    from research.identification._projection import ProjectedProblem
    from research.identification._pso import particle_swarm
    from research.identification._regression import RegressionOptions, build_regression
    from research.identification._simulation_error import simulation_error_fit
    from research.identification._synthetic import synthetic_log

    if table not in ("6.1", "6.2"):
        raise ParameterError(f"obtained_estimates: table must be '6.1' or '6.2', got {table!r}")
    base = table_6_1_closed_loop() if table == "6.1" else table_6_2_closed_loop()
    truth = ClosedLoopModel(base.a1, base.a2, base.a3, base.b0, base.b1, base.b2, dc)
    ref = identification_program(seed).trajectory()
    log = synthetic_log(truth, ref, encoder=Encoder(encoder_resolution_mm), seed=seed + 1)
    reg = build_regression(log, RegressionOptions.thesis())
    fits = {"ls_thesis": least_squares(reg), "pso_thesis": particle_swarm(ProjectedProblem.from_regression(reg), seed=seed),
            "simulation_error": simulation_error_fit(log, "eq6.3")}
    out = {}
    for k, f in fits.items():
        wn, z, p = f.pole_parameters()
        out[k] = (wn / HZ, z, p / HZ, f.dc)
    wn, z, p = truth.pole_parameters()
    out["truth"] = (wn / HZ, z, p / HZ, float(dc))
    return out
