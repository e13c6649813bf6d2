"""Discrete-time simulation of drive models at the control period ``Ts`` with ``jax.lax.scan``.

Discretization (exact for the linear part). Over each period ``[t_k, t_k + Ts)``:

- the friction inputs ``w = [f_c sigma(x'_k), f_ff sigma(x'_r,k)]`` are held constant (zero-order hold
  of the friction sign evaluated at the start of the period, ``sigma`` = exact sign of eq 6.2 or its
  ``tanh`` approximation);
- the reference is held according to ``hold``:

  * ``"cubic"`` (default): ``x_r(t_k + tau) = q_k + v_k tau + a_k tau^2/2 + j_k tau^3/6`` with
    ``x_r'``, ``x_r''`` its derivatives, built from the ``Trajectory``'s q, v, a, j. Exact for references
    that are cubic over each period (jerk-limited profiles switching on the grid).
  * ``"zoh"``: ``x_r``, ``x_r'``, ``x_r''`` each held at their sample values (scipy ``cont2discrete``
    ``'zoh'`` / ``lsim(interp=False)``).
  * ``"foh"``: each linearly interpolated between samples (scipy ``lsim(interp=True)``).

The linear state update is then ``z_{k+1} = Ad z_k + G c_k + Gw w_k`` with ``Ad = e^{A Ts}`` and ``G``,
``Gw`` read off the matrix exponential of an augmented system (Van Loan's construction,
:mod:`research.drives._discretize`), so the states at the sample instants are exact for the held
inputs. The per-axis discretization is ``jax.vmap``-ed over the axes; a sequential ``scan`` per axis then
steps the recursion, with the held inputs, friction signs and outputs fused into its body
(:mod:`research.drives._stepper`, which records why it is shaped this way). There is no separate
"fast path": the Coulomb sign feeds back every period, so every model runs the same exact recursion.
"""

from __future__ import annotations

from functools import partial
from typing import Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from research._device import device_array
from research.drives._discretize import HOLDS, continuous_system, discretize
from research.drives._friction import coulomb_sign, smooth_sign
from research.drives._modes import FlexibleMode
from research.drives._stepper import run
from research.drives._validation import check_sample_period, check_stable, is_concrete
from research.errors import ParameterError
from research.trajectory import Trajectory

FRICTIONS = ("exact", "smooth")


class DriveResponse(eqx.Module):
    """Simulated (or measured) axis motion, arrays ``(N, A)`` like the input ``Trajectory``.

    Attributes:
        t: sample times [s], ``(N,)``.
        reference: commanded positions ``x_r`` [mm] (rad for rotary axes).
        position: actual positions ``x`` [mm].
        velocity: actual velocities ``x'`` [mm/s].
        control: control voltage ``u`` [V] for physical controller models, ``None`` for eq 6.3 models.
        deflection: structural-mode deflection ``delta`` [mm] when modes were given, else ``None``.
        friction: residual Coulomb disturbance ``f_c sigma(x') - f_ff sigma(x_r')`` held over each period,
            in the model's disturbance unit ([mm/s^2] for eq 6.3 models, [N m] for physical ones).
        axes: axis names.
        sample_period: ``Ts`` [s].
    """

    t: Array
    reference: Array
    position: Array
    velocity: Array
    control: Array | None
    deflection: Array | None
    friction: Array
    axes: tuple[str, ...] = eqx.field(static=True)
    sample_period: float = eqx.field(static=True)

    @property
    def tracking_error(self) -> Array:
        """``x_r - x`` [mm], ``(N, A)``."""
        return self.reference - self.position


# -- simulation core --------------------------------------------------------------------------------
def _axis_outputs(model):
    r = model.realization()
    return r.C, r.D, r.Dw, r.friction_amplitude, r.friction_feedforward


def _simulate_core(models, modes, q, v, a, j, width, *, sample_period, hold, friction, indices, has_modes, has_control):
    """Discretize every axis (vmap) and step each axis through the trajectory
    (:func:`research.drives._stepper.run`); returns ``(x, x', u or None, deflection or None, residual friction)``, each ``(N, A)``."""
    sigma = coulomb_sign if friction == "exact" else (lambda x: smooth_sign(x, width))

    def axis_discretization(model, mode):
        return discretize(*continuous_system(model, mode if has_modes else None), sample_period, hold)

    system = jax.vmap(axis_discretization)(models, modes)
    outputs = jax.vmap(_axis_outputs)(models)
    z0 = jax.vmap(partial(_initial_state, velocity_index=indices[1]))(models, q[0], v[0])
    return run(system, outputs, (q, v, a, j), z0, sigma=sigma, sample_period=sample_period, hold=hold,
               indices=indices, has_control=has_control)


def _initial_state(model, position, velocity, *, velocity_index):
    """Drive state at sample 0: the equilibrium ``z = -A^-1 B [x_r, 0, 0]`` of the loop holding the
    reference at rest at ``position`` (integrators loaded: e.g. ``int(x_r - x) dt = (a2 - b2) x_r / a3``
    for eq 6.3), with the velocity state set to the reference velocity ``velocity``. A stable loop with
    integral action has unit DC gain, so the position state equals ``position``. Friction is zero at
    rest (``sigma(0) = 0``)."""
    r = model.realization()
    z = -jnp.linalg.solve(r.A, r.B[:, 0] * position)
    return z.at[velocity_index].set(velocity)


