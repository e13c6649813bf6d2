"""Fit reports: simulation fit %, pole/zero/damping table, stability flag, FRF against a known truth,
residuals, and a JSON result file."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np

from research.drives import frequency_response, pole_zero_report
from research.identification._compare import fit_percent
from research.identification._log import DriveLog
from research.identification._output_error import simulate_log
from research.identification._result import IdentifiedDrive


@dataclasses.dataclass(frozen=True, eq=False)
class FitReport:
    """How well an identified model simulates a log.

    Attributes:
        result: the :class:`IdentifiedDrive`.
        log: the log simulated (free run from its start on its reference).
        windows: name -> ``(start, stop)`` [s] of the parts reported separately, e.g. estimation and validation.
        simulated: ``(N,)`` simulated position [mm], or None when the model cannot be simulated (unstable or
            ``dc < 0``; ``reason`` says why).
        reason: why there is no simulation, else None.
        fits: window -> ``{"position": fit %, "tracking_error": fit %}``, both from the free-run simulation
            (position ``x`` vs ``x_sim``; tracking error ``x_r - x`` vs ``x_r - x_sim``).
        rms_error_um: window -> RMS of ``x - x_sim`` [um].
        truth: optional true model (virtual drives) for the FRF comparison.
    """

    result: IdentifiedDrive
    log: DriveLog
    windows: dict
    simulated: np.ndarray | None
    reason: str | None
    fits: dict
    rms_error_um: dict
    truth: object | None = None

    @property
    def stable(self) -> bool:
        return self.result.stable

    def pole_zero_table(self) -> str:
        """Poles, zeros, frequency [Hz] and damping (thesis Table 6.3 layout) plus the stability flag."""
        c = self.result.coefficients
        wn, z, p = self.result.pole_parameters()
        rows = [(f"{self.result.method}: wn = {wn / (2 * np.pi):.4g} Hz, zeta = {z:.4g}, p = {p / (2 * np.pi):.4g} Hz, "
                 f"dc = {c['dc']:.5g} mm/s^2 ({'stable' if self.stable else 'UNSTABLE'})")]
        for kind, roots in (("pole", self.result.poles()), ("zero", self.result.zeros())):
            for r in roots:
                w = abs(r)
                rows.append(f"  {kind} {r.real:12.5g} {r.imag:+12.5g}j rad/s  {w / (2 * np.pi):9.4g} Hz  damping {(-r.real / w if w else 1.0):7.3g}")
        return "\n".join(rows)

    def frf_error(self, frequency_hz=None) -> dict | None:
        """Largest tracking-FRF error against ``truth`` over ``frequency_hz`` [Hz] (default 0.1-100 Hz): magnitude [dB] and phase [deg];
        None without a truth, or for an unstable model or one with ``dc < 0`` (no drive model to compare)."""
        if self.truth is None or self.result.dc < 0 or not self.result.stable:
            return None
        f = np.logspace(-1, 2, 200) if frequency_hz is None else np.asarray(frequency_hz, dtype=np.float64)
        est = np.asarray(frequency_response(self.result.model(), f).tracking)
        tru = np.asarray(frequency_response(self.truth, f).tracking)
        mag = 20 * np.log10(np.abs(est) / np.abs(tru))
        ph = np.degrees(np.angle(est / tru))
        return {"f_max_hz": float(f[-1]), "max_magnitude_error_db": float(np.max(np.abs(mag))),
                "max_phase_error_deg": float(np.max(np.abs(ph)))}

    def residual(self) -> np.ndarray | None:
        """``x - x_sim`` [mm] over the whole log, or None without a simulation."""
        return None if self.simulated is None else self.log.actual - self.simulated

    def to_dict(self) -> dict:
        d = {"identification": self.result.to_dict(), "log": self.log.to_dict(), "windows_s": self.windows,
             "fit_percent": self.fits, "fit_definition": "100 (1 - ||y - y_sim|| / ||y - mean y||), free-run simulation",
             "rms_error_um": self.rms_error_um, "stable": self.stable, "no_simulation_reason": self.reason,
             "pole_zero_table": self.pole_zero_table(), "frf_vs_truth": self.frf_error()}
        if self.truth is not None:
            rep = pole_zero_report(self.truth)
            d["truth"] = {"wn_hz": rep.natural_frequency_hz, "zeta": rep.damping, "p_hz": rep.real_pole_hz,
                          "dc": float(self.truth.closed_loop_model().dc)}
        return d

    def write_json(self, path) -> Path:
        """Write :meth:`to_dict` as JSON; returns the path."""
        path = Path(path)
        path.write_text(json.dumps(self.to_dict(), indent=2, default=_json_default))
        return path


def _json_default(o):
    if isinstance(o, (np.floating, np.integer)):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(f"not JSON serializable: {type(o).__name__}")


def fit_report(result: IdentifiedDrive, log: DriveLog, *, windows: dict | None = None, truth=None) -> FitReport:
    """Simulate ``result`` on the whole ``log`` (reference only, from rest) and score it per window.

    Args:
        result: an identified model.
        log: the log [s, mm]; with ``windows`` e.g. ``{"estimation": (0, 12), "validation": (12, 15)}`` the
            model is still simulated over the whole log (so the validation part starts from the simulated
            state, not from measured data) and each window is scored on its own.
        windows: name -> ``(start, stop)`` [s]; default the whole log as ``"all"``.
        truth: the true drive model when known (virtual drives), for :meth:`FitReport.frf_error`.
    Returns:
        :class:`FitReport`.
    """
    windows = {"all": (float(log.t[0]), float(log.t[-1]) + log.sample_period)} if windows is None else dict(windows)
    sim, reason = None, None
    if not result.stable:
        reason = "unstable poles: " + ", ".join(f"{r:.4g}" for r in result.poles())
    elif result.dc < 0:
        reason = f"negative friction dc = {result.dc:.4g} mm/s^2"
    else:
        sim = simulate_log(result.model(), log)
    fits, rms = {}, {}
    for name, (a, b) in windows.items():
        k = (log.t >= a) & (log.t < b)
        if sim is None:
            fits[name], rms[name] = {"position": None, "tracking_error": None}, None
            continue
        fits[name] = {"position": fit_percent(log.actual[k], sim[k]),
                      "tracking_error": fit_percent(log.tracking_error[k], log.reference[k] - sim[k])}
        rms[name] = float(1e3 * np.sqrt(np.mean((log.actual[k] - sim[k]) ** 2)))
    return FitReport(result, log, windows, sim, reason, fits, rms, truth)
