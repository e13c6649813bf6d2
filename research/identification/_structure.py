"""Closed-loop model structures of a feed-drive axis: how many poles, which numerator, which disturbance path.

Every structure is a linear closed loop from the reference ``x_r`` to the position ``x`` with unity DC gain
(an axis that holds a commanded position reaches it), plus a disturbance ``w`` [mm/s^2] (Coulomb friction
``d_c sign(x')`` of thesis eq 6.2 and, optionally, a constant offset force) entering where the plant
integrates acceleration::

    D(s) x = N(s) x_r - s^k w,   D(s) = s^n + d_{n-1} s^{n-1} + ... + d_0,   N(s) = b_m s^m + ... + b_1 s + d_0

* ``k = 1`` for a loop with integral action (P-PI cascade, PID): the thesis' eq 6.3 is ``n = 3, m = 3, k = 1``
  (``G_dist = s / D``, Fig 6.2);
* ``k = 0`` for a loop without integrator, e.g. the cascaded P position / P velocity loop of the EMPS
  benchmark: ``n = 2, m = 2, k = 0`` (``G_dist = 1 / D``; the steady tracking error then carries the friction).

The poles are parametrized as complex pairs ``s^2 + 2 zeta wn s + wn^2`` (``zeta > 1``: two real poles, as the
thesis' PSO allows) and, for odd ``n``, one real pole ``s + p``; with ``wn, p > 0`` and ``zeta > 0`` every
parameter value is a stable model, so bounds on them are stability bounds (thesis eq 6.13-6.14 generalized).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from research.errors import ParameterError

HZ = 2 * np.pi


@dataclasses.dataclass(frozen=True)
class ModelStructure:
    """One closed-loop structure (module docstring).

    Attributes:
        name: label used in reports and configs.
        n_poles: ``n``, the order of ``D(s)`` (>= 2).
        n_zeros: ``m``, the degree of ``N(s)`` (1 <= m <= n); ``N(0) = D(0)`` fixes its constant term.
        integrator: the loop has integral action (disturbance path ``s / D``) or not (``1 / D``).
        offset: also fit a constant disturbance (gravity, cable force, amplifier offset) [mm/s^2]. Only for loops
            without integrator: with integral action its response ``s/D 1`` is a decaying transient, the same
            as an initial state, so it is not identifiable (refused).
        friction: fit the Coulomb friction ``d_c sign(x')`` of eq 6.2 [mm/s^2].
        force: a measured external force (cutting force, a benchmark's force pulses) enters the disturbance
            path, ``+ s^k/D (g f)``, with a fitted gain ``force_gain`` [mm/s^2 per unit of f] (eq 6.1's
            disturbance transfer function; the force must then be given to the fit and the simulation).
    """

    name: str
    n_poles: int
    n_zeros: int
    integrator: bool
    offset: bool = False
    friction: bool = True
    force: bool = False

    def __post_init__(self):
        if not (isinstance(self.n_poles, int) and 2 <= self.n_poles <= 8):
            raise ParameterError(f"ModelStructure {self.name!r}: n_poles must be an int in [2, 8], got {self.n_poles!r}")
        if not (isinstance(self.n_zeros, int) and 1 <= self.n_zeros <= self.n_poles):
            raise ParameterError(f"ModelStructure {self.name!r}: n_zeros must be an int in [1, n_poles = {self.n_poles}], "
                                 f"got {self.n_zeros!r}")
        if self.offset and self.integrator:
            raise ParameterError(f"ModelStructure {self.name!r}: a constant offset is rejected by a loop with integral "
                                 "action (its response is a transient, indistinguishable from the initial state); "
                                 "set offset=False or integrator=False")
        if self.n_poles - int(self.integrator) < 2:
            raise ParameterError(f"ModelStructure {self.name!r}: the disturbance path s^k/D needs relative degree >= 2 "
                                 f"(n_poles - integrator >= 2), got n_poles = {self.n_poles}")

    @property
    def n_pairs(self) -> int:
        return self.n_poles // 2

    @property
    def has_real_pole(self) -> bool:
        return self.n_poles % 2 == 1

    @property
    def pole_names(self) -> tuple[str, ...]:
        """Names of the pole parameters in order: ``wn1, zeta1, [wn2, zeta2, ...], [p]`` (rad/s, -, rad/s)."""
        names = []
        for i in range(self.n_pairs):
            sfx = "" if self.n_pairs == 1 else str(i + 1)
            names += [f"wn{sfx}", f"zeta{sfx}"]
        return tuple(names + (["p"] if self.has_real_pole else []))

    @property
    def linear_names(self) -> tuple[str, ...]:
        """Names of the parameters the output is linear in: ``b1 .. bm`` (coefficient of ``s^i`` in ``N``),
        then ``dc`` and ``offset`` when fitted [mm/s^2]."""
        return (tuple(f"b{i}" for i in range(1, self.n_zeros + 1)) + (("dc",) if self.friction else ())
                + (("offset",) if self.offset else ()) + (("force_gain",) if self.force else ()))

    @property
    def n_parameters(self) -> int:
        """Free parameters (poles, numerator, friction, offset), initial state not counted."""
        return len(self.pole_names) + len(self.linear_names)

    def default_bounds(self, sample_period: float) -> tuple[np.ndarray, np.ndarray]:
        """Stability bounds of the pole parameters: frequencies in [0.2 Hz, 0.45 / Ts] (thesis §6.5 uses
        0.2-500 Hz at Ts = 1 ms; 0.45/Ts keeps the poles below Nyquist), ``zeta`` in [0.05, 5]."""
        lo, hi = [], []
        fmax = 0.45 / sample_period * HZ
        for _ in range(self.n_pairs):
            lo += [0.2 * HZ, 0.05]
            hi += [fmax, 5.0]
        if self.has_real_pole:
            lo.append(0.2 * HZ)
            hi.append(fmax)
        return np.array(lo), np.array(hi)

    def poles(self, sigma) -> np.ndarray:
        """Continuous poles [rad/s] of the pole parameters ``sigma`` (order :attr:`pole_names`)."""
        sigma = np.asarray(sigma, dtype=np.float64)
        out = []
        for i in range(self.n_pairs):
            wn, z = sigma[2 * i], sigma[2 * i + 1]
            out += list(np.roots([1.0, 2 * z * wn, wn * wn]))
        if self.has_real_pole:
            out.append(-sigma[-1])
        return np.array(out, dtype=complex)

    def denominator(self, sigma) -> np.ndarray:
        """``D(s)`` coefficients, descending powers (leading 1), from the pole parameters."""
        sigma = np.asarray(sigma, dtype=np.float64)
        d = np.array([1.0])
        for i in range(self.n_pairs):
            wn, z = sigma[2 * i], sigma[2 * i + 1]
            d = np.polymul(d, [1.0, 2 * z * wn, wn * wn])
        if self.has_real_pole:
            d = np.polymul(d, [1.0, sigma[-1]])
        return d

    def numerator(self, sigma, b) -> np.ndarray:
        """``N(s)`` coefficients, descending powers, length ``n + 1``: ``b = [b1 .. bm]`` and ``N(0) = D(0)``."""
        d = self.denominator(sigma)
        num = np.zeros(self.n_poles + 1)
        num[-1] = d[-1]
        for i, bi in enumerate(np.asarray(b, dtype=np.float64), start=1):
            num[-1 - i] = bi
        return num

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)


#: cascaded P position / P velocity loop (no integrator), e.g. the EMPS benchmark axis
PP2 = ModelStructure("pp2", 2, 2, integrator=False, offset=True)
#: the thesis' general model eq 6.3: 3 poles, 3 zeros, integral action, Coulomb friction
EQ_6_3 = ModelStructure("eq6.3", 3, 3, integrator=True)
#: higher orders: a P/P loop with one more pole pair (velocity-loop lag or a resonance) and no integrator
PP4 = ModelStructure("pp4", 4, 4, integrator=False, offset=True)
#: an integral-action loop with an extra pole pair (eq 6.3 plus a mode)
PI5 = ModelStructure("pi5", 5, 5, integrator=True)

STRUCTURES = {s.name: s for s in (PP2, EQ_6_3, PP4, PI5)}


def structure(name_or_structure) -> ModelStructure:
    """A :class:`ModelStructure` by name (one of :data:`STRUCTURES`) or itself."""
    if isinstance(name_or_structure, ModelStructure):
        return name_or_structure
    try:
        return STRUCTURES[name_or_structure]
    except (KeyError, TypeError):
        raise ParameterError(f"unknown model structure {name_or_structure!r}; expected one of {sorted(STRUCTURES)} "
                             "or a ModelStructure") from None
