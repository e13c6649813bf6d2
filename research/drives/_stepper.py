"""The simulation loop: the exact recursion ``z_{k+1} = Ad z_k + G c_k + Gw w_k`` of every axis.

Given the discretization of every axis (:mod:`research.drives._discretize`), each axis is stepped by
its own sequential ``jax.lax.scan`` over the ``N`` periods; the axes are independent, so this is the
same recursion as a batched one, only ordered axis by axis. One period of one axis is:

- read row ``k`` of the ``(N, A)`` trajectory columns and form the held input ``c_k`` (``[q, v, a, j]``,
  ``[q, v, a]``, or for ``"foh"`` ``[q, v, a]`` and the slopes to sample ``k + 1``);
- form the friction inputs ``w_k = [f_c sigma(x'_k), f_ff sigma(x_r,k')]`` from the state and the
  reference velocity;
- write the outputs of sample ``k`` (position, velocity, residual friction ``w_0 - w_1``, and the control
  signal / mode deflection when asked for) into column ``a`` of the ``(N, A)`` results;
- update the state, with the terms that do not depend on it (``G c_k``, the friction feed-forward)
  summed first, so the dependency chain from ``z_k`` to ``z_{k+1}`` is a few multiply-adds.

Everything is fused into the loop body: no ``(N, A, m)`` input or ``(N, A, n)`` state history exists.

Why this shape (10^6 samples x 3 axes on the 2-core CPU development machine): XLA:CPU compiles a while
loop whose body touches under 1 kB per iteration into one native kernel (its "small while loop" pass)
and otherwise dispatches every operation of the body separately, at ~30 ns each. A one-axis body stays
under the limit for every model, hold and output (hence modes in a second loop); an all-axes body does
not (the traced coefficients of 3 axes alone are ~600 bytes) and ran 2-3x slower, as did unrolling.
Arrays above 32 MB get fresh pages on every call there (about 1 ms per MB), so nothing larger than
``(N, A)`` is allocated; for the same reason, and because it would cover friction-free models only, an
``associative_scan`` over the affine maps (``(N, A, n, n)`` intermediates) is not used.
"""

from __future__ import annotations

from collections.abc import Callable

import jax
import jax.numpy as jnp


def _combine(coefficients, values):
    """``sum_i coefficients[i] * values[i]`` as a balanced tree of additions."""
    terms = [c * x for c, x in zip(coefficients, values)]
    while len(terms) > 1:
        terms = [terms[i] + terms[i + 1] if i + 1 < len(terms) else terms[i] for i in range(0, len(terms), 2)]
    return terms[0]


def _read(x, k, axis):
    """Element ``x[k, axis]`` of an ``(N, A)`` column (``k`` traced, ``axis`` static)."""
    return jax.lax.dynamic_slice(x, (k, jnp.int32(axis)), (1, 1))[0, 0]


def _write(x, value, k, axis):
    return jax.lax.dynamic_update_slice(x, jnp.reshape(value, (1, 1)), (k, jnp.int32(axis)))


def _control(rows, z, c, w):
    """Control signal ``u = C[2] z + D[2] r + Dw[2] w`` of one axis (``rows = (C[2], D[2], Dw[2])``)."""
    return _combine([*rows[0], *rows[1], *rows[2]], [*z, *c[:3], *w])


def _held_inputs(hold: str, columns, k, axis: int, sample_period: float):
    """The input vector ``c_k`` of :func:`research.drives.discretize` for one axis, as scalars.

    ``columns`` is ``(q, v, a, j)`` of shape ``(N, A)``; for ``"foh"`` the slope over the last period
    is zero (the next sample index is clamped to ``N - 1``).
    """
    row = [_read(x, k, axis) for x in columns[: 4 if hold == "cubic" else 3]]
    if hold != "foh":
        return row
    following = [_read(x, jnp.minimum(k + 1, columns[0].shape[0] - 1), axis) for x in columns[:3]]
    return row + [(r1 - r0) / sample_period for r0, r1 in zip(row, following)]


def _scan_axis(step, state0, results, length: int):
    """Run ``step((state, k, results)) -> (state, k + 1, results)`` for ``k = 0 .. length - 1``."""
    (_, _, results), _ = jax.lax.scan(lambda carry, _: (step(*carry), None), (state0, jnp.int32(0), results), None,
                                      length=length)
    return results


