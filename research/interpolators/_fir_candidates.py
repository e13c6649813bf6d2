"""Cycle time that never increases when the tolerance grows, by construction (FIR on CAM programs).

:func:`~research.interpolators.fir.plan_fir` chooses, at one tolerance, the least verified cycle
time among look-ahead candidates that are *built from* that tolerance (window feeds, eq 13/14
dwells) and repaired against it (feeds scaled by ``sqrt(eps / error)``, overlaps by
``(eps / error)^(1/(n+1))``, exact stops). Neither the candidates nor the repairs are monotone in
``eps``: a looser tolerance lets eq 13/14 allow full overlap at a corner whose window then needs a
slow-down, or a repair that scales a whole window's blocks, and the plan can come out slower
(measured in ``benchmarks/README.md``, bench_cam section). A rule that is monotone for every
candidate and every repair would need the candidate generation and the repairs to be monotone
maps of ``eps``, which they are not (a repair's outcome depends on which vertices violate, and
the errors of a window of short blocks are not monotone in its feeds).

The construction here does not ask that of the planner. It rests on one fact of the verification:

    a plan verified at tolerance ``eps`` has every checked error (vertex distances, sampled path
    deviation) ``<= eps (1 + 1e-9) + 1e-9`` (``_fir_kernels.verified_bound``) and holds the limits, so it passes the same checks at
    every ``eps' >= eps`` (the checks compare the same, tolerance-free distances with a larger
    bound) -- it is a feasible plan for ``eps'``.

(In detail: the vertex distances and the limit ratios do not depend on the tolerance; a path
sample passes when its three-block distance, or the tighter ``distance_bound`` computed for the
samples that fail that first test, is within the bound of its block or vertex, a predicate that
only gets easier as the bound grows, componentwise for per-block tolerances.)

So over a set of tolerances ``E`` (scalars, or one per block ordered componentwise), the plan
returned for ``eps_j`` is the least cycle time among the verified plans of every ``eps_i <= eps_j``
in ``E`` (:func:`envelope`). For ``eps_i <= eps_j`` the candidate set of ``eps_j`` contains the
candidate set of ``eps_i`` (``<=`` is transitive), every member is feasible for its own tolerance
and therefore for ``eps_j``, and the choice is the minimum: the cycle time at ``eps_j`` is at most
the one at ``eps_i``, exactly (the same plan object or a faster one, no rounding involved). This
is the cycle-time envelope of a tolerance sweep, and costs nothing beyond planning each tolerance.

What it does not give: a single :func:`plan_fir` call is still a function of its own tolerance
alone, so two separate calls can still disagree (the envelope needs the tighter tolerances to be
planned). One call offers the dwell sets of the tighter tolerances ``eps 2^-k/2`` (``_fir_lookahead``,
nesting in eps), which removes most such disagreements but proves none away. Making one call monotone by the same argument needs the plans of *every* tighter
tolerance, an infinite set; no finite set of tighter tolerances is nested across all ``eps``
without a lower bound on the cycle time at all tighter tolerances, which this planner does not
have (zigzag chains cancel, so a vertex's turning angle bounds nothing).
"""

from __future__ import annotations

from collections.abc import Sequence

import equinox as eqx
import numpy as np

from research.errors import ParameterError


def envelope(tolerances: Sequence[np.ndarray], cycle_times: Sequence[float]) -> tuple[int, ...]:
    """For each tolerance ``j``, the index of the least cycle time among all ``i`` with
    ``tolerances[i] <= tolerances[j]`` componentwise (``j`` itself included; ties keep ``j``,
    then the largest tolerance, then the lowest index).

    Args:
        tolerances: ``K`` tolerance vectors [mm], all of one shape.
        cycle_times: ``K`` verified cycle times [s].

    Returns:
        ``K`` indices into the inputs. The cycle time at the returned index is non-increasing
        along any chain ``tolerances[i] <= tolerances[j]`` (module docstring).
    """
    tol = np.stack([np.asarray(t, dtype=np.float64).reshape(-1) for t in tolerances])
    times = np.asarray(cycle_times, dtype=np.float64)
    if times.shape != (tol.shape[0],):
        raise ParameterError(f"envelope: {tol.shape[0]} tolerances but {times.size} cycle times")
    below = np.all(tol[:, None, :] <= tol[None, :, :], axis=2)  # below[i, j]: tol_i <= tol_j
    out = []
    for j in range(tol.shape[0]):
        cand = np.flatnonzero(below[:, j])
        # least time; a tie goes to j itself, then to the largest tolerance (sum), then the lowest index
        key = sorted(cand, key=lambda i: (times[i], i != j, -float(tol[i].sum()), i))
        out.append(int(key[0]))
    return tuple(out)


class FIRSweep(eqx.Module):
    """Plans over a tolerance sweep with cycle time non-increasing in the tolerance.

    Attributes:
        tolerances: the tolerances as given (scalars or per-block arrays) [mm].
        plans: ``plans[j]`` the plan used at ``tolerances[j]`` (a verified plan of some
            ``tolerances[i] <= tolerances[j]``, the fastest of them).
        planned_at: ``planned_at[j]`` that ``i``.
        own_cycle_times: ``(K,)`` cycle time [s] of the plan of each tolerance itself (what
            :func:`plan_fir` alone returns there; not monotone in general).
    """

    tolerances: tuple = eqx.field(static=True)
    plans: tuple
    planned_at: tuple[int, ...] = eqx.field(static=True)
    own_cycle_times: tuple[float, ...] = eqx.field(static=True)

    @property
    def cycle_times(self) -> np.ndarray:
        """``(K,)`` cycle time [s] at each tolerance."""
        return np.array([float(p.cycle_time) for p in self.plans])
