"""Output-error fit, reports and JSON, and the real EMPS log (skipped when ../shared/data is absent)."""

import json

import numpy as np
import pytest

from research.drives import THESIS_LINEAR_ENCODER, table_6_1_closed_loop
from research.identification import (
    EMPS_SPLIT_S,
    ASSUMED_FRICTION,
    bounded_fit,
    fit_percent,
    fit_report,
    identification_program,
    identify_emps,
    least_squares,
    load_emps,
    output_error_fit,
    synthetic_log,
)

from .conftest import EMPS, relative_errors, with_friction



def test_fit_percent_definition():
    y = np.array([0.0, 1.0, 2.0, 3.0])
    assert fit_percent(y, y) == 100.0
    assert fit_percent(y, np.full(4, y.mean())) == pytest.approx(0.0)
    assert fit_percent(y, y + 0.5) == pytest.approx(100 * (1 - 1.0 / np.sqrt(5.0)))


def test_output_error_is_not_biased_by_the_thesis_encoder(tmp_path):
    """With the thesis' 2.9 um encoder (§4.5) the equation-error fit differentiates quantized positions
    and is biased; the output-error fit of the JAX model recovers wn, zeta, p within 1 % and dc within 2 %,
    and is closer to the truth than the equation-error fit on the same log. Short program (25 moves, seed 0).

    The size of the equation-error bias is a property of one quantization realization, not a constant: on
    this program its worst relative error was 1.6 % (no dither) and 1.0-4.4 % with a 0.1 um dither (seeds
    0-3), while the output-error fit stayed at 0.5-0.8 %; four samples near the start that flip one count
    move it by 1.2 points. So the test compares the two fits rather than fixing the bias's size."""
    truth = with_friction(table_6_1_closed_loop(), ASSUMED_FRICTION)
    ref = identification_program(0, n_moves=25).trajectory()
    log = synthetic_log(truth, ref, encoder=THESIS_LINEAR_ENCODER, seed=0, source="table 6.1, 2.9 um encoder")
    vp = bounded_fit(log)
    oe = output_error_fit(log, initial=vp)
    assert np.all(relative_errors(oe, truth) < 0.01), oe.pole_parameters()
    assert np.max(relative_errors(oe, truth)) < np.max(relative_errors(vp, truth))
    assert oe.dc == pytest.approx(ASSUMED_FRICTION, rel=0.02)  # 1.1 % here (3 mm/s^2)
    assert oe.loss < oe.info["initial_loss"]
    rep = fit_report(oe, log, truth=truth)
    assert rep.fits["all"]["tracking_error"] > 99.0 and rep.stable
    frf = rep.frf_error()
    assert frf["max_magnitude_error_db"] < 0.5 and frf["max_phase_error_deg"] < 3.0  # 0.1-100 Hz
    data = json.loads(rep.write_json(tmp_path / "r.json").read_text())
    assert data["identification"]["method"] == "output_error" and data["truth"]["dc"] == pytest.approx(ASSUMED_FRICTION)
    assert "pole" in data["pole_zero_table"] and data["stable"] is True


def test_report_of_an_unstable_fit_has_no_simulation():
    log = load_emps(EMPS) if EMPS.exists() else pytest.skip(f"EMPS data not found at {EMPS}")
    est, _ = log.split(EMPS_SPLIT_S)
    ls = least_squares(est)  # the P/P loop has no integrator: LS puts the real pole slightly in the RHP
    rep = fit_report(ls, log)
    assert not ls.stable and rep.simulated is None and "unstable" in rep.reason
    assert rep.fits["all"]["position"] is None and "UNSTABLE" in rep.pole_zero_table()


@pytest.mark.skipif(not EMPS.exists(), reason=f"EMPS benchmark data not found at {EMPS} (../shared/data is absent)")
def test_emps_identify_on_12_s_validate_on_last_3_s():
    """Real ball-screw axis: fit on t < 12 s, free-run simulation scored on the held-out 12-15 s.
    Tracking-error fit (the meaningful one; position fit is ~99.99 % for any sane model):
    bounded VP 98.9 % / 98.3 %, output error 99.2 % / 99.0 % (estimation / validation)."""
    vp, oe = identify_emps(EMPS, max_steps=12)
    for rep, floor in ((vp, 98.0), (oe, 98.7)):
        assert rep.stable
        assert rep.fits["validation"]["tracking_error"] > floor
        assert rep.fits["estimation"]["tracking_error"] > floor
        assert rep.fits["validation"]["position"] > 99.9
    assert oe.fits["validation"]["tracking_error"] > vp.fits["validation"]["tracking_error"]
    # why the JAX output-error fit reports no convergence on EMPS: the P/P loop has no integrator, so the
    # eq 6.3 real pole drifts to its lower bound, which the logistic map only approaches (issue 14)
    assert oe.result.info["converged"] is False and oe.result.info["at_bound"] == ["p"]
    assert oe.log.units["actual"] == "mm" and np.ptp(oe.log.reference) > 200  # metres converted to mm