def run(
    system,
    outputs,
    columns,
    initial_state,
    *,
    sigma: Callable,
    sample_period: float,
    hold: str,
    indices: tuple[int, int],
    has_control: bool,
):
    """Step every axis through the trajectory.

    Args:
        system: ``(Ad, G, Gw)``, ``(A, n, n)``, ``(A, n, m)``, ``(A, n, 2)``: discretized axes.
        outputs: ``(C, D, Dw, f_c, f_ff)`` of the axes' realizations (``(A, 3, n0)``, ``(A, 3, 3)``,
            ``(A, 3, 2)``, ``(A,)``, ``(A,)``). The first ``n0`` states belong to the drive; states
            ``n0, n0 + 1`` (when ``n > n0``) are a structural mode's ``[delta, delta']``.
        columns: ``(q, v, a, j)``, each ``(N, A)`` (``j`` is read only for the cubic hold).
        initial_state: ``(A, n0)`` drive states at sample 0 (the modes start at rest).
        sigma: the friction sign (exact or smooth), applied elementwise.
        sample_period: ``Ts`` [s].
        hold: ``"cubic"``, ``"zoh"`` or ``"foh"``.
        indices: ``(position_index, velocity_index)`` in the state.
        has_control: also return the control signal (row 2 of the output map).
    Returns:
        ``(x, x', u or None, deflection or None, residual friction)``, each ``(N, A)``; row ``k`` is the
        state at sample ``k`` (row 0 is the initial state) and the friction held over period ``k``.

    A mode does not load the drive (its block of ``Ad`` above the diagonal is zero), so the drive states
    are stepped first and the modes afterwards, driven by the stored drive states (the control signal is
    then formed in the mode loop); each loop stays small.
    """
    Ad, G, Gw = system
    C, D, Dw, fc, fff = outputs
    pos_i, vel_i = indices
    n, n0 = Ad.shape[-1], C.shape[-1]
    N, n_axes = columns[0].shape
    has_modes = n > n0
    stored = [i for i in range(n0) if i not in (pos_i, vel_i)] if has_modes else []  # drive states the modes need
    drive_control = has_control and not has_modes
    results = tuple(jnp.zeros_like(columns[0]) for _ in range(3 + drive_control + len(stored)))

    for axis in range(n_axes):
        # this axis' coefficients, sliced once outside its loop
        ad, g, gw, cu = Ad[axis, :n0, :n0], G[axis, :n0], Gw[axis, :n0], (C[axis, 2], D[axis, 2], Dw[axis, 2])
        f_c, f_ff = fc[axis], fff[axis]

        def drive_step(z, k, res, axis=axis, ad=ad, g=g, gw=gw, cu=cu, f_c=f_c, f_ff=f_ff):
            c = _held_inputs(hold, columns, k, axis, sample_period)
            w = [f_c * sigma(z[vel_i]), f_ff * sigma(c[1])]  # c[1] is the reference velocity v_k
            out = [z[pos_i], z[vel_i], w[0] - w[1]]
            if drive_control:
                out.append(_control(cu, z, c, w))
            out += [z[i] for i in stored]
            res = tuple(_write(r, value, k, axis) for r, value in zip(res, out))
            z_next = [_combine([*g[i], gw[i, 1]], [*c, w[1]]) + _combine([*ad[i], gw[i, 0]], [*z, w[0]]) for i in range(n0)]
            return jnp.stack(z_next), k + 1, res

        results = _scan_axis(drive_step, initial_state[axis], results, N)

    position, velocity, friction = results[:3]
    if not has_modes:
        return position, velocity, results[3] if has_control else None, None, friction

    drive_states = [position if i == pos_i else velocity if i == vel_i else results[3 + stored.index(i)] for i in range(n0)]
    results = tuple(jnp.zeros_like(columns[0]) for _ in range(1 + has_control))
    for axis in range(n_axes):
        ad, g, gw, cu = Ad[axis, n0:], G[axis, n0:], Gw[axis, n0:], (C[axis, 2], D[axis, 2], Dw[axis, 2])
        f_c, f_ff = fc[axis], fff[axis]

        def mode_step(y, k, res, axis=axis, ad=ad, g=g, gw=gw, cu=cu, f_c=f_c, f_ff=f_ff):
            z = [_read(x, k, axis) for x in drive_states]
            c = _held_inputs(hold, columns, k, axis, sample_period)
            w = [f_c * sigma(z[vel_i]), f_ff * sigma(c[1])]
            out = [y[0], _control(cu, z, c, w)] if has_control else [y[0]]
            res = tuple(_write(r, value, k, axis) for r, value in zip(res, out))
            y_next = [_combine([*g[i], *gw[i], *ad[i, :n0]], [*c, *w, *z]) + _combine(ad[i, n0:], y) for i in range(n - n0)]
            return jnp.stack(y_next), k + 1, res

        results = _scan_axis(mode_step, jnp.zeros(n - n0, columns[0].dtype), results, N)
    return position, velocity, results[1] if has_control else None, results[0], friction
