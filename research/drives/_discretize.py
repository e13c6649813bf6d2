"""Exact discretization of a drive model at the control period ``Ts`` (Van Loan's construction).

Over each period ``[t_k, t_k + Ts)`` the friction inputs ``w`` are held constant and the reference
``r = [x_r, x_r', x_r'']`` is held according to ``hold``:

* ``"cubic"``: ``x_r(t_k + tau) = q_k + v_k tau + a_k tau^2/2 + j_k tau^3/6`` with ``x_r'``, ``x_r''`` its
  derivatives (exact for references that are cubic over each period);
* ``"zoh"``: ``x_r``, ``x_r'``, ``x_r''`` each held at their sample values (scipy ``cont2discrete``
  ``'zoh'`` / ``lsim(interp=False)``);
* ``"foh"``: each linearly interpolated between samples (scipy ``lsim(interp=True)``).

Then ``z_{k+1} = Ad z_k + G c_k + Gw w_k`` with ``Ad = e^{A Ts}`` and ``G``, ``Gw`` read off the matrix
exponential of an augmented system, so the states at the sample instants are exact for the held inputs.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from jax.scipy.linalg import expm

from research.errors import ParameterError

HOLDS = ("cubic", "zoh", "foh")


def continuous_system(model, mode):
    """(A, B, Bw) of one axis, with the structural mode (if any) appended to the state."""
    r = model.realization()
    if mode is None:
        return r.A, r.B, r.Bw
    Am, e = mode.state_matrices()
    n = r.A.shape[0]
    k = r.velocity_index
    A = jnp.zeros((n + 2, n + 2)).at[:n, :n].set(r.A).at[n:, n:].set(Am).at[n:, :n].set(jnp.outer(e, r.A[k]))
    B = jnp.concatenate([r.B, jnp.outer(e, r.B[k])])
    Bw = jnp.concatenate([r.Bw, jnp.outer(e, r.Bw[k])])
    return A, B, Bw


def _balanced_expm(M, iterations: int = 8):
    """``expm(M)`` computed on a diagonally balanced matrix ``D^-1 M D`` (power-of-two scaling, so the
    similarity is exact in floating point). The drive matrices mix entries from 1 to ``a3 Ts ~ 1e3``;
    balancing makes the Pade/squaring error, and hence finite differences of the result, ~1e-13
    relative instead of ~1e-9. The scaling is computed under ``stop_gradient`` (it is piecewise constant)."""
    mag = jax.lax.stop_gradient(jnp.abs(M))
    d = jnp.ones(M.shape[0])
    for _ in range(iterations):
        Bm = mag * d[None, :] / d[:, None]
        col = jnp.sum(Bm, 0) - jnp.diag(Bm)
        row = jnp.sum(Bm, 1) - jnp.diag(Bm)
        ok = (col > 0) & (row > 0)
        d = d * jnp.where(ok, jnp.exp2(jnp.round(0.5 * jnp.log2(jnp.where(ok, row, 1.0) / jnp.where(ok, col, 1.0)))), 1.0)
    return expm(M * d[None, :] / d[:, None]) * d[:, None] / d[None, :]


def discretize(A, B, Bw, sample_period, hold: str = "cubic"):
    """Exact discretization of ``z' = A z + B r + Bw w`` for the reference hold ``hold``.

    Args:
        A ``(n, n)``, B ``(n, 3)`` for ``r = [x_r, x_r', x_r'']``, Bw ``(n, 2)``: continuous matrices.
        sample_period: ``Ts`` [s].
        hold: ``"cubic"``, ``"zoh"`` or ``"foh"`` (module docstring).
    Returns:
        ``(Ad, G, Gw)``: ``z_{k+1} = Ad z_k + G c_k + Gw w_k`` where ``c_k`` is ``[q, v, a, j]`` (cubic),
        ``[q, v, a]`` (zoh) or ``[q, v, a, dq, dv, da]`` with the slopes ``d = (r_{k+1} - r_k)/Ts`` (foh).
    """
    n = A.shape[0]
    if hold == "cubic":
        m = n + 6
        M = jnp.zeros((m, m)).at[:n, :n].set(A).at[:n, n : n + 3].set(B).at[:n, n + 4 :].set(Bw)
        M = M.at[n, n + 1].set(1.0).at[n + 1, n + 2].set(1.0).at[n + 2, n + 3].set(1.0)
        Phi = _balanced_expm(M * sample_period)
        return Phi[:n, :n], Phi[:n, n : n + 4], Phi[:n, n + 4 :]
    if hold == "zoh":
        m = n + 5
        M = jnp.zeros((m, m)).at[:n, :n].set(A).at[:n, n : n + 3].set(B).at[:n, n + 3 :].set(Bw)
        Phi = _balanced_expm(M * sample_period)
        return Phi[:n, :n], Phi[:n, n : n + 3], Phi[:n, n + 3 :]
    if hold == "foh":
        m = n + 8
        M = jnp.zeros((m, m)).at[:n, :n].set(A).at[:n, n : n + 3].set(B).at[:n, n + 6 :].set(Bw)
        M = M.at[n : n + 3, n + 3 : n + 6].set(jnp.eye(3))
        Phi = _balanced_expm(M * sample_period)
        return Phi[:n, :n], Phi[:n, n : n + 6], Phi[:n, n + 6 :]
    raise ParameterError(f"hold must be one of {HOLDS}, got {hold!r}")
