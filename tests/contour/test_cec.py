"""CEC mirror compensation: Prévost 2012 Applications 1 and 2 with the paper's single mirror pass,
the two extensions (iterated mirror, Newton model inversion), the limit check and non-convergence.

The paper's drive and CNC are unknown; the stand-ins are in ``research/contour/_prevost.py``.
Expected values come from the paper's text (quoted) or from derivations, never from earlier runs.
"""

import numpy as np
import pytest
from scipy.signal import find_peaks

from research.contour import (
    EXTENSIONS,
    PAPER_METHOD,
    PREVOST_TS,
    execution_errors,
    intersample_response,
    contour_error,
    mirror_compensation,
    mirror_passes,
    mirror_single_pass,
    prevost2012_application1,
    prevost2012_application2,
    simulate_setpoint,
    smoothed_corner_case,
)
from research.errors import ConvergenceError, InfeasibleProblem, ParameterError
from research.limits import AxisLimits


@pytest.fixture(scope="module")
def app1():
    return prevost2012_application1()


def test_application1_before(app1):
    """Prévost §4.1 / Fig 5: "The algebraic sum of e1 and e2 coincides with eT" (first order in the
    errors: to 2 um here) and "maximal errors can reach 70 µm before compensation" (a model
    prediction here, set by the stand-in CNC and drive: 77 um with 24/12 ms, 47 um with 12/6 ms,
    196 um with 48/24 ms; only the order of magnitude is asserted)."""
    assert app1.setpoint.sample_period == PREVOST_TS == 0.006  # "T_sampling = 6ms" (§3)
    ex = execution_errors(app1.cam_path, app1.setpoint, simulate_setpoint(app1.setpoint, app1.drive))
    assert 0.01 < ex.max_abs()["eT"] < 0.3
    assert np.max(np.abs(ex.e1 + ex.e2 - ex.eT)) < 2e-3


def test_application1_single_pass(app1):
    """The paper's method, one mirror pass (eq 4): "maximal errors can reach 70 µm before
    compensation and fall down to 2 µm (5 µm in the critical zones of axis inversions)", a ratio
    of 14-35. Asserted: at least 10x smaller after one pass, at the samples and between them (6x
    finer simulation of the same cubic hold); "errors e2 ... are the same after and before
    compensation" (max |e2| within 10 %); "the error distribution [of e1] becomes symmetrical about
    the feed drive errors" (|e1 + e2| small against |e2|); "the maximum simulated current and
    jerks after compensation ... are very close to those before" (within the 5 % check).
    Measured: 77.0 -> 3.40 um (x23)."""
    r = mirror_single_pass(app1.problem, limits=app1.limits, control_limit=app1.control_limit)
    assert r.method == PAPER_METHOD and r.history == (r.after.max,)
    assert r.after.max < r.before.max / 10
    fine = intersample_response(app1.problem, r.correction, 6)
    fine0 = intersample_response(app1.problem, np.zeros_like(r.correction), 6)
    assert contour_error(app1.cam_path, fine).max < contour_error(app1.cam_path, fine0).max / 10
    before = execution_errors(app1.cam_path, app1.setpoint, simulate_setpoint(app1.setpoint, app1.drive))
    ex = execution_errors(app1.cam_path, r.setpoint, r.response)
    assert ex.max_abs()["e2"] == pytest.approx(before.max_abs()["e2"], rel=0.1)
    assert np.max(np.abs(ex.e1 + ex.e2)) < 0.25 * ex.max_abs()["e2"]
    assert r.limits is not None and r.limits.ok, r.limits.summary()


def test_application1_single_pass_across_standins():
    """The same >= 10x reduction with the stand-in CNC's filters halved (12/6 ms): the paper's
    result does not hang on the 24/12 ms choice (measured 47.3 -> 2.41 um; 48/24 ms, not run here:
    196 -> 8.6 um)."""
    c = prevost2012_application1((0.012, 0.006))
    r = mirror_single_pass(c.problem)
    assert r.after.max < r.before.max / 10


def test_application1_error_peaks_against_axis_reversals(app1):
    """Prévost: "Peaks appearing at abscissas 100 and 175 mm exactly correspond to axis direction
    inversions". On the paper's own B-spline the reversals are at s = 100.2 mm (Y) and 189.7 mm (X)
    (computed here from the curve; the paper's 175 is 15 mm off its own curve). With the stand-in
    drive (friction compensated in the Table 6.1 cascade) the peaks of |eT| are not at the
    reversals but within 3 mm past the curvature maxima (84.8 and 196.2 mm; contour error of a
    lagging servo grows with curvature): a finding against the paper, not a reproduction."""
    cam = app1.cam_path
    u = np.linspace(*cam.domain, 200001)
    s = cam.arc_length(u)
    d1 = cam(u, 1)
    reversals = [s[np.nonzero(np.diff(np.sign(d1[:, ax])))[0]] for ax in (0, 1)]
    rev = np.concatenate([r[(r > 1.0) & (r < cam.length - 1.0)] for r in reversals])
    np.testing.assert_allclose(np.sort(rev), [100.17, 189.66], atol=0.05)
    k, _ = find_peaks(cam.curvature(u))
    resp = simulate_setpoint(app1.setpoint, app1.drive)
    eT = np.abs(execution_errors(cam, app1.setpoint, resp).eT)
    sa = cam.arc_length(cam.project(np.asarray(resp.position))[1])
    p, _ = find_peaks(eT, prominence=0.3 * eT.max())
    big = np.sort(sa[p][np.argsort(eT[p])[-2:]])  # the two largest peaks
    curv = np.sort(s[k][np.argsort(cam.curvature(u)[k])[-2:]])
    assert np.all((big - curv > 0) & (big - curv < 3.0))
    assert np.all(np.abs(big - np.sort(rev)) > 5.0)