_core = jax.jit(_simulate_core, static_argnames=("sample_period", "hold", "friction", "indices", "has_modes", "has_control"))


_state_matrices = jax.jit(jax.vmap(lambda model: model.realization().A))


_LAYOUTS: dict = {}  # memo: model tree structure -> its static realization layout


def _layout(model) -> dict:
    """The static part of ``model.realization()`` (state indices, whether it has a control output).

    It is read once per model structure (class and static fields) by abstract evaluation, which costs
    no computation but a few ms of tracing, and memoized.
    """
    key = jax.tree_util.tree_structure(model)
    if key not in _LAYOUTS:
        found = {}

        def probe(m):
            r = m.realization()
            found.update(indices=(r.position_index, r.velocity_index), has_control=r.has_control)
            return r.A

        jax.eval_shape(probe, model)
        _LAYOUTS[key] = found
    return _LAYOUTS[key]


def _per_axis(name, value, axes, kind):
    """Broadcast one object to all axes, or check a sequence has one per axis."""
    if isinstance(value, (list, tuple)):
        if len(value) != len(axes):
            raise ParameterError(
                f"mismatched axis counts: {len(value)} {name} for a trajectory with {len(axes)} axes {axes}; "
                f"give one {kind} per axis, or a single one for all axes"
            )
        items = list(value)
    else:
        items = [value] * len(axes)
    types = {type(x) for x in items}
    if len(types) > 1:
        raise ParameterError(f"all {name} must be of one type to run together, got {sorted(t.__name__ for t in types)}")
    return items


def simulate(
    drive,
    trajectory: Trajectory,
    *,
    modes: FlexibleMode | Sequence[FlexibleMode] | None = None,
    friction: str = "exact",
    friction_width: float = 1.0,
    hold: str = "cubic",
) -> DriveResponse:
    """Run a ``Trajectory`` through drive models at its sample period ``Ts`` (the control period).

    Args:
        drive: a model with ``realization()`` (:class:`ClosedLoopModel`, :class:`PPICascade`,
            :class:`PIDController`) used for every axis, or a sequence with one model per axis (all of
            one type).
        trajectory: reference motion; ``q, v, a, j`` ``(N, A)`` in mm (rad), mm/s, mm/s^2, mm/s^3.
        modes: optional :class:`FlexibleMode` (all axes) or one per axis, excited by the actual axis
            acceleration.
        friction: ``"exact"`` (sign of eq 6.2) or ``"smooth"`` (``tanh(v / friction_width)``, for gradients).
        friction_width: velocity scale of the smooth sign [mm/s].
        hold: reference hold over each period, ``"cubic"``, ``"zoh"`` or ``"foh"`` (module docstring).
    Returns:
        :class:`DriveResponse` with ``(N, A)`` arrays. The motion starts at the reference position and
        velocity of sample 0, with the integrators at the equilibrium of a loop holding that position
        and the modes at rest: exactly the steady state for a trajectory that starts at rest, so the
        response does not depend on where the stroke lies (translation invariant).
    Raises:
        ParameterError: mismatched axis counts, unstable model (the poles are listed), ``Ts`` too coarse
            for the fastest pole, unknown ``hold``/``friction``.
    """
    if hold not in HOLDS:
        raise ParameterError(f"hold must be one of {HOLDS}, got {hold!r}")
    if friction not in FRICTIONS:
        raise ParameterError(f"friction must be one of {FRICTIONS}, got {friction!r}")
    axes = trajectory.axes
    models = _per_axis("drive models", drive, axes, "drive model")
    if not hasattr(models[0], "realization"):
        raise ParameterError(f"drive must be a drive model with a realization(), got {type(models[0]).__name__}")
    has_modes = modes is not None
    mode_list = _per_axis("modes", modes, axes, "FlexibleMode") if has_modes else None
    Ts = float(trajectory.sample_period)
    stacked = jax.tree.map(lambda *x: jnp.stack(x), *models)
    stacked_modes = jax.tree.map(lambda *x: jnp.stack(x), *mode_list) if has_modes else jnp.zeros(len(axes))
    if is_concrete(models, mode_list):
        for k, (A, name) in enumerate(zip(np.asarray(_state_matrices(stacked), dtype=np.float64), axes)):
            poles = np.linalg.eigvals(A)
            check_stable(f"the drive model of axis {name!r}", poles)
            if has_modes:
                poles = np.concatenate([poles, mode_list[k].poles()])
            check_sample_period(f"the drive model of axis {name!r}", poles, Ts)
    if not (isinstance(friction_width, jax.core.Tracer) or float(friction_width) > 0):
        raise ParameterError(f"friction_width must be > 0 mm/s, got {friction_width!r}")
    q, v, a, j = (device_array(x) for x in (trajectory.q, trajectory.v, trajectory.a, trajectory.j))
    x, xd, control, deflection, fr = _core(
        stacked, stacked_modes, q, v, a, j, jnp.asarray(friction_width, dtype=jnp.float64),
        sample_period=Ts, hold=hold, friction=friction, has_modes=has_modes, **_layout(models[0]),
    )
    return DriveResponse(
        t=device_array(trajectory.t), reference=q, position=x, velocity=xd,
        control=control, deflection=deflection, friction=fr,
        axes=tuple(axes), sample_period=Ts,
    )
