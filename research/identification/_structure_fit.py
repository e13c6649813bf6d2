"""The result of a simulation-error fit of a :class:`ModelStructure`: parameters, their uncertainty, the
convergence flag, and the simulation of the identified model on any log."""

from __future__ import annotations

import dataclasses

import numpy as np

from research.errors import ParameterError
from research.identification._log import DriveLog
from research.identification._simulation import Reference, consistent_signs, linear_part, responses
from research.identification._structure import HZ, ModelStructure

#: samples at the start of a log from which :meth:`StructureFit.simulate` reads the initial state ("data")
INITIAL_SAMPLES = 50


@dataclasses.dataclass(frozen=True, eq=False)
class StructureFit:
    """An identified closed-loop model of one :class:`ModelStructure`.

    Attributes:
        structure: the structure.
        parameters: name -> value: pole parameters (``wn*`` [rad/s], ``zeta*``, ``p`` [rad/s]), numerator
            ``b1 .. bm`` [1/s^(n-i) ...], ``dc`` and ``offset`` [mm/s^2].
        std: name -> standard deviation from the Gauss-Newton covariance ``s^2 (J^T J)^-1`` at the optimum
            (white-residual assumption; coloured residuals make it optimistic, see :func:`residual_analysis`).
        loss: ``0.5 ||x - x_sim||^2`` [mm^2] on the estimation log.
        rms_um: RMS simulation error on the estimation log [um].
        converged: the last optimizer pass met its tolerance (not its evaluation limit) and the friction
            signs of the final model are those the optimizer held fixed.
        at_bound: pole parameters that ended on a stability bound.
        initial: ``"estimate"`` (initial state fitted) or ``"rest"``.
        method: ``"simulation_error"``.
        source: the estimation log's source.
        wall_time_s: fit wall time [s].
        info: diagnostics (starts, passes, optimizer messages, bounds).
    """

    structure: ModelStructure
    parameters: dict
    std: dict
    loss: float
    rms_um: float
    converged: bool
    at_bound: tuple
    initial: str
    method: str
    source: str
    wall_time_s: float
    info: dict = dataclasses.field(default_factory=dict)

    @property
    def sigma(self) -> np.ndarray:
        return np.array([self.parameters[k] for k in self.structure.pole_names])

    @property
    def b(self) -> np.ndarray:
        return np.array([self.parameters[f"b{i}"] for i in range(1, self.structure.n_zeros + 1)])

    @property
    def dc(self) -> float:
        return float(self.parameters.get("dc", 0.0))

    @property
    def offset(self) -> float:
        return float(self.parameters.get("offset", 0.0))

    @property
    def force_gain(self) -> float | None:
        """Gain of the measured force input [mm/s^2 per unit], None without one."""
        return self.parameters.get("force_gain")

    def denominator(self) -> np.ndarray:
        return self.structure.denominator(self.sigma)

    def numerator(self) -> np.ndarray:
        return self.structure.numerator(self.sigma, self.b)

    def poles(self) -> np.ndarray:
        """Closed-loop poles [rad/s]; stable by construction (every parameter inside its bounds)."""
        return self.structure.poles(self.sigma)

    def zeros(self) -> np.ndarray:
        """Zeros of the tracking transfer function [rad/s]."""
        return np.roots(np.trim_zeros(self.numerator(), "f"))

    @property
    def stable(self) -> bool:
        return bool(np.all(self.poles().real < 0))

    def pole_parameters(self) -> tuple[float, float, float]:
        """``(wn, zeta, p)`` [rad/s, -, rad/s] for eq 6.3-like structures (one pair and one real pole)."""
        s = self.structure
        if s.n_pairs != 1 or not s.has_real_pole:
            raise ParameterError(f"pole_parameters: structure {s.name!r} is not one pair + one real pole; read .parameters")
        return tuple(float(v) for v in self.sigma)

    def pole_table(self) -> list[dict]:
        """One row per pole parameter: value, standard deviation, and frequency in Hz for ``wn``/``p``."""
        rows = []
        for k in self.structure.pole_names:
            v, sd = self.parameters[k], self.std.get(k, float("nan"))
            hz = not k.startswith("zeta")
            rows.append({"name": k, "value": v, "std": sd, "unit": "rad/s" if hz else "-",
                         "hz": v / HZ if hz else None, "hz_std": sd / HZ if hz else None, "at_bound": k in self.at_bound})
        return rows

    def closed_loop_model(self):
        """The eq 6.3 :class:`research.drives.ClosedLoopModel` (structures with 3 poles, integral action, no
        offset), so the drive simulator, frequency responses and CEC can use the identified axis.

        Raises:
            ParameterError: the structure is not eq 6.3 (its disturbance path or order differ).
        """
        from research.drives import ClosedLoopModel

        s = self.structure
        if not (s.n_poles == 3 and s.integrator and not s.offset):
            raise ParameterError(f"structure {s.name!r} is not eq 6.3 (3 poles, integral action, no offset); "
                                 "simulate it with StructureFit.simulate")
        d, num = self.denominator(), self.numerator()
        return ClosedLoopModel(d[1], d[2], d[3], num[0], num[1], num[2], self.dc)

    def to_identified_drive(self):
        """The eq 6.3 fit as an :class:`IdentifiedDrive` (for :func:`fit_report`, FRFs and the thesis tables)."""
        from research.identification._result import IdentifiedDrive

        m = self.closed_loop_model()
        coeffs = {k: float(getattr(m, k)) for k in ("a1", "a2", "a3", "b0", "b1", "b2", "dc")}
        return IdentifiedDrive(method=self.method, coefficients=coeffs, loss=self.loss, loss_kind="simulation error",
                               wall_time_s=self.wall_time_s, iterations=int(self.info.get("evaluations", 0)),
                               source=self.source, info={"converged": self.converged, "std": self.std,
                                                         "initial": self.initial})

    def simulate(self, log: DriveLog, *, initial: str = "data", initial_samples: int = INITIAL_SAMPLES,
                 force=None) -> np.ndarray:
        """Free-run simulation on ``log``'s reference -> ``x_sim`` ``(N,)`` [mm].

        Args:
            log: any log of the axis [s, mm].
            initial: ``"data"``: the initial state is the least-squares fit of the free responses to the first
                ``initial_samples`` measured positions (a log that starts mid-move starts the model there);
                ``"rest"``: the loop starts at rest at the first reference sample.
            initial_samples: samples used by ``"data"``.
            force: ``(N,)`` measured force, required when the structure has a force input.
        """
        if initial not in ("data", "rest"):
            raise ParameterError(f"initial must be 'data' or 'rest', got {initial!r}")
        ref = Reference.from_samples(log.reference, log.sample_period)
        R = responses(self.structure, self.sigma, ref)
        if self.structure.force and force is None:
            raise ParameterError(f"structure {self.structure.name!r} has a force input: pass force=")
        fin = (self.force_gain, force) if self.structure.force else None
        pl, vl = linear_part(self.structure, R, self.b, self.offset, None, fin)
        pos, vel, s, _ = consistent_signs(R, pl, vl, self.dc)
        if initial == "data":
            w = slice(0, min(int(initial_samples), log.n_samples))
            y = log.actual - ref.x0
            for _ in range(20):  # the initial state moves the friction signs: iterate to a consistent pair
                base = pl - self.dc * R.disturbance_position(s)
                c, *_ = np.linalg.lstsq(R.modes_pos[w], (y - base)[w], rcond=None)
                pos, _v, s_new, _n = consistent_signs(R, *linear_part(self.structure, R, self.b, self.offset, c, fin),
                                                      self.dc, s)
                if np.array_equal(s_new, s):
                    break
                s = s_new
        return pos + ref.x0

    def to_dict(self) -> dict:
        return {"method": self.method, "structure": self.structure.to_dict(), "parameters": dict(self.parameters),
                "std": dict(self.std), "loss": self.loss, "rms_um": self.rms_um, "converged": self.converged,
                "at_bound": list(self.at_bound), "initial": self.initial, "source": self.source,
                "wall_time_s": self.wall_time_s, "stable": self.stable,
                "poles_rad_s": [[float(r.real), float(r.imag)] for r in self.poles()],
                "zeros_rad_s": [[float(r.real), float(r.imag)] for r in self.zeros()],
                "pole_table": self.pole_table(), "info": self.info}

