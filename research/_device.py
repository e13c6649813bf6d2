"""Concrete NumPy results handed to JAX without a compilation.

On JAX 0.10, ``jnp.asarray`` of a NumPy array stages a conversion primitive that is compiled once
per shape (about 15 ms and 0.1-1 MB kept each, measured on a (1000, 4, 3) float64 array), so a
process that plans many programs of different sizes (a sweep) compiled, and kept, one conversion
per array per plan: 1.5 MB and 16 ms a plan for the FIR profile alone. ``jax.device_put`` of the
same array is a transfer (0.15 ms, nothing kept).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array


def device_array(x) -> Array:
    """``x`` as a float64 JAX array: a NumPy array (or array-like) by a transfer, not a staged
    conversion; a JAX array or tracer as it is (``jnp.asarray``, no copy at float64).

    On the CPU the result may share the memory of a 64-byte aligned ``x``: pass arrays the caller
    does not change afterwards (the planner's own results, a trajectory's samples)."""
    if isinstance(x, jax.Array):  # a float64 one as it is (jnp.asarray is a dispatch, ~6 us)
        return x if x.dtype == jnp.float64 else jnp.asarray(x, dtype=jnp.float64)
    a = np.asarray(x, dtype=np.float64)  # (np.ascontiguousarray would make a 0-d array 1-d)
    return jax.device_put(a if a.flags.c_contiguous else np.ascontiguousarray(a))


def device_arrays(*xs) -> tuple[Array, ...]:
    """:func:`device_array` of each of ``xs``, the NumPy ones in one transfer: ``jax.device_put``
    has a fixed cost per call (about 20 us on the CPU; the eight of an unrefined 1,000-block
    ``plan_fir`` took a sixth of its time), which one call for the tuple pays once."""
    out = [device_array(x) if isinstance(x, jax.Array) else None for x in xs]
    host = [(i, np.asarray(x, dtype=np.float64)) for i, x in enumerate(xs) if out[i] is None]
    moved = jax.device_put([a if a.flags.c_contiguous else np.ascontiguousarray(a) for _, a in host])
    for (i, _), y in zip(host, moved):
        out[i] = y
    return tuple(out)
