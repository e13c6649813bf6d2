"""Exact sampled simulation of a :class:`ModelStructure`, written as responses the output is linear in.

For fixed poles the simulated position of every structure is linear in the numerator coefficients, the
friction and offset amplitudes and the initial state (module :mod:`research.identification._structure`)::

    x_k = x_r,0 + d_0 S_0,k + sum_i b_i S_i,k - d_c F_k[sign(x'_.)] - offset F_k[1] + sum_m c_m phi_m,k

with ``S_i = s^i / D (x_r - x_r,0)`` (the loop starts at rest at ``x_r,0`` when ``c = 0``), ``F[u] = s^k / D u``
for a disturbance ``u`` held over each period, and ``phi_m`` the free responses (modes ``e^{lambda t}`` of the
poles) that carry an initial state read from the data. The velocity is the same sum with every response
differentiated, so the friction sign ``sign(x'_k)`` is that of the simulated velocity at the start of
each period, held over the period (zero-order hold, as in :func:`research.drives.simulate`).

Discretization (exact for the held inputs): the reference between samples is the not-a-knot cubic spline
through the logged ``x_r`` (a log carries samples only; the spline is exact for the piecewise-cubic
references of jerk-limited interpolators away from their switching instants), fed to the controllable
canonical form ``z' = A z + e_n x_r`` (``z_j = S_{j-1}``) written in time normalized by ``Ts`` (coefficients
``d_j Ts^{n-j}``, well scaled); the matrix exponential of the system augmented with the cubic's
generator (Van Loan) gives ``z_{k+1} = Ad z_k + G [q, v Ts, a Ts^2, j Ts^3]_k``. Each state is then one
FIR (all states and channels at once: ``n + 1`` small matrix products over the record) plus one IIR filter
(``scipy.signal.lfilter``), so a simulation costs about a millisecond for 10^4 samples. The free responses
are set to zero once their envelope has decayed below 1e-20 (:data:`DECAYED`). ``S_n`` and ``S_{n+1}`` follow
from the identities ``S_n = x_r - sum d_j S_j`` and ``S_{n+1} = x_r' - sum d_j S_{j+1}``.

The friction sign feeds back (the sign at sample ``k`` depends on signs before ``k`` only), so it is found by
a fixed-point iteration that is exact when it stops: signs -> simulated velocity -> signs, until no sign
changes (each pass fixes at least the first wrong sample; :func:`consistent_signs`).
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.signal import lfilter

from research.errors import ConvergenceError
from research.identification._structure import ModelStructure

#: a free response is set to zero once its envelope e^{a t} is below e^-DECAYED = 1e-20 of its start (far
#: below double rounding of the fitted positions); exp would only underflow gradually there
DECAYED = 20 * np.log(10.0)
#: passes of the friction-sign fixed point before giving up (each pass costs two IIR filters)
MAX_SIGN_PASSES = 5000


@dataclasses.dataclass(frozen=True, eq=False)
class Reference:
    """The logged reference as per-sample cubic pieces ``q + v tau + a tau^2/2 + j tau^3/6`` on ``[t_k, t_k+Ts)``.

    Attributes:
        q, v, a, j: ``(N,)`` [mm, mm/s, mm/s^2, mm/s^3], ``q = x_r - x_r,0``.
        x0: ``x_r,0`` [mm].
        sample_period: ``Ts`` [s].
    """

    q: np.ndarray
    v: np.ndarray
    a: np.ndarray
    j: np.ndarray
    x0: float
    sample_period: float

    @staticmethod
    def from_samples(x_r, sample_period: float) -> Reference:
        """Not-a-knot cubic spline through ``x_r`` [mm] sampled every ``sample_period`` [s]."""
        x_r = np.asarray(x_r, dtype=np.float64)
        Ts = float(sample_period)
        q = x_r - x_r[0]
        t = np.arange(q.size) * Ts
        c = CubicSpline(t, q).c  # (4, N-1): c0 tau^3 + c1 tau^2 + c2 tau + c3 on interval k
        last = lambda row, val: np.append(row, val)  # the last sample starts no interval: hold its slope
        v = last(c[2], c[2, -1] + 2 * c[1, -1] * Ts + 3 * c[0, -1] * Ts * Ts)
        a = last(2 * c[1], 2 * c[1, -1] + 6 * c[0, -1] * Ts)
        j = last(6 * c[0], 0.0)
        return Reference(q, v, a, j, float(x_r[0]), Ts)

    @property
    def n_samples(self) -> int:
        return int(self.q.size)

    @functools.cached_property
    def channels(self) -> np.ndarray:
        """``(4, N)`` normalized cubic channels ``[q, v Ts, a Ts^2, j Ts^3]`` of the discretization."""
        Ts = self.sample_period
        return np.vstack((self.q, self.v * Ts, self.a * Ts**2, self.j * Ts**3))

    @functools.cached_property
    def t(self) -> np.ndarray:
        """``(N,)`` sample times from 0 [s]."""
        return np.arange(self.n_samples) * self.sample_period


def _expm(M):
    """Matrix exponential by scaling and squaring of an 18-term Taylor series (``||M/2^s|| <= 1/2``: truncation
    below 1e-20 relative). ``scipy.linalg.expm`` costs ~5 ms per call for these 8 x 8 matrices, which would
    dominate a fit; this costs ~0.05 ms."""
    norm = float(np.max(np.sum(np.abs(M), axis=1)))
    s = max(0, int(np.ceil(np.log2(norm / 0.5)))) if norm > 0.5 else 0
    X = M / 2.0**s
    E = np.eye(M.shape[0])
    term = np.eye(M.shape[0])
    for k in range(1, 19):
        term = term @ X / k
        E = E + term
    for _ in range(s):
        E = E @ E
    return E


def _discretize(den, Ts):
    """Normalized-time controllable form of ``1/D``: ``(Ad, G (n, 4), Gw (n,))`` for the cubic reference
    channels ``[q, v Ts, a Ts^2, j Ts^3]`` and a zero-order-held disturbance."""
    n = den.size - 1
    dn = den[1:] * Ts ** np.arange(1, n + 1)  # d_{n-1} Ts, d_{n-2} Ts^2, ..., d_0 Ts^n
    A = np.zeros((n, n))
    A[:-1, 1:] = np.eye(n - 1)
    A[-1, :] = -dn[::-1]
    M = np.zeros((n + 5, n + 5))
    M[:n, :n] = A
    M[n - 1, n] = 1.0  # input x_r = first generator state
    M[n:n + 3, n + 1:n + 4] = np.eye(3)  # cubic generator: q' = v, v' = a, a' = j
    M[n - 1, n + 4] = 1.0  # held disturbance
    E = _expm(M)
    return E[:n, :n], E[:n, n:n + 4], E[:n, n + 4]


def _state_filters(Ad, B):
    """Numerators ``(n, n+1, k)`` (state, power of ``1/z``, input column) and the denominator of
    ``(zI - Ad)^-1 B`` for every state, by the Faddeev-LeVerrier recursion
    ``adj(zI - A) = sum_k z^(n-1-k) M_k``, ``M_0 = I``, ``M_k = A M_(k-1) + c_k I``."""
    n = Ad.shape[0]
    den = np.real(np.poly(Ad))
    M = np.eye(n)
    num = np.zeros((n, n + 1, B.shape[1]))
    for k in range(n):
        num[:, k + 1, :] = M @ B
        M = Ad @ M + den[k + 1] * np.eye(n)
    return num, den


@dataclasses.dataclass(frozen=True, eq=False)
class Responses:
    """The responses of one structure with fixed poles on one reference (module docstring), in mm per unit.

    Attributes:
        S: ``(N, n + 2)``: ``S_0 .. S_{n+1}`` (``S_i = s^i/D q``) [mm s^i... per the unit of ``s^i``].
        modes_pos, modes_vel: ``(N, n)`` free responses and their derivatives.
        offset_pos, offset_vel: ``(N,)`` response ``s^k/D 1`` to a unit held disturbance and its derivative.
        den: ``D(s)`` (descending), ``k``: the disturbance path's power of ``s``.
    """

    S: np.ndarray
    modes_pos: np.ndarray
    modes_vel: np.ndarray
    offset_pos: np.ndarray
    offset_vel: np.ndarray
    den: np.ndarray
    k: int
    Ts: float
    _w_num: np.ndarray
    _w_den: np.ndarray

    def disturbance(self, u) -> tuple[np.ndarray, np.ndarray]:
        """``(s^k/D u, s^{k+1}/D u)`` at the samples for a disturbance ``u`` held over each period [mm, mm/s per unit]."""
        n = self.den.size - 1
        y = lfilter([1.0], self._w_den, u)
        out = _fir(self._w_num[[self.k, self.k + 1]][:, :, None], y[None, :])
        return out[0] * self.Ts ** (n - self.k), out[1] * self.Ts ** (n - self.k - 1)

    def disturbance_position(self, u) -> np.ndarray:
        """``s^k/D u`` only (the first output of :meth:`disturbance`) [mm per unit]."""
        n = self.den.size - 1
        return lfilter(self._w_num[self.k], self._w_den, u) * self.Ts ** (n - self.k)


def _fir(taps, U):
    """``sum_k taps[:, k, :] @ U[:, t - k]``: the FIR filters of every state over every input channel
    (``taps`` ``(n, n+1, c)``, ``U`` ``(c, N)``) as ``n + 1`` small matrix products (zero before the record)."""
    n_taps, N = taps.shape[1], U.shape[1]
    out = taps[:, 0, :] @ U
    for k in range(1, n_taps):
        out[:, k:] += taps[:, k, :] @ U[:, :N - k]
    return out


def responses(structure: ModelStructure, sigma, ref: Reference) -> Responses:
    """All responses of :class:`Responses` for pole parameters ``sigma`` (order ``structure.pole_names``)."""
    Ts, n = ref.sample_period, structure.n_poles
    den = structure.denominator(sigma)
    Ad, G, Gw = _discretize(den, Ts)
    num, dz = _state_filters(Ad, np.column_stack([G, Gw]))
    fir = _fir(num[:, :, :4], ref.channels)  # (n, N)
    ST = np.empty((n + 2, ref.n_samples))  # rows S_0 .. S_{n+1}, contiguous; S is its transpose
    ST[:n] = lfilter([1.0], dz, fir, axis=-1)
    ST[:n] *= (Ts ** (n - np.arange(n)))[:, None]
    d = den[::-1]  # d_0, d_1, ..., d_{n-1}, 1
    ST[n] = ref.q - d[:n] @ ST[:n]
    ST[n + 1] = ref.v - d[:n - 1] @ ST[1:n] - d[n - 1] * ST[n]
    S = ST.T
    w_num, w_den = num[:, :, 4], dz
    k = int(structure.integrator)
    step = lfilter([1.0], w_den, np.ones(ref.n_samples))  # 1/den(z) of a unit step, then each numerator
    off = _fir(w_num[[k, k + 1]][:, :, None], step[None, :]) * (Ts ** (n - np.array([k, k + 1])))[:, None]
    mp, mv = _modes(structure.poles(sigma), ref.t)
    return Responses(S, mp, mv, off[0], off[1], den, k, Ts, w_num, w_den)


def _modes(poles, t):
    """Real basis of the free responses ``e^{lambda t}`` (and derivatives) of the poles ``(n,)``: ``e^{a t}`` for a
    real pole, ``e^{a t} cos(b t)``, ``e^{a t} sin(b t)`` for a pair ``a +- i b`` (upper one taken)."""
    n_t = t.size
    pos, vel = np.zeros((n_t, len(poles))), np.zeros((n_t, len(poles)))
    done, col = set(), 0
    for i, lam in enumerate(poles):
        if i in done:
            continue
        # samples until the envelope e^{a t} falls below e^-DECAYED (1e-20): zero after that, exact to that level
        k = n_t if lam.real >= 0 or n_t < 2 else min(n_t, int(np.ceil(DECAYED / (-lam.real * t[1]))) + 1)
        tk = t[:k]
        if abs(lam.imag) <= 1e-9 * abs(lam):
            e = np.exp(lam.real * tk)
            pos[:k, col], vel[:k, col] = e, lam.real * e
            col += 1
        else:
            j = next(m for m in range(i + 1, len(poles)) if m not in done and abs(poles[m] - np.conj(lam)) <= 1e-9 * abs(lam))
            done.add(j)
            a, b = lam.real, lam.imag
            e = np.exp(a * tk)
            c, s = e * np.cos(b * tk), e * np.sin(b * tk)
            pos[:k, col], pos[:k, col + 1] = c, s
            vel[:k, col], vel[:k, col + 1] = a * c - b * s, b * c + a * s
            col += 2
    return pos, vel


def linear_part(structure: ModelStructure, R: Responses, b, offset: float, c, force=None) -> tuple[np.ndarray, np.ndarray]:
    """Position and velocity without friction: ``d_0 S_0 + sum b_i S_i - offset F[1] + sum c_m phi_m``
    (relative to ``x_r,0``) [mm, mm/s], plus ``g F[f]`` when ``force = (g, f)`` (a measured force ``f``)."""
    d0 = R.den[-1]
    pos = d0 * R.S[:, 0] + R.S[:, 1:structure.n_zeros + 1] @ np.asarray(b)
    vel = d0 * R.S[:, 1] + R.S[:, 2:structure.n_zeros + 2] @ np.asarray(b)
    if offset:
        pos, vel = pos - offset * R.offset_pos, vel - offset * R.offset_vel
    if c is not None:
        pos, vel = pos + R.modes_pos @ np.asarray(c), vel + R.modes_vel @ np.asarray(c)
    if force is not None:
        fp, fv = R.disturbance(np.asarray(force[1], dtype=np.float64))
        pos, vel = pos + force[0] * fp, vel + force[0] * fv
    return pos, vel


def consistent_signs(R: Responses, pos_lin, vel_lin, dc: float, signs=None):
    """Solve the friction feedback exactly: signs ``s_k = sign(x'_k)`` of the velocity they produce.

    Args:
        R: responses of the model.
        pos_lin, vel_lin: the friction-free position and velocity [mm, mm/s].
        dc: Coulomb friction [mm/s^2] (>= 0).
        signs: starting guess (default: signs of ``vel_lin``).
    Returns:
        ``(position, velocity, signs, passes)``.
    Raises:
        ConvergenceError: no fixed point within :data:`MAX_SIGN_PASSES` passes.
    """
    s = np.sign(vel_lin) if signs is None else np.asarray(signs, dtype=np.float64)
    if dc == 0:
        return pos_lin, vel_lin, np.sign(vel_lin), 0
    for it in range(1, MAX_SIGN_PASSES + 1):
        fp, fv = R.disturbance(s)
        pos, vel = pos_lin - dc * fp, vel_lin - dc * fv
        s_new = np.sign(vel)
        changed = np.flatnonzero(s_new != s)
        if not changed.size:
            return pos, vel, s, it
        s = s_new
    raise ConvergenceError(f"friction sign fixed point did not settle in {MAX_SIGN_PASSES} passes "
                           f"({changed.size} signs still changing, first at sample {int(changed[0])})",
                           residual=float(changed.size), steps=MAX_SIGN_PASSES)