@pytest.fixture(scope="module")
def app1_extensions(app1):
    kw = dict(tolerance=2e-3, limits=app1.limits, control_limit=app1.control_limit)
    return {m: mirror_compensation(app1.problem, method=m, **kw) for m in ("fixed_point", "newton")}


@pytest.mark.parametrize("method", ["fixed_point", "newton"])
def test_application1_extensions_reach_2_um(app1, app1_extensions, method):
    """Extensions (not in the paper): iterating the mirror, or Newton's model inversion, reach the
    paper's 2 um everywhere, between the samples too, within the limits."""
    assert method in EXTENSIONS
    r = app1_extensions[method]
    assert r.converged and r.after.max <= 2e-3
    assert contour_error(app1.cam_path, intersample_response(app1.problem, r.correction, 6)).max <= 2e-3
    assert r.limits is not None and r.limits.ok, r.limits.summary()
    assert r.loop_discrepancy < 1e-5


def test_newton_needs_no_more_simulations_and_gets_closer(app1_extensions):
    """Newton's iterates converge quadratically, the mirror's linearly (rate |1 - G|): Newton lands
    far below the tolerance with no more primal simulations."""
    fp, nt = app1_extensions["fixed_point"], app1_extensions["newton"]
    assert nt.simulations <= fp.simulations and nt.jacobians == nt.steps and fp.jacobians == 0
    assert nt.after.max < 0.1 * fp.after.max


def test_fixed_point_reports_non_convergence_with_residual(app1):
    with pytest.raises(ConvergenceError, match="did not converge") as info:
        mirror_compensation(app1.problem, method="fixed_point", tolerance=0.1e-3, max_steps=2)
    assert info.value.residual > 0.1e-3 and info.value.steps == 2
    assert info.value.residual == info.value.result.after.max  # the reported residual is the exact error
    assert info.value.result is not None and not info.value.result.converged


def test_refuse_violating_setpoint(app1):
    tight = AxisLimits.uniform(2, 150.0, 1e4, 1e7)  # feed 166.7 mm/s > 150 mm/s
    with pytest.raises(InfeasibleProblem, match="velocity on x"):
        mirror_passes(app1.problem, 1, limits=tight, on_violation="refuse")


def test_bad_arguments(app1):
    with pytest.raises(ParameterError, match="method"):
        mirror_compensation(app1.problem, method="gauss")
    with pytest.raises(ParameterError, match="tolerance"):
        mirror_compensation(app1.problem, tolerance=-1.0)
    with pytest.raises(ParameterError, match="on_violation"):
        mirror_compensation(app1.problem, on_violation="ignore")


@pytest.fixture(scope="module")
def app2():
    return prevost2012_application2()


def test_application2_sharp_corner(app2):
    """Prévost §4.2: "The global deviation e_T is reduced by twice but is not null" after the CEC
    algorithm "is directly applied" (one pass). Asserted: one pass reduces eT, and leaves more than
    30 % of it. The halving is a MISS with the stand-in CNC (measured 115.6 -> 83.7 um, x0.72: its
    24 ms filter corners at about 7000 mm/s^2, so the servo error e2 dominates, where the mirror
    rule gains least). The rounding: eq 14 puts the trajectory ``eps`` from the vertex on the
    bisector, hence ``eps / sqrt(2)`` = 3.54 um from the lines (3 %: the closest sample to the
    vertex); the paper's e1 is 17 um. The corrected setpoint's kink costs effort: flagged."""
    eps = 0.005
    assert app2.setpoint.sample_period == 0.006
    fine_e1 = contour_error(app2.cam_path, app2.setpoint.resample(1e-4)).max
    assert fine_e1 == pytest.approx(eps / np.sqrt(2), rel=0.03)
    r = mirror_single_pass(app2.problem, limits=app2.limits, control_limit=app2.control_limit)
    assert 0.3 * r.before.max < r.after.max < r.before.max
    assert not r.limits.ok


def test_application2_iteration_does_not_converge(app2):
    with pytest.raises(ConvergenceError) as info:
        mirror_compensation(app2.problem, method="fixed_point", tolerance=2e-3, max_steps=4)
    assert info.value.residual > 5e-3


def test_tangent_continuous_target_with_q_filter(app2):
    """Beyond the paper (its suggestion for §4.2 taken further): the C2 setpoint curve as the target
    and a 3-sample (18 ms) Q-filter on the iterated mirror. Each pass lowers eT (no stall), and the
    result beats the single pass on the sharp corner."""
    single = mirror_single_pass(app2.problem)
    smooth = smoothed_corner_case(app2)
    r = mirror_passes(smooth.problem, 4, smoothing=3)
    assert np.all(np.diff(r.history) < 0)
    assert r.history[-1] < single.after.max
