"""Thesis Tables 6.1 / 6.2 (Sencer 2009 §6.5.1): the printed columns checked against each other (eq 6.13),
the Table 6.2 LS a3 typo, and the estimate columns as obtained here, beside the printed ones."""

import numpy as np
import pytest

from research.identification import (
    PRINTED,
    TABLE_6_2_LS_A3_CORRECTED,
    check_table_6_2_a3_typo,
    obtained_estimates,
    pole_parameters_hz,
)


@pytest.mark.parametrize("table,column", [("6.1", "actual"), ("6.1", "ls"), ("6.1", "pso"), ("6.2", "pso")])
def test_printed_coefficients_give_the_printed_search_variables(table, column):
    """Independent check from the paper alone: the roots of s^3 + a1 s^2 + a2 s + a3 of each printed column
    (eq 6.13) reproduce the printed (wn, zeta, p) within one unit of the last printed digit (Table 6.1's
    "Actual" p is printed 10.8 for 10.73 and Table 6.2's PSO zeta 0.688 for 0.6871: not plain rounding)."""
    (wn, z, p), coeffs = PRINTED[table][column]
    got = pole_parameters_hz(*coeffs[:3])
    for printed, value in zip((wn, z, p), got):
        unit = 10.0 ** -len(repr(printed).split(".")[1])
        assert abs(value - printed) <= unit + 1e-12, (printed, value)


def test_table_6_2_actual_wn_differs_from_its_coefficients():
    """Table 6.2 "Actual" prints wn = 49.1 Hz but its coefficients a1 = 475.31142, a2 = 111794.743,
    a3 = 4263669.10 give 48.25 Hz (1.8 % lower); zeta 0.707 and p 7.4 Hz agree."""
    wn, z, p = pole_parameters_hz(*PRINTED["6.2"]["actual"][1][:3])
    assert wn == pytest.approx(48.25, abs=0.01) and abs(wn / 49.1 - 1) > 0.015
    assert z == pytest.approx(0.707, abs=0.001) and p == pytest.approx(7.4, abs=0.02)


def test_table_6_2_ls_a3_is_a_typo():
    """Table 6.2 LS column prints "a3 521019.0346" with "p[Hz] 7.63": with that a3 the real pole is at
    0.65 Hz (off by 11x); 5210190.346 gives 52.55 Hz / 0.6243 / 7.61 Hz, the printed 52.53 / 0.62433 / 7.63."""
    chk = check_table_6_2_a3_typo()
    assert chk["printed"][2] < 1.0  # the printed a3 puts p near 0.65 Hz
    np.testing.assert_allclose(chk["corrected"], chk["table"], rtol=0.005)
    assert TABLE_6_2_LS_A3_CORRECTED == pytest.approx(10 * chk["printed_a3"], rel=1e-12)


def test_table_6_2_friction_ratios_differ_from_table_6_1():
    """The 218x of Table 6.1 (585.30 / 2.6815) is not repeated by Table 6.2 (LS 626.397, PSO 646.906 for the
    same 2.6815): 234x and 241x, 7-11 % more, so one rg/J cannot explain all three estimates exactly."""
    t61 = PRINTED["6.1"]["ls"][1][6] / PRINTED["6.1"]["actual"][1][6]
    ls62 = PRINTED["6.2"]["ls"][1][6] / PRINTED["6.2"]["actual"][1][6]
    pso62 = PRINTED["6.2"]["pso"][1][6] / PRINTED["6.2"]["actual"][1][6]
    assert t61 == pytest.approx(218.27, abs=0.01)
    assert ls62 / t61 - 1 > 0.06 and pso62 / t61 - 1 > 0.10


@pytest.mark.parametrize("table", ["6.1", "6.2"])
def test_obtained_estimate_columns(table):
    """The thesis-faithful LS (eq 6.9 as printed) and PSO on the Table 6.1 / 6.2 drives with friction
    2.6815 mm/s^2 (the "Actual" column read in eq 6.3 units). The thesis: "The slower pole at 10.8 [Hz] is
    estimated at 11.4 [Hz]" (Table 6.1) and "The PSO and LS estimates are almost identical" (Table 6.2).
    Obtained: p too high as printed (the rectangle-rule bias of eq 6.9, > 2.5 %), LS = PSO (the LS optimum
    lies inside the PSO bounds), but wn too *low* (the thesis prints it too high: 31.3 vs 30.6 Hz and
    52.53 vs 49.1 Hz); the simulation-error fit recovers all three within 0.1 %."""
    est = obtained_estimates(table, 2.6815)
    truth = np.array(est["truth"][:3])
    ls, pso, se = (np.array(est[k][:3]) for k in ("ls_thesis", "pso_thesis", "simulation_error"))
    assert ls[2] / truth[2] - 1 > 0.025  # p too high, as printed
    assert ls[0] < truth[0]  # wn too low: the printed LS moves the other way
    np.testing.assert_allclose(pso, ls, rtol=1e-3)
    np.testing.assert_allclose(se, truth, rtol=1e-3)
