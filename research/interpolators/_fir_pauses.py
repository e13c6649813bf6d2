"""Pauses in a FIR plan: G4 dwells and M0/M1 program stops as exact stops held for their duration.

A pause at vertex ``k`` (``k = 0`` the start, ``k = M`` the end, else the junction of blocks
``k - 1`` and ``k``) stops the motion there, as a controller that waits for the motion queue to
drain before a dwell or a program stop does (LinuxCNC: ``G4``, ``M0``, ``M1``). A stop is the
overlap ``T_k = 0`` of eq 11: block ``k`` starts ``T_d`` after block ``k - 1``'s pulse ends, when
the filtered motion of every block before it has ended, at rest on the vertex (eq 6: a block's
filtered pulse lasts ``T_v + T_d``). Nothing then couples the two sides: the corner errors, path
deviation and axis peaks of each side depend on its own blocks only. So :func:`parts` cuts the
program at its pauses, each part is planned alone, and :func:`join` lays the parts end to end,
each later one delayed by the pause before it: the profile holds the vertex (a constant piece) for
the pause's duration. The joined plan is the plan of the whole program with those exact stops.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from research._device import device_array
from research.piecewise import PiecewisePolynomial


def parts(pauses: np.ndarray) -> list[tuple[int, int]]:
    """Block ranges ``[(first, stop), ...]`` between the interior pauses of ``pauses`` ``(M + 1,)``."""
    M = pauses.size - 1
    cuts = [0, *(int(k) for k in np.flatnonzero(~np.isnan(pauses[1:M])) + 1), M]
    return list(zip(cuts[:-1], cuts[1:]))


def per_block(x, first: int, stop: int, n_blocks: int):
    """Blocks ``first .. stop - 1`` of a scalar-or-``(M,)`` argument (a scalar as it is)."""
    shape = getattr(x, "shape", np.shape(x))
    if len(shape) == 1 and shape[0] == n_blocks:
        return x[first:stop]
    return x


def join(plans, ranges, pauses: np.ndarray):
    """The fields of the plan of the whole program from the plans of its parts.

    Args:
        plans: the :class:`~research.interpolators.fir.FIRPlan` of each part, in order.
        ranges: their block ranges (:func:`parts`).
        pauses: ``(M + 1,)`` [s] (``research.paths.gcode.checked_pauses``).

    Returns:
        ``(start_times, pulse_times, overlaps, feeds, position, corner_times, path_deviation,
        rounds)`` of the whole program [s, mm/s, mm]: the parts' own, delayed by the motion and
        pauses before them, with ``T_k = 0`` at each cut and a constant piece for each pause (a
        pause of 0 s gives an empty piece); the cut's corner time is the instant the motion
        reaches its vertex.
    """
    dwell = np.where(np.isnan(pauses), 0.0, pauses)
    M = pauses.size - 1
    D = max(p.position.coeffs.shape[1] for p in plans)  # parts with arcs carry higher degrees: pad with zeros
    # concrete plans are joined in NumPy (JAX would compile each operation for each new size, every
    # program anew) and handed to JAX by transfer; traced ones (gradients) in JAX
    traced = any(isinstance(x, jax.core.Tracer) for x in jax.tree_util.tree_leaves(plans))
    xp = jnp if traced else np

    def arrays(plan):
        pos = plan.position
        fields = (plan.start_times, plan.corner_times, plan.overlaps, pos.breaks, pos.coeffs)
        return fields if traced else tuple(np.asarray(x) for x in fields)

    def hold(value):  # the coefficients of one constant piece at ``value`` (A,)
        return xp.concatenate([xp.reshape(value, (1, 1, -1)), xp.zeros((1, D - 1, value.shape[0]))], axis=1)

    starts, corners, overlaps, breaks, coeffs = [], [], [], [], []  # left breaks and pieces, in time order
    t = xp.asarray(0.0)
    if not np.isnan(pauses[0]):
        breaks.append(xp.zeros(1))
        coeffs.append(hold(arrays(plans[0])[4][0, 0]))
        t = t + dwell[0]
    for j, (plan, (first, stop)) in enumerate(zip(plans, ranges)):
        start_times, corner_times, plan_overlaps, pos_breaks, pos_coeffs = arrays(plan)
        shift = t - pos_breaks[0]
        if j > 0:
            corners.append(xp.reshape(t - dwell[first], (1,)))  # the motion reached the cut's vertex, then held it
            overlaps.append(xp.zeros(1))
        starts.append(start_times + shift)
        corners.append(corner_times + shift)
        overlaps.append(plan_overlaps)
        breaks.append(pos_breaks[:-1] + shift)
        coeffs.append(xp.pad(pos_coeffs, ((0, 0), (0, D - pos_coeffs.shape[1]), (0, 0))))
        t = pos_breaks[-1] + shift
        if stop < M or not np.isnan(pauses[M]):  # the pause after this part
            breaks.append(xp.reshape(t, (1,)))
            coeffs.append(hold(PiecewisePolynomial(pos_breaks, pos_coeffs).end_values()))  # NumPy in, NumPy out
            t = t + dwell[stop]
    breaks.append(xp.reshape(t, (1,)))
    deviations = [p.path_deviation for p in plans]
    deviation = float("nan") if np.any(np.isnan(deviations)) else float(max(deviations))
    out = (xp.concatenate(starts), xp.concatenate([p.pulse_times for p in plans]), xp.concatenate(overlaps),
           xp.concatenate([p.feeds for p in plans]), xp.concatenate(breaks), xp.concatenate(coeffs),
           xp.concatenate(corners))
    if not traced:
        out = tuple(device_array(np.asarray(x)) for x in out)
    starts, pulses, overlaps, feeds, breaks, coeffs, corners = out
    return (starts, pulses, overlaps, feeds, PiecewisePolynomial(breaks, coeffs), corners, deviation,
            max(p.rounds for p in plans))
