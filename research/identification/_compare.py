"""What a user of MATLAB's ``compare`` and ``resid`` expects of an identified drive model: simulation fit %,
RMS and max error [um] per window, and residual whiteness / independence tests with confidence bounds.

Residual tests (Ljung 1999 §16.6): the normalized autocorrelation ``r_ee(tau)`` of the simulation residual
``e = x - x_sim`` for lags ``1..max_lag`` and its cross-correlation ``r_eu(tau)`` with the input for lags
``-max_lag..max_lag``, against the 99 % band ``+-2.576 / sqrt(N)`` of white, independent residuals. The
input is the reference *velocity* ``diff(x_r)/Ts`` (the position is a non-stationary ramp whose sample
correlation means nothing); a model that leaves input dynamics unexplained shows ``r_eu`` outside the band.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from research.errors import ParameterError
from research.identification._log import DriveLog
from research.identification._result import IdentifiedDrive
from research.identification._structure_fit import StructureFit

#: two-sided 99 % normal quantile of the residual tests
Z99 = 2.5758293035489


def fit_percent(y, y_hat) -> float:
    """``100 (1 - ||y - y_hat|| / ||y - mean(y)||)`` [%] (100 = perfect, 0 = as good as the mean, can be < 0)."""
    y, y_hat = np.asarray(y, dtype=np.float64), np.asarray(y_hat, dtype=np.float64)
    den = np.linalg.norm(y - y.mean())
    if den == 0:
        raise ParameterError("fit_percent: the measured signal is constant, the fit is undefined")
    return float(100.0 * (1.0 - np.linalg.norm(y - y_hat) / den))


def simulate_model(model, log: DriveLog, *, initial: str = "data", force=None) -> tuple[np.ndarray | None, str | None]:
    """``(x_sim [mm], None)``, or ``(None, reason)`` when the model cannot be simulated (unstable poles, listed,
    or negative friction). :class:`StructureFit` models start from the data (``initial``); thesis
    :class:`IdentifiedDrive` models from rest at ``x_r[0]`` (as :func:`fit_report`)."""
    if isinstance(model, StructureFit):
        return model.simulate(log, initial=initial, force=force), None
    if not isinstance(model, IdentifiedDrive):
        raise ParameterError(f"expected a StructureFit or IdentifiedDrive, got {type(model).__name__}")
    if not model.stable:
        return None, "unstable poles: " + ", ".join(f"{r:.4g}" for r in model.poles()) + " rad/s"
    if model.dc < 0:
        return None, f"negative friction dc = {model.dc:.4g} mm/s^2 (not a Coulomb friction)"
    from research.identification._output_error import simulate_log

    return simulate_log(model.model(), log), None


def _scores(log, sim, k):
    e = log.actual[k] - sim[k]
    return {"position_fit_percent": fit_percent(log.actual[k], sim[k]),
            "tracking_error_fit_percent": fit_percent(log.tracking_error[k], log.reference[k] - sim[k]),
            "rms_um": float(1e3 * np.sqrt(np.mean(e * e))), "max_um": float(1e3 * np.max(np.abs(e)))}


def compare(model, log: DriveLog, *, windows: dict | None = None, initial: str = "data", force=None) -> dict:
    """MATLAB ``compare``: free-run simulation of ``model`` on ``log``, scored per window.

    Args:
        model: :class:`StructureFit` or :class:`IdentifiedDrive`.
        log: the log [s, mm] (simulated as a whole; a held-out window is predicted from the record's start,
            it never sees measured positions).
        windows: name -> ``(start, stop)`` [s]; default the whole log as ``"all"``.
        initial: initial state of a :class:`StructureFit` (``"data"``: from the first samples, or ``"rest"``).
        force: ``(N,)`` measured force for structures with a force input.
    Returns:
        window -> ``{position_fit_percent, tracking_error_fit_percent, rms_um, max_um}``, or
        ``{"reason": ...}`` for every window when the model cannot be simulated. Fit % is
        ``100 (1 - ||y - y_sim|| / ||y - mean y||)``.
    """
    windows = {"all": (-np.inf, np.inf)} if windows is None else dict(windows)
    sim, reason = simulate_model(model, log, initial=initial, force=force)
    out = {}
    for name, (a, b) in windows.items():
        k = (log.t >= a) & (log.t < b)
        if not k.any():
            raise ParameterError(f"compare: window {name!r} [{a}, {b}) s holds no sample of {log.source} "
                                 f"({log.t[0]:g} - {log.t[-1]:g} s)")
        out[name] = {"reason": reason} if sim is None else _scores(log, sim, k)
    return out


@dataclasses.dataclass(frozen=True, eq=False)
class ResidualAnalysis:
    """MATLAB ``resid``: residual autocorrelation and input cross-correlation with 99 % bounds.

    Attributes:
        lags: ``(L,)`` lags ``1..max_lag`` of :attr:`autocorrelation` [samples].
        autocorrelation: ``r_ee(tau) / r_ee(0)``.
        cross_lags: ``(2L + 1,)`` lags ``-max_lag..max_lag``.
        cross_correlation: normalized ``r_eu(tau)`` with the reference velocity.
        bound: the 99 % band ``Z99 / sqrt(N)``.
        n_samples: residual samples ``N``.
    """

    lags: np.ndarray
    autocorrelation: np.ndarray
    cross_lags: np.ndarray
    cross_correlation: np.ndarray
    bound: float
    n_samples: int

    @property
    def white(self) -> bool:
        """All autocorrelations inside the band (no unexplained dynamics in the residual)."""
        return bool(np.all(np.abs(self.autocorrelation) <= self.bound))

    @property
    def independent(self) -> bool:
        """All input cross-correlations inside the band."""
        return bool(np.all(np.abs(self.cross_correlation) <= self.bound))

    def to_dict(self) -> dict:
        return {"bound": self.bound, "n_samples": self.n_samples, "white": self.white, "independent": self.independent,
                "max_abs_autocorrelation": float(np.max(np.abs(self.autocorrelation))),
                "max_abs_cross_correlation": float(np.max(np.abs(self.cross_correlation))),
                "fraction_autocorrelation_outside": float(np.mean(np.abs(self.autocorrelation) > self.bound)),
                "fraction_cross_correlation_outside": float(np.mean(np.abs(self.cross_correlation) > self.bound))}


def residual_analysis(model, log: DriveLog, *, max_lag: int = 50, initial: str = "data") -> ResidualAnalysis:
    """Residual tests of ``model`` on ``log`` (module docstring).

    Raises:
        ParameterError: the model cannot be simulated (the reason is given), or ``max_lag`` is not in
            ``[1, N/4]``.
    """
    sim, reason = simulate_model(model, log, initial=initial)
    if sim is None:
        raise ParameterError(f"residual_analysis: no simulation of {log.source}: {reason}")
    e = log.actual - sim
    u = np.diff(log.reference, prepend=log.reference[0]) / log.sample_period
    N = e.size
    if not (isinstance(max_lag, (int, np.integer)) and 1 <= max_lag <= N // 4):
        raise ParameterError(f"residual_analysis: max_lag must be an int in [1, N/4 = {N // 4}], got {max_lag!r}")
    e = e - e.mean()
    u = u - u.mean()
    ree0, ruu0 = float(e @ e), float(u @ u)
    if ree0 == 0:
        raise ParameterError(f"residual_analysis: the residual on {log.source} is identically zero")
    lags = np.arange(1, max_lag + 1)
    acf = np.array([e[t:] @ e[:-t] for t in lags]) / ree0
    cl = np.arange(-max_lag, max_lag + 1)
    ccf = np.array([(e[t:] @ u[:N - t]) if t >= 0 else (e[:N + t] @ u[-t:]) for t in cl]) / np.sqrt(ree0 * ruu0)
    return ResidualAnalysis(lags, acf, cl, ccf, float(Z99 / np.sqrt(N)), int(N))
