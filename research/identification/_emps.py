"""The EMPS benchmark log (Janot, Gautier, Brunot 2019; nonlinearbenchmark.org): a real DC-motor ball-screw
axis under cascaded P/P control, reference ``qg`` -> measured ``qm`` at 1 kHz. The file stores metres and
volts; :func:`load_emps` converts positions to mm at this edge (the control voltage ``vir`` stays in V).
"""

from __future__ import annotations

from research.identification._bounded import bounded_fit
from research.identification._log import DriveLog, load_drive_log
from research.identification._output_error import output_error_fit
from research.identification._report import FitReport, fit_report
from research.identification._selection import StructureSelection, select_structure
from research.identification._structure import STRUCTURES

#: the issue's protocol: fit on t < 12 s, validate on the held-out last 3 s of the 15 s excerpt
EMPS_SPLIT_S = 12.0


def load_emps(path) -> DriveLog:
    """Read ``emps_estimation_first15s.mat`` (or any file with ``t``, ``qg``, ``qm``, ``vir`` in s, m, m, V) as a
    :class:`DriveLog` in s and mm."""
    return load_drive_log(path, time="t", reference="qg", actual="qm", control="vir", length_unit="m", control_unit="V")


def identify_emps(path, *, split_s: float = EMPS_SPLIT_S, max_steps: int = 60) -> tuple[FitReport, FitReport]:
    """Identify eq 6.3 on ``t < split_s`` and score on estimation and held-out validation windows.

    Returns:
        ``(bounded variable-projection report, output-error report)``; both models are simulated over the
        whole record from its reference only (the validation window never sees measured positions).
    """
    log = load_emps(path)
    est, _ = log.split(split_s)
    windows = {"estimation": (float(log.t[0]), split_s), "validation": (split_s, float(log.t[-1]) + 1.0)}
    vp = bounded_fit(est)
    oe = output_error_fit(est, initial=vp, max_steps=max_steps)
    return fit_report(vp, log, windows=windows), fit_report(oe, log, windows=windows)


def emps_structures(path, *, split_s: float = EMPS_SPLIT_S, structures=tuple(STRUCTURES)) -> StructureSelection:
    """Every model structure fitted by simulation error on ``t < split_s`` of the EMPS log and scored on the
    held-out rest (free run from the record's start): :func:`select_structure` on :func:`load_emps`."""
    return select_structure(load_emps(path), split_s, structures)
