"""Choosing the model structure: every candidate fitted by simulation error on the estimation part, scored by
Akaike's criterion on that part and by its free-run prediction of a held-out part (the deciding score)."""

from __future__ import annotations

import dataclasses

import numpy as np

from research.errors import ParameterError
from research.identification._compare import compare
from research.identification._log import DriveLog
from research.identification._simulation_error import simulation_error_fit
from research.identification._structure import STRUCTURES, structure as as_structure
from research.identification._structure_fit import StructureFit


def aic(fit: StructureFit, n_samples: int) -> float:
    """Akaike's information criterion ``N ln(V) + 2 d`` with ``V = ||e||^2 / N`` [mm^2] and ``d`` the free
    parameters including the initial state (Ljung 1999 eq 16.33, Gaussian residual)."""
    d = fit.structure.n_parameters + (fit.structure.n_poles if fit.initial == "estimate" else 0)
    return float(n_samples * np.log(2.0 * fit.loss / n_samples) + 2 * d)


@dataclasses.dataclass(frozen=True, eq=False)
class StructureSelection:
    """Candidates and the chosen one.

    Attributes:
        fits: name -> :class:`StructureFit` (on the estimation part).
        scores: name -> ``{"aic", "estimation": compare scores, "validation": compare scores}``.
        best: the name with the lowest held-out RMS error.
        best_aic: the name with the lowest AIC.
    """

    fits: dict
    scores: dict
    best: str
    best_aic: str

    def table(self) -> list[dict]:
        """One row per structure: parameters, AIC, held-out fit % and RMS / max error [um], converged."""
        return [{"structure": k, "n_parameters": f.structure.n_parameters, "aic": self.scores[k]["aic"],
                 "validation_tracking_fit_percent": self.scores[k]["validation"]["tracking_error_fit_percent"],
                 "validation_rms_um": self.scores[k]["validation"]["rms_um"],
                 "validation_max_um": self.scores[k]["validation"]["max_um"], "converged": f.converged}
                for k, f in self.fits.items()]


def select_structure(log: DriveLog, split_s: float, structures=tuple(STRUCTURES), **fit_kwargs) -> StructureSelection:
    """Fit each of ``structures`` on ``t < split_s`` of ``log`` and score it on ``t >= split_s``.

    The held-out part is predicted by a free-run simulation over the whole record (initial state from the
    record's first samples), so it never sees measured positions.

    Raises:
        ParameterError: the split leaves fewer than 10 % of the record on either side.
    """
    t0, t1 = float(log.t[0]), float(log.t[-1])
    if not (t0 + 0.1 * (t1 - t0) <= split_s <= t1 - 0.1 * (t1 - t0)):
        raise ParameterError(f"select_structure: split_s = {split_s} s must leave 10 % of {log.source} "
                             f"({t0:g} - {t1:g} s) on each side")
    est, _ = log.split(split_s)
    windows = {"estimation": (t0, split_s), "validation": (split_s, np.inf)}
    fits, scores = {}, {}
    for s in structures:
        st = as_structure(s)
        fit = simulation_error_fit(est, st, **fit_kwargs)
        fits[st.name] = fit
        scores[st.name] = {"aic": aic(fit, est.n_samples), **compare(fit, log, windows=windows)}
    best = min(scores, key=lambda k: scores[k]["validation"]["rms_um"])
    best_aic = min(scores, key=lambda k: scores[k]["aic"])
    return StructureSelection(fits, scores, best, best_aic)
