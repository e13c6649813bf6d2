"""Eq 10 delays on the estimated modes and the robustness table (issue 20)."""

import numpy as np
import pytest
from scipy import signal

from research.errors import ParameterError
from research.vibration import FREQUENCY_ERRORS, TrueMode, estimate_modes, residual_ratio, robustness_table, tune_delays


def _eq9(f_hz, delays):
    """Sencer 2015 eq 9, written out independently: prod_i |sin(w T_i / 2) / (w T_i / 2)|."""
    x = np.pi * f_hz * np.asarray(delays)
    return float(np.prod(np.abs(np.sin(x) / x)))


@pytest.mark.parametrize("k", [1, 2])
def test_eq10_puts_a_zero_on_each_estimated_mode(sweep_log, k):
    """Eq 10: "T_i = k 2 pi / w_r"; checked by evaluating eq 9 at each estimated frequency."""
    modes = list(estimate_modes(sweep_log).dominant().values())
    tuned = tune_delays(modes, k=k)
    assert list(tuned.delays_s) == sorted(tuned.delays_s, reverse=True)  # longest first, as the paper's T1, T2
    for f in (m.frequency_hz for m in modes):
        assert _eq9(f, tuned.delays_s) < 1e-12
    assert tuned.delays_s[0] == pytest.approx(k / min(m.frequency_hz for m in modes), rel=1e-12)
    # §4: 148 ms and 89 ms for the 6.8 / 11.4 Hz beams (k = 1; the estimate is within 1 %, so within 1.5 ms)
    if k == 1:
        assert np.allclose(np.asarray(tuned.delays_s) * 1e3, [148.0, 89.0], atol=1.5)


def test_residual_ratio_matches_a_simulated_step():
    """Independent check of R: a unit velocity step through the chain (acceleration = the chain's impulse
    response h, built by np.convolve of the rectangles) drives the damped mode, simulated by scipy.signal.lsim.
    An unfiltered unit step leaves the envelope 1 / w_d at the end of its motion, so R = w_d times the
    envelope at the filtered motion's end T_d (read off the free vibration long after it)."""
    fn, zeta, T = 8.0, 0.03, (0.11, 0.07)
    fs = 20000.0
    wn = 2 * np.pi * fn
    wd = wn * np.sqrt(1 - zeta**2)
    mode = signal.StateSpace([[0, 1], [-wn * wn, -2 * zeta * wn]], [[0], [-1]], [[1, 0]], [[0]])
    t = np.arange(int(1.5 * fs)) / fs
    h = np.convolve(*(np.where(t < Ti, 1 / Ti, 0.0) for Ti in T))[: t.size] / fs
    _, _, x = signal.lsim(mode, h, t)
    k = t.size - 1
    envelope_end = np.hypot(x[k, 0], (x[k, 1] + zeta * wn * x[k, 0]) / wd) * np.exp(zeta * wn * (t[k] - sum(T)))
    assert wd * envelope_end == pytest.approx(float(residual_ratio(fn, zeta, T)[0]), rel=2e-3)


def test_robustness_table_properties():
    """Model prediction (the paper prints no numbers): with one filter tuned to one undamped mode, the residual
    grows with |frequency error| on each side (the main lobe of eq 9), the tuned point is a zero, and the
    damped ratio tends to eq 9 as zeta -> 0."""
    tuned = tune_delays([TrueMode("x", 20.0, 1e-9)])
    rows = robustness_table(tuned)
    assert [r["error"] for r in rows] == list(FREQUENCY_ERRORS)
    by_e = {r["error"]: r for r in rows}
    assert by_e[0.0]["eq9"] < 1e-12 and by_e[0.0]["ratio"] < 1e-6
    for side in (-1, 1):
        vals = [by_e[side * e]["eq9"] for e in (0.05, 0.10, 0.20)]
        assert vals == sorted(vals)
    for r in rows:
        assert r["ratio"] == pytest.approx(r["eq9"], abs=1e-6)
        assert r["true_hz"] == pytest.approx(20.0 * (1 + r["error"]))
    # the undamped eq 9 value of the +-20 % rows: sin(pi e) / (pi (1 + e)), written out
    assert by_e[0.2]["eq9"] == pytest.approx(np.sin(0.2 * np.pi) / (1.2 * np.pi), rel=1e-9)


def test_robustness_table_takes_a_path_residual():
    tuned = tune_delays([TrueMode("x", 20.0, 0.02), TrueMode("y", 10.0, 0.02)])
    rows = robustness_table(tuned, errors=(0.0, 0.1), residual_fn=lambda i, f: i + f)
    assert [r["path_residual"] for r in rows] == [pytest.approx(0 + 10.0), pytest.approx(0 + 11.0),
                                                  pytest.approx(1 + 20.0), pytest.approx(1 + 22.0)]


def test_bad_tuning_input():
    with pytest.raises(ParameterError):
        tune_delays([])
    with pytest.raises(ParameterError):
        tune_delays([TrueMode("x", 20.0, 0.02)], k=0)
    with pytest.raises(ParameterError):
        robustness_table(tune_delays([TrueMode("x", 20.0, 0.02)]), errors=(-1.5,))
    with pytest.raises(ParameterError):
        residual_ratio(-1.0, 0.02, [0.1])


def test_robustness_margin_matches_the_sinc_crossings():
    """One filter on one undamped mode: R(e) = sin(pi |e|) / (pi (1 + e)) (eq 9 at f (1 + e) with T = 1 / f).
    The 5 % margin's ends, solved independently with brentq, match the scan within its step (5e-4)."""
    from scipy.optimize import brentq

    from research.vibration import robustness_margin

    tuned = tune_delays([TrueMode("x", 20.0, 1e-9)])
    (row,) = robustness_margin(tuned, tolerance=0.05)
    g = lambda e: np.sin(np.pi * abs(e)) / (np.pi * (1 + e)) - 0.05  # noqa: E731
    assert row["high"] == pytest.approx(brentq(g, 1e-6, 0.4), abs=5e-4)
    assert row["low"] == pytest.approx(brentq(g, -0.4, -1e-6), abs=5e-4)
    assert row["ratio_at_estimate"] < 1e-6
    # heavy damping: even the estimate leaves more than 5 % (no margin reported)
    (row,) = robustness_margin(tune_delays([TrueMode("x", 20.0, 0.3)]), tolerance=0.05)
    assert row["ratio_at_estimate"] > 0.05 and row["low"] is None and row["high"] is None
