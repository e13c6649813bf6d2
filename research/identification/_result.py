"""The result of one identification: the eq 6.3 coefficients and how they were obtained."""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

import numpy as np

from research.errors import ParameterError
from research.identification._regression import (
    coefficients_from_theta,
    theta_from_coefficients,
)

if TYPE_CHECKING:
    from research.drives import ClosedLoopModel

COEFFICIENTS = ("a1", "a2", "a3", "b0", "b1", "b2", "dc")


@dataclasses.dataclass(frozen=True, eq=False)
class IdentifiedDrive:
    """An identified closed-loop axis model (thesis eq 6.3).

    Attributes:
        method: ``"ls"`` (eq 6.12), ``"pso"`` (§6.4), ``"optimistix"`` (bounded variable projection) or
            ``"output_error"``.
        coefficients: ``{a1, a2, a3, b0, b1, b2, dc}`` [1/s, 1/s^2, 1/s^3, -, 1/s, 1/s^2, mm/s^2].
        loss: the minimized objective [mm^2] (see ``loss_kind``).
        loss_kind: ``"equation error, eq 6.10"`` or ``"simulation error"``.
        wall_time_s: solver wall time [s] (excludes building the regression).
        iterations: iterations (LS: 0; PSO: swarm iterations; optimistix: solver steps summed over starts).
        source: the log it came from.
        history: PSO only, ``(iterations, 4)``: ``[f_gbest, wn_gbest [rad/s], zeta_gbest, p_gbest [rad/s]]`` per
            iteration (thesis Fig 6.8).
        info: solver settings and diagnostics (JSON-serializable).
    """

    method: str
    coefficients: dict
    loss: float
    loss_kind: str
    wall_time_s: float
    iterations: int
    source: str
    history: np.ndarray | None = None
    info: dict = dataclasses.field(default_factory=dict)

    @staticmethod
    def from_theta(theta, **kwargs) -> IdentifiedDrive:
        """Build from eq 6.8 normalized parameters (de-normalized as in PSO step 7)."""
        return IdentifiedDrive(coefficients=coefficients_from_theta(theta), **kwargs)

    @property
    def theta(self) -> np.ndarray:
        """Eq 6.8 normalized parameters."""
        return theta_from_coefficients(*(self.coefficients[k] for k in COEFFICIENTS))

    @property
    def dc(self) -> float:
        """Identified Coulomb friction of eq 6.3 [mm/s^2] (may be negative for an unconstrained fit)."""
        return float(self.coefficients["dc"])

    def poles(self) -> np.ndarray:
        """Roots of ``s^3 + a1 s^2 + a2 s + a3`` [rad/s]."""
        c = self.coefficients
        return np.roots([1.0, c["a1"], c["a2"], c["a3"]])

    def zeros(self) -> np.ndarray:
        """Roots of ``b0 s^3 + b1 s^2 + b2 s + a3`` [rad/s]."""
        c = self.coefficients
        return np.roots(np.trim_zeros(np.array([c["b0"], c["b1"], c["b2"], c["a3"]]), "f"))

    @property
    def stable(self) -> bool:
        """All poles in the open left half plane."""
        return bool(np.all(self.poles().real < 0))

    def pole_parameters(self) -> tuple[float, float, float]:
        """``(wn [rad/s], zeta, p [rad/s])`` of eq 6.13 (see :meth:`ClosedLoopModel.pole_parameters`);
        for unstable fits ``zeta`` or ``p`` come out negative."""
        r = self.poles()
        cplx = r[np.abs(r.imag) > 1e-9 * np.abs(r)]
        if cplx.size:
            pair = cplx[0]
            real = r[np.abs(r.imag) <= 1e-9 * np.abs(r)].real[0]
            wn = abs(pair)
            return float(wn), float(-pair.real / wn), float(-real)
        r = np.sort(r.real)[::-1]
        p, r1, r2 = r
        wn = np.sqrt(r1 * r2) if r1 * r2 > 0 else np.nan
        return float(wn), float(-(r1 + r2) / (2 * wn)), float(-p)

    def model(self) -> ClosedLoopModel:
        """The identified :class:`ClosedLoopModel` (eq 6.3).

        Raises:
            ParameterError: poles not all in the open left half plane (listed: an unconstrained LS optimum can be
                unstable, e.g. on the EMPS log), or ``dc < 0`` (an unconstrained fit traded friction against the
                linear part; such a model cannot be simulated as Coulomb friction). The result itself stays
                readable: :attr:`stable`, :meth:`poles` and :meth:`to_dict` flag it.
        """
        c = self.coefficients
        if not self.stable:
            raise ParameterError(
                f"{self.method} fit of {self.source} is unstable: poles " + ", ".join(f"{r:.6g}" for r in self.poles())
                + " rad/s (a real part >= 0); it is a flagged result, not a drive model (use a bounded fit: "
                "bounded_fit, particle_swarm or simulation_error_fit keep the poles inside stability bounds)")
        if c["dc"] < 0:
            raise ParameterError(
                f"{self.method} fit of {self.source} has negative Coulomb friction dc = {c['dc']:.6g} mm/s^2; "
                "it is not a physical eq 6.3 model"
            )
        from research.drives import ClosedLoopModel  # imports JAX: only here, a fit is made and read without it

        return ClosedLoopModel(*(c[k] for k in COEFFICIENTS))

    def to_dict(self) -> dict:
        """JSON-serializable summary (coefficients, poles, zeros, (wn, zeta, p), loss, timing, info)."""
        wn, z, p = self.pole_parameters()
        return {
            "method": self.method, "source": self.source, "coefficients": dict(self.coefficients),
            "wn_hz": wn / (2 * np.pi), "zeta": z, "p_hz": p / (2 * np.pi), "stable": self.stable,
            "poles_rad_s": [[float(r.real), float(r.imag)] for r in self.poles()],
            "zeros_rad_s": [[float(r.real), float(r.imag)] for r in self.zeros()],
            "loss": self.loss, "loss_kind": self.loss_kind, "wall_time_s": self.wall_time_s,
            "iterations": self.iterations, "info": self.info,
        }

