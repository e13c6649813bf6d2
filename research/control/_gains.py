"""Gain sets of the thesis' sliding-mode controllers (Sencer 2009, Tables 4.2 / 5.2 / 5.3) and the
closed-loop stability check every gain set passes before it is simulated.

Units: ``lam``, ``wn`` [rad/s]; ``Ks`` [V/(mm/s)] (Cartesian) or [V/(rad/s)] (rotary); ``Gamma``
[V/mm] or [V/rad] (per second of integrated surface: ``d_hat' = Gamma S``, eq 5.24); ``W`` [1/s]
(eq 5.22 adds ``W int eps dt`` to a position error, so W is a rate).

Stability check (:func:`check_axis_gains`, :func:`check_tip_gains`): the controller is discrete-time
(1 kHz, thesis §4.5) on a continuous plant, so the check builds the exact sampled closed loop of one
axis (or one Frenet direction) without friction or reference (homogeneous error dynamics), as the
Jacobian of one control period (JAX ``jacfwd``, exact because that map is linear), and requires every
eigenvalue inside the unit circle. A direction of the tool-tip controller is checked on its nominal
inertia ``m_F`` and zero damping (the law cancels the viscous terms axis by axis); the coupled loop is
time-varying, so this frozen-coefficient check is necessary, not sufficient (stated, not hidden).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from research.errors import ParameterError, UnstableGainsError

AXES = ("x", "y", "z", "a", "c")
DIRECTIONS = ("tangent", "normal", "binormal")


def _arr(x, n, name, owner):
    a = jnp.broadcast_to(jnp.asarray(x, dtype=jnp.float64), (n,)) if np.ndim(x) == 0 else jnp.asarray(x, dtype=jnp.float64)
    if a.shape != (n,):
        raise ParameterError(f"{owner}.{name} must have {n} entries (one per {'axis' if n != 3 else 'direction'}), "
                             f"got shape {a.shape}")
    return a


def _concrete(*xs) -> bool:
    return not any(isinstance(x, jax.core.Tracer) for x in xs)


class AxisSMC(eqx.Module):
    """SISO sliding-mode axis controller gains (thesis [35]; eq 5.23-5.27 with W = 0), one per axis.

    Surface ``S = lam e + e'`` (eq 5.23), law ``u = m (lam e' + q''_ref) + c q' + Ks S + d_hat`` (eq 5.27),
    adaptation ``d_hat(k) = d_hat(k-1) + T Gamma S(k)`` (eq 5.24, kappa = 1: no bounds, see module
    ``_loop``). The thesis tables call ``lam`` the bandwidth ``omega_n``.

    Attributes:
        lam: ``(n,)`` surface bandwidth [rad/s]; Ks: ``(n,)`` feedback gain; Gamma: ``(n,)`` adaptation gain.
    """

    lam: Array
    Ks: Array
    Gamma: Array

    def __init__(self, lam, Ks, Gamma, n: int = 5):
        self.lam, self.Ks, self.Gamma = (_arr(v, n, k, "AxisSMC") for k, v in (("lam", lam), ("Ks", Ks), ("Gamma", Gamma)))

    def __check_init__(self):
        if not _concrete(self.lam, self.Ks, self.Gamma):
            return
        for name in ("lam", "Ks", "Gamma"):
            v = np.asarray(getattr(self, name))
            if not np.all(np.isfinite(v)):
                raise ParameterError(f"AxisSMC.{name} must be finite, got {v}")


class TipGains(eqx.Module):
    """Tool-tip contour controller gains per Frenet direction (tangent, normal, binormal), eq 5.5-5.8.

    Surface ``S = e_F' + 2 zeta wn e_F + wn^2 int e_F`` (eq 5.5 with eq 5.7, ``C_D = I``).

    Attributes:
        wn: ``(3,)`` [rad/s]; zeta: ``(3,)`` damping of the surface dynamics; Ks: ``(3,)`` [V/(mm/s)];
        Gamma: ``(3,)`` [V/mm]. Table 5.3 gives wn, Ks, Gamma; it prints no zeta, so zeta = 1 (the
        surface polynomial ``(s + wn)^2``, whose double root is the bandwidth the table names) is an
        assumption of ours.
    """

    wn: Array
    zeta: Array
    Ks: Array
    Gamma: Array

    def __init__(self, wn, Ks, Gamma, zeta=1.0):
        self.wn, self.zeta, self.Ks, self.Gamma = (
            _arr(v, 3, k, "TipGains") for k, v in (("wn", wn), ("zeta", zeta), ("Ks", Ks), ("Gamma", Gamma)))


class ContourGains(eqx.Module):
    """Complete 5-axis contour controller (Fig 5.4): tool-tip controller for X, Y, Z and the
    orientation contour controller (eq 5.22-5.27) for A, C with coupling weights ``W = diag(wa, wc)``.

    Attributes:
        tip: :class:`TipGains`; rotary: :class:`AxisSMC` with 2 entries (A, C); W: ``(2,)`` [1/s] >= 0.
    """

    tip: TipGains
    rotary: AxisSMC
    W: Array

    def __init__(self, tip: TipGains, rotary: AxisSMC, W=(0.0, 0.0)):
        self.tip, self.rotary = tip, rotary
        self.W = jnp.asarray(W, dtype=jnp.float64)

    def __check_init__(self):
        if self.W.shape != (2,):
            raise ParameterError(f"ContourGains.W must be diag(wa, wc), 2 entries, got shape {self.W.shape}")
        if self.rotary.lam.shape != (2,):
            raise ParameterError(f"ContourGains.rotary must hold the A and C axes (2 entries), got {self.rotary.lam.shape}")
        if _concrete(self.W) and np.any(np.asarray(self.W) < 0):
            raise ParameterError(f"ContourGains.W must be positive semi-definite (eq 5.22, 5.39), got diag{tuple(np.asarray(self.W))}")

    def with_weights(self, wa: float, wc: float) -> "ContourGains":
        """The same controller with ``W = diag(wa, wc)`` (Fig 5.10 uses 0, 3, 4, 5)."""
        return ContourGains(self.tip, self.rotary, (wa, wc))

    def with_bandwidths(self, wn) -> "ContourGains":
        """The same controller with tip bandwidths ``wn = (tangent, normal, binormal)`` (Table 5.5)."""
        return ContourGains(TipGains(wn, self.tip.Ks, self.tip.Gamma, self.tip.zeta), self.rotary, self.W)


#: Thesis Table 4.2 = Table 5.2: SISO SMC of X, Y, Z, A, C ("omega_n" 200 200 180 150 200 rad/s,
#: Ks 7 5 5 0.5 1 V/(mm or rad)/s, Gamma 25 30 15 3 3 V/(mm or rad)).
def table_5_2() -> AxisSMC:
    """SISO sliding-mode gains of thesis Table 5.2 (identical to Table 4.2)."""
    return AxisSMC(lam=[200.0, 200.0, 180.0, 150.0, 200.0], Ks=[7.0, 5.0, 5.0, 0.5, 1.0], Gamma=[25.0, 30.0, 15.0, 3.0, 3.0])


def table_5_3(zeta: float = 1.0) -> ContourGains:
    """Contour controller gains of thesis Table 5.3: tangent / normal / binormal wn 100 230 230 rad/s,
    Ks 2 4 4 V/(mm/s), Gamma 10 20 20 V/mm; A, C: 150, 200 rad/s, Ks 0.5, 1, Gamma 3, 3; W = diag(0, 0).
    ``zeta`` is not in the table (see :class:`TipGains`)."""
    return ContourGains(TipGains([100.0, 230.0, 230.0], [2.0, 4.0, 4.0], [10.0, 20.0, 20.0], zeta),
                        AxisSMC([150.0, 200.0], [0.5, 1.0], [3.0, 3.0], n=2), (0.0, 0.0))


# --- discrete-time closed loop of one axis / direction ---------------------------------------------------

def plant_step_matrices(m, c, T):
    """Exact zero-order-hold discretization of ``m q'' + c q' = u`` (eq 4.11) over ``T`` [s].

    Args:
        m: inertia [V s^2/mm]; c: damping [V s/mm] (any shapes, broadcast); T: period [s].
    Returns:
        ``(Ad, Bd)`` of shapes ``(..., 2, 2)``, ``(..., 2)``: ``[q, q']_{k+1} = Ad [q, q']_k + Bd u_k``,
        from ``expm`` of the augmented matrix (``jax.scipy.linalg.expm``, differentiable in m, c).
    """
    m, c = jnp.broadcast_arrays(jnp.asarray(m, dtype=jnp.float64), jnp.asarray(c, dtype=jnp.float64))

    def one(mi, ci):
        M = jnp.array([[0.0, 1.0, 0.0], [0.0, -ci / mi, 1.0 / mi], [0.0, 0.0, 0.0]]) * T
        E = jax.scipy.linalg.expm(M)
        return E[:2, :2], E[:2, 2]

    f = one
    for _ in range(m.ndim):
        f = jax.vmap(f)
    return f(m, c)


def _axis_map(m, c, lam, Ks, Gamma, T, d=0.0):
    """One period of a PD-surface SMC axis with zero reference and a constant disturbance ``d`` [V]
    at the amplifier input (eq 4.11): state ``[q, q', d_hat]`` -> next (linear; homogeneous for d = 0)."""
    Ad, Bd = plant_step_matrices(m, c, T)

    def step(z):
        q, v, dh = z
        e, de = -q, -v
        S = lam * e + de
        dh = dh + T * Gamma * S
        u = m * lam * de + c * v + Ks * S + dh
        x = Ad @ jnp.array([q, v]) + Bd * (u - d)
        return jnp.array([x[0], x[1], dh])
    return step


def _tip_map(m, wn, zeta, Ks, Gamma, T):
    """One period of a PID-surface direction of the tip controller, zero reference, no damping:
    state ``[p, p', E, delta_hat]`` -> next."""
    Ad, Bd = plant_step_matrices(m, 0.0, T)

    def step(z):
        p, v, E, dh = z
        e, de = -p, -v
        E = E + T * e
        S = de + 2 * zeta * wn * e + wn**2 * E
        dh = dh + T * Gamma * S
        u = m * (2 * zeta * wn * de + wn**2 * e) + Ks * S + dh
        x = Ad @ jnp.array([p, v]) + Bd * u
        return jnp.array([x[0], x[1], E, dh])
    return step


def closed_loop_eigenvalues(step, n_states: int) -> np.ndarray:
    """Eigenvalues of the linear one-period map ``step`` (its Jacobian at 0)."""
    A = np.asarray(jax.jacfwd(step)(jnp.zeros(n_states)))
    return np.linalg.eigvals(A)


def _require_stable(eigs, where, T, what):
    k = int(np.argmax(np.abs(eigs)))
    z = complex(eigs[k])
    if not np.all(np.isfinite(eigs)) or abs(z) >= 1.0:
        s = np.log(z) / T if z != 0 else complex("nan")
        raise UnstableGainsError(
            f"{what} for {where!r} is unstable at T = {T * 1e3:g} ms: discrete closed-loop eigenvalue "
            f"z = {z.real:.6g}{z.imag:+.6g}j, |z| = {abs(z):.6g} >= 1 (s = log(z)/T = {s.real:.4g}{s.imag:+.4g}j rad/s)",
            where=where, eigenvalue=z)


def check_axis_gains(gains: AxisSMC, m, c, T: float, names=AXES) -> None:
    """Raise :class:`UnstableGainsError` unless every axis' sampled SMC loop is stable.

    Args:
        gains: the axes' gains; m, c: ``(n,)`` plant inertia and damping (eq 4.11); T: control period [s];
        names: axis names for the message.
    Raises:
        ParameterError: mismatched axis counts or non-positive lam / Ks, negative Gamma.
        UnstableGainsError: an eigenvalue of the sampled loop has ``|z| >= 1``.
    """
    m, c = np.atleast_1d(np.asarray(m, float)), np.atleast_1d(np.asarray(c, float))
    n = gains.lam.shape[0]
    if not (m.shape == c.shape == (n,)) or len(names) != n:
        raise ParameterError(f"mismatched axis counts: {n} gain entries, {m.shape} inertias, {c.shape} dampings, "
                             f"{len(names)} axis names")
    for i, name in enumerate(names):
        lam, Ks, G = (float(np.asarray(getattr(gains, k))[i]) for k in ("lam", "Ks", "Gamma"))
        if not (lam > 0 and Ks > 0 and G >= 0):
            raise ParameterError(f"axis {name!r}: need lam > 0, Ks > 0, Gamma >= 0 (eq 5.23-5.26); got "
                                 f"lam = {lam}, Ks = {Ks}, Gamma = {G}")
        _require_stable(closed_loop_eigenvalues(_axis_map(m[i], c[i], lam, Ks, G, T), 3), name, T, "SMC axis loop")


def check_tip_gains(gains: TipGains, m_F, T: float) -> None:
    """As :func:`check_axis_gains` for the three Frenet directions of the tool-tip controller on their
    nominal inertias ``m_F`` ``(3,)`` (frozen-coefficient check; see the module docstring)."""
    m_F = np.atleast_1d(np.asarray(m_F, float))
    if m_F.shape != (3,):
        raise ParameterError(f"m_F must hold the tangent, normal, binormal inertias (3 entries), got {m_F.shape}")
    for i, name in enumerate(DIRECTIONS):
        wn, z, Ks, G = (float(np.asarray(getattr(gains, k))[i]) for k in ("wn", "zeta", "Ks", "Gamma"))
        if not (wn > 0 and z > 0 and Ks > 0 and G >= 0):
            raise ParameterError(f"tip direction {name!r}: need wn > 0, zeta > 0, Ks > 0, Gamma >= 0 (eq 5.7); "
                                 f"got wn = {wn}, zeta = {z}, Ks = {Ks}, Gamma = {G}")
        _require_stable(closed_loop_eigenvalues(_tip_map(m_F[i], wn, z, Ks, G, T), 4), name, T, "tool-tip SMC direction")
