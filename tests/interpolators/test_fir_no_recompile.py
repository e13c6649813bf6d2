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


def _read(plan):
    float(plan.cycle_time)
    plan.position
    np.asarray(plan.corner_errors)
    plan.trajectory(1e-3)


def _compilations(plans) -> list[float]:
    """The JAX backend compilations while ``plans()`` plans and reads its plans."""
    compiled = []

    def listen(event, duration, **kwargs):
        if event == _COMPILE:
            compiled.append(duration)

    jax.monitoring.register_event_duration_secs_listener(listen)
    try:
        plans()
    finally:
        jax.monitoring.unregister_event_duration_listener(listen)
    return compiled


def test_reading_plans_of_new_sizes_compiles_no_jax_executable():
    """After one plan has been read (the fixed-size compilations), plans of three other sizes
    (their profiles of other piece counts) are planned and read -- cycle time, position, corner
    errors, trajectory -- without one JAX backend compilation."""
    rng = np.random.default_rng(0)
    _read(plan_fir(_program(rng, 120), 100.0, [0.02, 0.01], 0.01))

    def plans():
        for n in (97, 143, 211):
            _read(plan_fir(_program(rng, n), 100.0, [0.02, 0.01], 0.01))

    assert _compilations(plans) == []


def test_three_filters_and_pauses_compile_nothing_per_program():
    """Regression (stress sweep re-run: a worker grew 11.5 MB a G-code program): with three filters
    the eq 14 inversion (``overlap_time``, JAX) was compiled for each program's corner count
    (bucketed at 16 sizes an octave), and a program with pauses (``G4``, ``M0``) joined its parts
    with JAX operations, each compiled for each new size. Now, after plans of 30 and 2,000 blocks
    (the inversion's fixed chunk sizes), programs of other sizes with and without pauses compile
    nothing."""
    rng = np.random.default_rng(1)
    delays = [0.03, 0.02, 0.01]

    def paused(n):
        pauses = np.full(n + 1, np.nan)
        pauses[rng.integers(1, n, 2)] = [0.0, 0.5]  # an M0 and a 0.5 s G4 inside the program
        return pauses

    for n in (30, 2000):
        _read(plan_fir(_program(rng, n), 100.0, delays, 0.01, pauses=paused(n)))

    def plans():
        for n in (41, 77, 133):
            _read(plan_fir(_program(rng, n), 100.0, delays, 0.01))
            _read(plan_fir(_program(rng, n), 100.0, delays, 0.01, pauses=paused(n)))

    assert _compilations(plans) == []
