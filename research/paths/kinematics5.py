"""Kinematics of the A/C table-tilting 5-axis machine of Sencer (2009) thesis ch 3-4, and the thesis'
5-axis test path (eq 4.36).

Axis vector ``q = [x, y, z, a, c]`` [mm, mm, mm, rad, rad]; tool pose in the workpiece frame: tip
``P = [Px, Py, Pz]`` [mm] and unit tool axis ``O = [Oi, Oj, Ok]``.

Conventions (eq 3.18, 3.21, 4.2, 4.5, 4.6). The tool axis in workpiece coordinates is

    O = [sin c sin a, -cos c sin a, cos a]                        (eq 3.18 / 4.2)
    a = arccos(Ok),  c = atan2(Oi, -Oj)                           (eq 3.21 / 4.1)

and the Cartesian axes follow from the inverse kinematics (eq 4.6)

    [x, y, z] = diag(-1, -1, 1) R(a, c) P + [0, -L_ac sin a, L_ac cos a + L_ya - L_t]
    R(a, c) = Rot(X, -a) Rot(Z, -c) = [[ cos c,         sin c,         0    ],
                                       [-cos a sin c,   cos a cos c,   sin a],
                                       [ sin a sin c,  -sin a cos c,   cos a]]

with the offsets of eq 4.5/4.6 along Z: ``L_ya`` (Y table to A pivot, ``L_Tya,z``), ``L_ac`` (A pivot
to the C table / workpiece origin, ``L_ac,z``) and ``L_t`` (spindle to tool tip, ``L_fpt,z``); the
``diag(-1, -1, 1)`` is the table moving against the tool in X and Y (eq 3.22). The thesis text
available to us has its signs partly garbled, so the signs here are those of the self-consistent
chain that reproduces eq 3.18 and eq 3.21 exactly; the forward map (eq 4.5) is its exact inverse.
The Jacobian of eq 4.8/4.9 is ``J = [[dP/dq], [0 0 0 1 0], [0 0 0 0 1]]`` (5 x 5).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from research.errors import ParameterError, PathError


def tool_orientation(a, c) -> Array:
    """Tool axis ``O`` in workpiece coordinates, eq 3.18 / 4.2.

    Args:
        a, c: rotary axis positions [rad] (any broadcastable shapes).
    Returns:
        ``(..., 3)`` unit vectors.
    """
    a, c = jnp.asarray(a, dtype=jnp.float64), jnp.asarray(c, dtype=jnp.float64)
    return jnp.stack([jnp.sin(c) * jnp.sin(a), -jnp.cos(c) * jnp.sin(a), jnp.cos(a)], axis=-1)


def rotary_angles(orientation) -> tuple[Array, Array]:
    """Rotary axis positions for a tool axis, eq 3.21 / 4.1: ``a = arccos(Ok)``, ``c = atan2(Oi, -Oj)``.

    Args:
        orientation: ``(..., 3)`` tool axis vectors (normalized here).
    Returns:
        ``(a, c)`` [rad], ``a`` in [0, pi], ``c`` in (-pi, pi]. At ``a = 0`` (vertical tool) ``c`` is
        undetermined and returned as ``atan2(0, 0) = 0``.
    """
    o = jnp.asarray(orientation, dtype=jnp.float64)
    o = o / jnp.linalg.norm(o, axis=-1, keepdims=True)
    a = jnp.arccos(jnp.clip(o[..., 2], -1.0, 1.0))
    c = jnp.arctan2(o[..., 0], -o[..., 1])
    return a, c


def _rotation(a, c):
    """``R(a, c) = Rot(X, -a) Rot(Z, -c)`` of eq 4.6, shape ``(..., 3, 3)``."""
    sa, ca, sc, cc = jnp.sin(a), jnp.cos(a), jnp.sin(c), jnp.cos(c)
    zero = jnp.zeros_like(sa)
    return jnp.stack([
        jnp.stack([cc, sc, zero], -1),
        jnp.stack([-ca * sc, ca * cc, sa], -1),
        jnp.stack([sa * sc, -sa * cc, ca], -1),
    ], -2)


class TableTiltingAC(eqx.Module):
    """A/C table-tilting 5-axis machine (thesis Fig 3.1b/3.2, eq 4.5/4.6).

    Attributes:
        L_ya: Z offset from the Y table to the A-axis pivot, ``L_Tya,z`` [mm].
        L_ac: Z offset from the A pivot to the C table (workpiece origin), ``L_ac,z`` [mm].
        L_t: Z offset from the spindle reference to the tool tip, ``L_fpt,z`` [mm].
    """

    L_ya: Array
    L_ac: Array
    L_t: Array

    def __init__(self, L_ya=0.0, L_ac=0.0, L_t=0.0):
        self.L_ya, self.L_ac, self.L_t = (jnp.asarray(v, dtype=jnp.float64) for v in (L_ya, L_ac, L_t))

    def __check_init__(self):
        if any(isinstance(v, jax.core.Tracer) for v in (self.L_ya, self.L_ac, self.L_t)):
            return
        for name in ("L_ya", "L_ac", "L_t"):
            if not np.isfinite(float(getattr(self, name))):
                raise ParameterError(f"TableTiltingAC.{name} must be a finite offset in mm, got {getattr(self, name)}")

    def _offset(self, a):
        return jnp.stack([jnp.zeros_like(a), -self.L_ac * jnp.sin(a), self.L_ac * jnp.cos(a) + self.L_ya - self.L_t], -1)

    def inverse(self, tip, orientation) -> Array:
        """Axis positions for a tool pose: eq 3.21 for (a, c), eq 4.6 for (x, y, z).

        Args:
            tip: ``(..., 3)`` tool tip ``P`` in workpiece coordinates [mm].
            orientation: ``(..., 3)`` tool axis ``O``.
        Returns:
            ``(..., 5)`` axis positions ``[x, y, z, a, c]`` [mm, rad].
        """
        a, c = rotary_angles(orientation)
        return self.inverse_with_angles(tip, a, c)

    def inverse_with_angles(self, tip, a, c) -> Array:
        """Eq 4.6 with the rotary positions given (e.g. by eq 4.36), ``(..., 5)`` ``[x, y, z, a, c]``."""
        P = jnp.asarray(tip, dtype=jnp.float64)
        a, c = jnp.asarray(a, dtype=jnp.float64), jnp.asarray(c, dtype=jnp.float64)
        xyz = jnp.einsum("...ij,...j->...i", _rotation(a, c), P) * jnp.array([-1.0, -1.0, 1.0]) + self._offset(a)
        return jnp.concatenate([xyz, a[..., None], c[..., None]], axis=-1)

    def forward(self, q) -> tuple[Array, Array]:
        """Tool tip and axis for axis positions, eq 4.5 and eq 4.2.

        Args:
            q: ``(..., 5)`` ``[x, y, z, a, c]`` [mm, rad].
        Returns:
            ``(P, O)``, each ``(..., 3)``: tip [mm] and unit tool axis in workpiece coordinates.
        """
        q = jnp.asarray(q, dtype=jnp.float64)
        a, c = q[..., 3], q[..., 4]
        k = (q[..., :3] - self._offset(a)) * jnp.array([-1.0, -1.0, 1.0])
        P = jnp.einsum("...ji,...j->...i", _rotation(a, c), k)
        return P, tool_orientation(a, c)

    def tip_jacobian(self, q) -> Array:
        """``dP/dq`` (eq 4.8), ``(..., 3, 5)`` [mm/mm, mm/rad], in closed form from eq 4.5."""
        q = jnp.asarray(q, dtype=jnp.float64)
        a, c = q[..., 3], q[..., 4]
        sgn = jnp.array([-1.0, -1.0, 1.0])
        R = _rotation(a, c)
        k = (q[..., :3] - self._offset(a)) * sgn
        sa, ca, sc, cc = jnp.sin(a), jnp.cos(a), jnp.sin(c), jnp.cos(c)
        zero = jnp.zeros_like(sa)
        dR_da = jnp.stack([
            jnp.stack([zero, zero, zero], -1),
            jnp.stack([sa * sc, -sa * cc, ca], -1),
            jnp.stack([ca * sc, -ca * cc, -sa], -1),
        ], -2)
        dR_dc = jnp.stack([
            jnp.stack([-sc, cc, zero], -1),
            jnp.stack([-ca * cc, -ca * sc, zero], -1),
            jnp.stack([sa * cc, sa * sc, zero], -1),
        ], -2)
        dk_da = -jnp.stack([zero, -self.L_ac * ca, -self.L_ac * sa], -1) * sgn
        dP_dxyz = jnp.swapaxes(R, -1, -2) * sgn[None, :]  # R^T diag(sgn)
        dP_da = jnp.einsum("...ji,...j->...i", dR_da, k) + jnp.einsum("...ji,...j->...i", R, dk_da)
        dP_dc = jnp.einsum("...ji,...j->...i", dR_dc, k)
        return jnp.concatenate([dP_dxyz, dP_da[..., None], dP_dc[..., None]], axis=-1)

    def jacobian(self, q) -> Array:
        """The square pose Jacobian of eq 4.9, ``(..., 5, 5)``: ``[P', a', c'] = J q'`` (eq 4.10)."""
        Jt = self.tip_jacobian(q)
        lead = Jt.shape[:-2]
        rows = jnp.broadcast_to(jnp.array([[0.0, 0, 0, 1, 0], [0, 0, 0, 0, 1]]), lead + (2, 5))
        return jnp.concatenate([Jt, rows], axis=-2)


def orientation_jacobian(a, c) -> Array:
    """Eq 4.3: ``dO/d[a, c]``, ``(..., 3, 2)`` [1/rad]."""
    a, c = jnp.asarray(a, dtype=jnp.float64), jnp.asarray(c, dtype=jnp.float64)
    sa, ca, sc, cc = jnp.sin(a), jnp.cos(a), jnp.sin(c), jnp.cos(c)
    return jnp.stack([
        jnp.stack([sc * ca, cc * sa], -1),
        jnp.stack([-cc * ca, sc * sa], -1),
        jnp.stack([-sa, jnp.zeros_like(sa)], -1),
    ], -2)


class FiveAxisPath(eqx.Module):
    """A 5-axis tool path sampled in its parameter ``l``.

    Attributes:
        l: path parameter samples, ``(N,)``.
        tip: tool tip ``P(l)`` in workpiece coordinates [mm], ``(N, 3)``.
        a, c: rotary axis positions [rad], ``(N,)``.
        name: path name.
    """

    l: Array
    tip: Array
    a: Array
    c: Array
    name: str = eqx.field(static=True, default="")

    @property
    def orientation(self) -> Array:
        """Tool axis ``O(l)`` by eq 3.18, ``(N, 3)``."""
        return tool_orientation(self.a, self.c)

    def axis_positions(self, machine: TableTiltingAC) -> Array:
        """``(N, 5)`` axis positions ``[x, y, z, a, c]`` on ``machine`` (eq 4.6)."""
        return machine.inverse_with_angles(self.tip, self.a, self.c)

    def tip_length(self) -> float:
        """Length of the tool-tip curve [mm] (trapezoidal sum over the samples)."""
        d = np.diff(np.asarray(self.tip), axis=0)
        return float(np.sum(np.linalg.norm(d, axis=1)))


def sencer2009_eq436(n_samples: int = 4001) -> FiveAxisPath:
    """Thesis eq 4.36 test path (Fig 4.5), ``l`` from 0 to 4 pi:

        Px = 15 cos l + 5 sin l,  Py = 15 sin l - 5 cos l,  Pz = 15 l  [mm],
        a = arccos(sin(l) / 5),   c = arctan(cos(l) / 5)               [rad].

    The tip travels a helix of radius sqrt(250) mm; its length is 4 pi sqrt(475) = 273.87 mm (thesis
    §4.5: "about 273.87 [mm]").

    Args:
        n_samples: number of uniformly spaced samples of ``l`` (>= 2).
    """
    if not isinstance(n_samples, (int, np.integer)) or n_samples < 2:
        raise PathError(f"sencer2009_eq436: n_samples must be an integer >= 2, got {n_samples!r}")
    l = jnp.linspace(0.0, 4 * jnp.pi, int(n_samples))
    tip = jnp.stack([15 * jnp.cos(l) + 5 * jnp.sin(l), 15 * jnp.sin(l) - 5 * jnp.cos(l), 15 * l], axis=-1)
    a = jnp.arccos(jnp.sin(l) / 5)
    c = jnp.arctan(jnp.cos(l) / 5)
    return FiveAxisPath(l, tip, a, c, name="sencer2009_eq436")


#: Named 5-axis paths: name -> (constructor, source). Kept here because ``paths.library`` holds 2-D
#: polylines only.
FIVE_AXIS_PATHS = {
    "sencer2009_eq436": (sencer2009_eq436, "thesis eq 4.36 / Fig 4.5: helical tip, varying A/C orientation"),
}


def five_axis_path(name: str, **kwargs) -> FiveAxisPath:
    """The 5-axis path called ``name`` (one of ``FIVE_AXIS_PATHS``)."""
    try:
        make = FIVE_AXIS_PATHS[name][0]
    except KeyError:
        raise PathError(f"unknown 5-axis path {name!r}; expected one of {sorted(FIVE_AXIS_PATHS)}") from None
    return make(**kwargs)
