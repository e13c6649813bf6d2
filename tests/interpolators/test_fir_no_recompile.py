"""Planning many programs in one process compiles nothing new per program (a sweep's memory).

Regression (seeded stress sweep: a worker died at about 24 GB after some 1,600 plans): on JAX 0.10
``jnp.asarray`` of a NumPy array, a JAX index of a concrete array and the JAX corner search each
compiled once per array size, so every plan of a new size compiled, and kept, a few executables
when its position, corner errors or trajectory were read: +5 MB and 0.35 s a plan (200-block
programs, 40 plans: 16.9 s and +413 MB; now 0.9 s and +64 MB, flat after the first).
"""

from __future__ import annotations

import jax
import numpy as np

from research.interpolators import plan_fir
from research.paths import Polyline

_COMPILE = "/jax/core/compile/backend_compile_duration"


def _program(rng, n):
    a = np.cumsum(rng.uniform(-0.5, 0.5, n))
    return Polyline(np.vstack([[0.0, 0.0], np.cumsum(np.column_stack([np.cos(a), np.sin(a)]), axis=0)]))


def test_reading_plans_of_new_sizes_compiles_no_jax_executable():
    """After one plan has been read (the fixed-size compilations), plans of three other sizes
    (their profiles of other piece counts) are planned and read -- cycle time, position, corner
    errors, trajectory -- without one JAX backend compilation."""
    rng = np.random.default_rng(0)

    def read(plan):
        float(plan.cycle_time)
        plan.position
        np.asarray(plan.corner_errors)
        plan.trajectory(1e-3)

    read(plan_fir(_program(rng, 120), 100.0, [0.02, 0.01], 0.01))
    compiled = []

    def listen(event, duration, **kwargs):
        if event == _COMPILE:
            compiled.append(duration)

    jax.monitoring.register_event_duration_secs_listener(listen)
    try:
        for n in (97, 143, 211):
            read(plan_fir(_program(rng, n), 100.0, [0.02, 0.01], 0.01))
    finally:
        jax.monitoring.unregister_event_duration_listener(listen)
    assert compiled == []
