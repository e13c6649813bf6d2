"""Physical model identification from reference, position and control voltage with a known controller:
the inverse-dynamics least squares of the EMPS benchmark's reference model (Janot, Gautier, Brunot 2019).

Rigid axis with viscous and Coulomb friction and a constant offset (eq 6.2 generalized)::

    M x'' + Fv x' + Fc sign(x') + F0 = gtau u          [N; x in m, u in V]

is linear in ``(M, Fv, Fc, F0)``. Positions and force are low-passed by the same zero-phase Butterworth
filter before ``x'``, ``x''`` are formed by central differences (the usual "parallel filtering": one
filter on both sides keeps the linear relation exact while it removes the noise that differentiating
would amplify); the friction column is ``H[sign(x')]``, the same filter ``H`` applied to the sign of the
filtered velocity (filtering only the position and force and not the sign trades viscous against Coulomb
friction: 24 % on Fv in the test's simulated loop).

In the known cascaded P/P loop ``u = kv (kp (x_r - x) - x')`` the model closes to the ``pp2`` structure
(:data:`research.identification.PP2`) with ``wn^2 = gtau kv kp / M``, ``2 zeta wn = (gtau kv + Fv) / M``,
no feed-forward zeros (``b1 = b2 = 0``), friction ``dc = Fc/M`` and offset ``F0/M`` [mm/s^2], so it is
simulated exactly like the closed-loop fits and compared with them on the same held-out data.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy.signal import butter, sosfiltfilt

from research.errors import DriveLogError, ParameterError
from research.identification._log import DriveLog
from research.identification._structure import PP2
from research.identification._structure_fit import StructureFit


@dataclasses.dataclass(frozen=True)
class PhysicalModel:
    """Identified rigid-axis parameters (SI) and the loop they were identified in.

    Attributes:
        mass: ``M`` [kg]; viscous: ``Fv`` [N s/m]; coulomb: ``Fc`` [N]; offset: ``F0`` [N].
        std: name -> standard deviation of the inverse-dynamics least squares (white-residual assumption).
        gtau: force per control volt [N/V]; kp [1/s], kv [V s/m]: the known P/P gains.
        cutoff_hz: prefilter cutoff [Hz]; rms_force_residual: RMS equation residual [N].
    """

    mass: float
    viscous: float
    coulomb: float
    offset: float
    std: dict
    gtau: float
    kp: float
    kv: float
    cutoff_hz: float
    rms_force_residual: float

    def closed_loop(self, source: str = "physical model") -> StructureFit:
        """The model closed by ``u = kv (kp (x_r - x) - x')`` as a ``pp2`` :class:`StructureFit` (module docstring)."""
        a2 = self.gtau * self.kv * self.kp / self.mass
        a1 = (self.gtau * self.kv + self.viscous) / self.mass
        wn = float(np.sqrt(a2))
        params = {"wn": wn, "zeta": a1 / (2 * wn), "b1": 0.0, "b2": 0.0, "dc": 1e3 * self.coulomb / self.mass,
                  "offset": 1e3 * self.offset / self.mass}
        return StructureFit(PP2, params, {}, float("nan"), float("nan"), True, (), "rest", "physical", source, 0.0,
                            {"physical": dataclasses.asdict(self)})


def physical_fit(log: DriveLog, *, gtau: float, kp: float, kv: float, cutoff_hz: float = 20.0,
                 trim: int = 200) -> PhysicalModel:
    """Inverse-dynamics least squares of ``(M, Fv, Fc, F0)`` (module docstring).

    Args:
        log: log with ``control`` = the controller output voltage [V] (positions in mm, converted to m here).
        gtau: force gain [N/V]; kp, kv: the known P/P gains (EMPS: ``gtau``, ``kp``, ``kv`` in the file).
        cutoff_hz: zero-phase Butterworth (4th order) cutoff [Hz] applied to position and force.
        trim: samples dropped at each end (filter edge effects).
    Raises:
        DriveLogError: the log has no control column, or is too short for the trim.
        ParameterError: non-positive gains or cutoff above Nyquist.
    """
    if log.control is None:
        raise DriveLogError(f"{log.source}: physical identification needs the control (voltage) column; "
                            "load the log with control='<column>'")
    for name, v in (("gtau", gtau), ("kp", kp), ("kv", kv), ("cutoff_hz", cutoff_hz)):
        if not (np.isfinite(v) and v > 0):
            raise ParameterError(f"physical_fit: {name} must be a finite number > 0, got {v!r}")
    Ts = log.sample_period
    if cutoff_hz >= 0.5 / Ts:
        raise ParameterError(f"physical_fit: cutoff_hz {cutoff_hz} must be below the Nyquist frequency {0.5 / Ts} Hz")
    if log.n_samples < 2 * trim + 100:
        raise DriveLogError(f"{log.source}: {log.n_samples} samples are too few (need {2 * trim + 100})")
    sos = butter(4, cutoff_hz, fs=1.0 / Ts, output="sos")
    x = sosfiltfilt(sos, 1e-3 * log.actual)
    f = sosfiltfilt(sos, gtau * np.asarray(log.control))
    v = np.gradient(x, Ts)
    a = np.gradient(v, Ts)
    s = sosfiltfilt(sos, np.sign(v))  # the friction column is filtered like every other term
    k = slice(trim, log.n_samples - trim)
    Phi = np.column_stack([a, v, s, np.ones_like(v)])[k]
    y = f[k]
    scale = np.linalg.norm(Phi, axis=0)
    theta = np.linalg.lstsq(Phi / scale, y, rcond=None)[0] / scale
    r = y - Phi @ theta
    s2 = float(r @ r) / max(r.size - 4, 1)
    cov = np.linalg.pinv((Phi / scale).T @ (Phi / scale)) / np.outer(scale, scale) * s2
    names = ("mass", "viscous", "coulomb", "offset")
    return PhysicalModel(*(float(t) for t in theta), dict(zip(names, np.sqrt(np.abs(np.diag(cov))).tolist())),
                         float(gtau), float(kp), float(kv), float(cutoff_hz), float(np.sqrt(np.mean(r * r))))
