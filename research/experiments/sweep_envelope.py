"""The tolerance envelope of a sweep: a looser tolerance never runs slower than a tighter one.

A plan verified within a cornering tolerance ``eps_i`` is within every ``eps_j >= eps_i``: the
machine may always run the tighter plan. The FIR planner's own choice at each tolerance is a
heuristic (``research.interpolators.fir``: candidates, branch and bound, repairs) and its cycle
time is not monotone in ``eps`` on every program (issue "FIR cornering on real CAM programs": "a
looser tolerance can make the part 17 % slower, which ruins any tolerance sensitivity study";
about 4 % of random line programs still rise somewhere on eps x 1 .. 3). So, as
:func:`research.interpolators.plan_fir_sweep` does for one path, a sweep over the tolerance keeps
at each point the fastest of the plans of the points that differ from it only by a tighter (or
equal) tolerance, from the rows it computed anyway (no extra planning).

Taken where it is sound (:func:`envelope_field`): one interpolator (every scalar of a row then
comes from its plan), an FIR planner whose plans are verified within the tolerance
(``refine = true`` or ``optimized = true``) or the time-optimal reference (a trajectory in the
tube of ``eps_i`` is in the wider one), and ``sweep.tolerance_envelope = true`` (the default).

A row whose kept plan is another point's takes that point's scalars (cycle time, corner and
contour errors, drive and control metrics: what the machine then runs), its derivatives with
respect to the tolerance set to 0 (the kept plan does not depend on this point's tolerance) and
the others (feed, delays) as the kept point's. Every row gets ``own_cycle_time`` [s], its own
plan's, and ``planned_at_tolerance_um``, the tolerance its kept plan was planned at. Failed
points stay failed (nothing is hidden) and lend no plan.
"""

from __future__ import annotations

import re

#: columns the envelope adds to every row of a sweep it applies to
OWN_CYCLE_TIME = "own_cycle_time"
PLANNED_AT = "planned_at_tolerance_um"

_TOLERANCE_FIELD = re.compile(r"interpolator(\[0\])?\.tolerance_um")
_BOOKKEEPING = ("index", "status", "error", "source")


def envelope_field(cfg) -> str | None:
    """The swept tolerance field the envelope applies to, or ``None`` (module docstring: where).

    Args:
        cfg: the base :class:`~research.experiments.config.ExperimentConfig` of a sweep.

    Returns:
        ``"interpolator.tolerance_um"`` (as written in ``[sweep.parameters]``) or ``None``.
    """
    if cfg.sweep is None or not cfg.sweep.tolerance_envelope or len(cfg.interpolators) != 1:
        return None
    ic = cfg.interpolators[0]
    verified = ic.kind == "time_optimal" or (ic.kind == "fir" and (ic.refine or ic.optimized))
    if not verified:
        return None
    return next((f for f in cfg.sweep.parameters if _TOLERANCE_FIELD.fullmatch(f)), None)


def tolerance_envelope(rows: list[dict], field: str, fields: list[str]) -> tuple[list[dict], int]:
    """Rows with the envelope over ``field`` applied (new dictionaries; ``rows`` is not changed).

    Args:
        rows: the sweep's rows: ``index``, the swept values (``fields``), ``status`` (``"ok"`` or
            not), ``error``, ``source`` and the scalars, among them ``cycle_time`` [s].
        field: the swept tolerance field (its values in um).
        fields: every swept field; rows equal in all but ``field`` form one group.

    Returns:
        ``(rows, moved)``: each ok row with the scalars of the fastest ok row of its group whose
        tolerance is at most its own (its own on a tie), ``own_cycle_time`` and
        :data:`PLANNED_AT` added; ``moved`` is the number of rows that took another row's plan.
    """
    others = [f for f in fields if f != field]
    groups: dict[tuple, list[int]] = {}
    for i, r in enumerate(rows):
        if r.get("status") == "ok" and isinstance(r.get("cycle_time"), (int, float)):
            groups.setdefault(tuple(repr(r[f]) for f in others), []).append(i)
    out = [dict(r) for r in rows]
    moved = 0
    for members in groups.values():
        members.sort(key=lambda i: rows[i][field])
        best = None  # the fastest row of the tolerances seen so far (this block's included)
        start = 0
        while start < len(members):  # one block of equal tolerances at a time
            stop = start + 1
            while stop < len(members) and rows[members[stop]][field] == rows[members[start]][field]:
                stop += 1
            block = members[start:stop]
            best = min(block + ([best] if best is not None else []), key=lambda j: rows[j]["cycle_time"])
            for i in block:
                kept = i if rows[i]["cycle_time"] <= rows[best]["cycle_time"] else best
                out[i] = _kept_row(rows[i], rows[kept], field, fields)
                moved += kept != i
            start = stop
    return out, moved


def _kept_row(own: dict, kept: dict, field: str, fields: list[str]) -> dict:
    """``own``'s swept values and bookkeeping with ``kept``'s scalars (module docstring)."""
    row = {k: v for k, v in own.items() if k in fields or k in _BOOKKEEPING}
    for k, v in kept.items():
        if k in row:  # (own's swept values and bookkeeping)
            continue
        row[k] = 0.0 if (kept is not own and k.startswith("d_") and k.endswith("/d_eps")) else v
    row[OWN_CYCLE_TIME] = own["cycle_time"]
    row[PLANNED_AT] = kept[field]
    return row
