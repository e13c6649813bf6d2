"""Verified coordinate ascent on an optimized FIR plan (``optimize_fir``'s last step).

A named extension (issue 19 item 2), not Sencer 2015's method. The smooth search
(``_fir_reorder``) and the SLSQP runs end in a local optimum of their own model, or in the feasible
start plan when no answer verified. The window bound (``_fir_window_bound``) shows where time is
left: on cam30 at bench_cam's setting without limits the plain plan keeps corners at 0.86-0.92 eps
(dwell longer than the tolerance needs). ``polish`` raises one coordinate at a time towards its
upper bound, each move checked on the exact profile (``_Problem.feasible``: corner errors, path
deviation, exact per-piece peaks; with modes also the residual vibration on the exact profile):

- a corner's overlap ``T_k / T_d`` towards 1 (the cycle time falls by ``T_d`` per unit, eq 11);
- a block's piece feeds ``F_p / F`` towards 1 together, ``f_p + theta (1 - f_p)``, ``theta`` in ``[0, 1]``
  (its pulse time falls, eq 5).

Each move tries the bound first and otherwise bisects (:data:`STEPS` halvings of the remaining
range); a coordinate whose whole range would gain less than ``_fir_reorder.REL_GAIN`` of the
cycle time is skipped, and sweeps repeat while one gains at least that much. Every accepted point is
verified, so the result is feasible and never slower than the start.
"""

from __future__ import annotations

import numpy as np

from research.interpolators._fir_reorder import REL_GAIN

#: bisection halvings per move (resolution 1/64 of the remaining range)
STEPS = 6
#: sweeps over all coordinates at most
SWEEPS = 3


def polish(problem, x: np.ndarray, ok, *, steps: int = STEPS, sweeps: int = SWEEPS) -> tuple[np.ndarray, int]:
    """Coordinate ascent from the feasible plan ``x`` of ``problem`` (``_fir_optimize._Problem``).

    Args:
        problem: the plan's ``_Problem`` (variables: overlaps, head / body / tail feeds, shares).
        x: a plan that ``ok`` accepts.
        ok: ``ok(x) -> bool``, the exact verification of a candidate.
        steps, sweeps: bisection halvings per move; sweeps at most.

    Returns:
        ``(x, checks)``: the polished plan (``x`` itself if no move verified) and the number of
        exact checks spent.
    """
    M = problem.M
    x = np.array(x, dtype=np.float64)
    checks = 0

    def moved(y0, idx, theta):
        y = y0.copy()
        y[idx] = y0[idx] + theta * (1.0 - y0[idx])
        return y

    coords = [np.array([k]) for k in range(M - 1)] + [M - 1 + np.arange(3) * M + k for k in range(M)]
    for _ in range(sweeps):
        t0 = problem.time(x)
        for idx in coords:
            if t0 - problem.time(moved(x, idx, 1.0)) < REL_GAIN * t0:
                continue  # nothing worth an exact check (also: already at the bound)
            checks += 1
            y = moved(x, idx, 1.0)
            if ok(y):
                x = y
                continue
            lo, hi = 0.0, 1.0
            for _ in range(steps):
                mid = 0.5 * (lo + hi)
                checks += 1
                lo, hi = (mid, hi) if ok(moved(x, idx, mid)) else (lo, mid)
            if lo > 0.0:
                x = moved(x, idx, lo)
        if problem.time(x) > t0 * (1.0 - REL_GAIN):
            break
    return x, checks
