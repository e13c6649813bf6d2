"""Thesis §6.5.3 / Table 6.3 / Fig 6.13: the Table 6.3 virtual 5-axis machine identified axis by axis with
LS and PSO, and the contour error predicted with the identified models (research.contour._identified_machine).

One identification and one prediction (the thesis' setup: §6.5 program, 75 mm/s, 1500 mm/s^2) are shared
by the tests (module fixture)."""

import numpy as np
import pytest

from research.contour import FIG6_13_BOUND, ContourPrediction, fig6_13, predict_contour_error
from research.contour._identified_machine import AXES
from research.drives import table_6_3_closed_loop
from research.errors import ParameterError


@pytest.fixture(scope="module")
def run():
    return fig6_13(seed=0)


def test_fig6_13_identified_models_predict_contour_error_within_10_um(run):
    """Thesis §6.5.3: "The discrepancy between the estimated and true contour errors is observed to be
    less than 10 [micron]" (eq 4.36 spiral, "tangential velocity of 75 [mm/sec] and acceleration of
    1500 [mm/sec^2]"). Both the LS and the PSO model sets must stay under that bound over the whole
    path, and the bound must not be vacuous: the true contour error itself is at least 10x the bound."""
    ident, pred = run
    assert pred.excluded == {}, pred.excluded
    assert pred.true.max() >= 10 * FIG6_13_BOUND
    for method in ("ls", "pso"):
        assert pred.discrepancy(method).max() < FIG6_13_BOUND, method


def test_x_and_y_poles_identified_closely(run):
    """Thesis §6.5.3: "As noted from the table, the X and Y poles are identified very closely". Table 6.3
    prints X 58 Hz against 55.54 (+4.4 %) and Y 90.9 Hz against 73.5 (+24 %), so "closely" in the thesis
    means within 24 %: the PSO wn and p of X and Y here must be within 25 % of the actual column."""
    ident, _ = run
    for axis in ("x", "y"):
        cols = ident[axis].columns()
        wn, _, p, _, _ = cols["actual"]
        for k, true in ((0, wn), (2, p)):
            assert abs(cols["pso"][k] / true - 1) < 0.25, (axis, k, cols["pso"][k], true)


def test_pso_loss_never_below_the_unconstrained_least_squares(run):
    """LS (eq 6.12) is the unconstrained minimizer of the eq 6.10 loss that PSO minimizes inside the
    §6.5 bounds, so no PSO estimate can have a lower loss (to rounding, 1e-9 relative); and where the LS
    estimate is stable and inside the bounds, PSO can at best equal it (independent property of the
    two solvers on the same regression)."""
    ident, _ = run
    for axis in AXES:
        ls, pso = ident[axis].ls, ident[axis].pso
        assert pso.loss >= ls.loss * (1 - 1e-9), axis


def test_every_fit_is_stable_and_simulable(run):
    """The models used for the prediction are stable eq 6.3 models with non-negative friction (a model
    that is not would be listed in ``excluded`` with the reason, never dropped silently)."""
    ident, _ = run
    for axis in AXES:
        for m in ("ls", "pso"):
            model = ident[axis].model(m)
            assert np.all(np.roots([1.0, model.a1, model.a2, model.a3]).real < 0)
            assert model.dc >= 0


def test_prediction_of_the_true_machine_has_zero_discrepancy():
    """Predicting with the true Table 6.3 models reproduces the true contour error exactly (same
    simulation path), and a model set without 5 axes raises ParameterError."""
    truth = tuple(table_6_3_closed_loop(a) for a in AXES)
    pred = predict_contour_error({"truth": truth}, feed=150.0, acceleration=3000.0)
    assert isinstance(pred, ContourPrediction)
    assert pred.discrepancy("truth").max() == 0.0
    with pytest.raises(ParameterError, match="5 axes"):
        predict_contour_error({"short": truth[:4]})


def test_unstable_or_frictionless_fit_is_refused_with_the_reason():
    """An identified model with a right-half-plane pole cannot predict a contour error: ``model`` raises
    ParameterError naming the axis and the poles (fig6_13 lists such a method under ``excluded``)."""
    from research.contour import AxisIdentification
    from research.identification import IdentifiedDrive

    coeffs = dict(a1=-10.0, a2=1e4, a3=1e5, b0=0.0, b1=0.0, b2=1e4, dc=1.0)  # s^3 - 10 s^2 + ...: unstable
    fit = IdentifiedDrive(method="ls", coefficients=coeffs, loss=0.0, loss_kind="equation error, eq 6.10",
                          wall_time_s=0.0, iterations=0, source="test")
    ai = AxisIdentification("x", table_6_3_closed_loop("x"), fit, fit)
    with pytest.raises(ParameterError, match=r"ls fit of axis 'x' has unstable poles"):
        ai.model("ls")
    with pytest.raises(ParameterError, match="method"):
        ai.model("optimistix")
