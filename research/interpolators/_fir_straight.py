"""Straight vertices: consecutive line blocks that make one line, planned as one block (beyond Sencer 2015).

CAM post-processors and hand-written programs cut straight lines into several moves (a long
facing pass written in pieces, a move split where a tool-path segment ends). Two collinear line
blocks at one feed, at full overlap, give the FIR chain the same input as the single line: one
rectangular velocity pulse (Sencer 2015 eq 5), so the same exact profile. Planned block by block,
though, the split point is a vertex like any other: under axis limits each piece is checked
*alone* between exact stops (``_fir_limits``), where a short piece peaks higher than the line it
belongs to (a pulse shorter than ``T1 + T2`` doubles its jerk), and the pieces were slowed below
what the whole line keeps (a stress sweep of ``G61`` programs with split lines: up to 25 % slower
than the unsplit program); at tolerance 0 every point a rounding puts off the line was a turn.
LinuxCNC's ``G61`` (exact path) reads the same way: "If two sequential moves are exactly co-linear
movement will not stop".

So :func:`straight_runs` finds the runs of line blocks with one feed and one tolerance whose inner
vertices all lie within ``VERIFY_ATOL`` (1 pm, the verification's absolute slack) of the run's
chord, :func:`merged_path` makes each run one block, the planner plans that path, and
:func:`split_plan` gives each original block its share of the merged plan: its pulse start and
length where the input passes its ends, full overlap at the inner vertices (corner instant ``T_d /
2`` after the block's end, eq 11 with ``T_k = T_d``), the fastest piece feed over its stretch, and
the same profile. A trajectory that follows the chord passes within 1 pm of every inner vertex and
of the programmed segments, which is what the verification accepts at any tolerance.

Under axis limits the pieces of a line can also help: they are the steps of a staircase ramp
that one block, starting from rest at its full feed, cannot take. :func:`ramp_pieces` cuts each end
of such a line (or straight run) into pieces commanded at the feeds of the steps the axes allow,
and :func:`join_plan` gives each original block its pieces' plan. Under limits ``plan_fir`` plans
the path as written, with its straight runs merged, and with its lines cut into ramps, and
returns the fastest (a 1,000 mm line under limits below the FIR's own envelope: 500.03 s as one
block, 82.22 s with ramp pieces, for ``L / v + T_d`` = 81.99 s, in 1, 2, 5 or 300 blocks alike).
An arc that cannot start or stop at its feed is cut the same way along its arc length, into arcs
about its centre (:func:`_arc_ramps`: the steps also carry its centripetal acceleration), as a
plan of its own (a half circle of R 20 mm at 6.2 % of the envelope: 34.06 s at the arc's safe
feed, 5.87 s ramped).
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from research._device import device_array
from research.interpolators._fir_kernels import VERIFY_ATOL
from research.interpolators._fir_limits import arc_limit_caps, feed_caps
from research.paths.toolpath import ToolPath


def run_bounds(run: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The first and the last block of each run of the non-decreasing labels ``run`` ``(M,)``."""
    first = np.concatenate([[0], np.flatnonzero(np.diff(run)) + 1])
    return first, np.append(first[1:] - 1, run.size - 1)


def _segment_distances(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance [mm] from each of ``points`` ``(N, d)`` to the segment ``a -> b``."""
    ab = b - a
    ab2 = float(ab @ ab)
    if ab2 == 0.0:
        return np.linalg.norm(points - a, axis=1)
    u = np.clip((points - a) @ ab / ab2, 0.0, 1.0)
    return np.linalg.norm(points - a - u[:, None] * ab, axis=1)


def straight_runs(tp: ToolPath, feeds: np.ndarray, tol_block: np.ndarray) -> np.ndarray | None:
    """The run of every block ``(M,)`` (non-decreasing run indices), or None where no two blocks merge.

    Blocks ``j`` and ``j + 1`` may share a run where both are lines of nonzero length with equal
    commanded feed ``feeds`` ``(M,)`` [mm/s] and tolerance ``tol_block`` ``(M,)`` [mm] and the
    vertex between them lies within ``VERIFY_ATOL`` of the segment from ``j``'s start to ``j + 1``'s
    end. A stretch of such vertices is one run where every inner vertex lies that close to the
    run's own chord (start of its first block to end of its last); otherwise it is split at its
    farthest vertex and each side is tried again (as Douglas and Peucker simplify a polyline): one
    pass over a straight stretch, ``O(n log n)`` at worst. The path's part (:func:`_collinear`) is
    made once per path, and the runs of the last call are kept with the vertices they were found
    for (a sweep plans one path many times)."""
    M = tp.n_blocks
    if M < 2:
        return None
    local = _collinear(tp) & (feeds[:-1] == feeds[1:]) & (tol_block[:-1] == tol_block[1:])
    if not local.any():
        return None
    key, last = local.tobytes(), tp._cache.get("straight_runs")
    if last is not None and last[0] == key:
        return last[1]
    run = _runs(tp, local)
    if run is not None:
        run.setflags(write=False)
    tp._cache["straight_runs"] = (key, run)
    return run


def _collinear(tp: ToolPath) -> np.ndarray:
    """``(M - 1,)`` True at each vertex between two line blocks of nonzero length that lies within
    ``VERIFY_ATOL`` of the segment from the first one's start to the second one's end (read-only;
    made once per path)."""
    if "collinear" not in tp._cache:
        V = np.vstack([tp.start, tp.ends])
        line = ~tp.is_arc & (tp.lengths > 0)
        ab, a1 = V[2:] - V[:-2], V[1:-1] - V[:-2]  # every vertex's (the arcs' are not read)
        ab2 = np.einsum("kd,kd->k", ab, ab)  # 0 where the path returns to its point: a reversal
        u = np.clip(np.einsum("kd,kd->k", a1, ab) / np.where(ab2 > 0, ab2, 1.0), 0.0, 1.0)
        local = line[:-1] & line[1:] & (np.linalg.norm(a1 - u[:, None] * ab, axis=1) <= VERIFY_ATOL)
        local.setflags(write=False)
        tp._cache["collinear"] = local
    return tp._cache["collinear"]


def _runs(tp: ToolPath, local: np.ndarray) -> np.ndarray | None:
    """:func:`straight_runs` from the vertices ``local`` ``(M - 1,)`` that may join their blocks."""
    M = tp.n_blocks
    V = np.vstack([tp.start, tp.ends])
    joined = np.zeros(M - 1, dtype=bool)  # vertex j inside a run
    edges = np.flatnonzero(np.diff(np.concatenate([[0], local.astype(np.int8), [0]])))
    stack = [(int(a), int(b)) for a, b in zip(edges[0::2], edges[1::2])]  # vertex ranges [a, b)
    while stack:
        a, b = stack.pop()  # blocks a .. b, inner vertices a .. b - 1 (vertex j ends block j)
        dist = _segment_distances(V[a + 1: b + 1], V[a], V[b + 1])
        if np.all(dist <= VERIFY_ATOL):
            joined[a:b] = True
            continue
        far = a + int(np.argmax(dist))  # split at the farthest vertex: blocks a .. far, far + 1 .. b
        if far > a:
            stack.append((a, far))
        if b > far + 1:
            stack.append((far + 1, b))
    if not joined.any():
        return None
    return np.concatenate([[0], np.cumsum(~joined)])


def merged_path(tp: ToolPath, run: np.ndarray) -> ToolPath:
    """``tp`` with each run of :func:`straight_runs` one line block (a block alone: itself). The
    last one made is kept with its runs (its own caches, the pulse table among them, then serve
    every plan of the same runs)."""
    key, last = run.tobytes(), tp._cache.get("merged_path")
    if last is not None and last[0] == key:
        return last[1]
    _, last = run_bounds(run)
    merged = ToolPath(tp.start, tp.ends[last], tp.centers[last], tp.normals[last], tp.sweeps[last])
    tp._cache["merged_path"] = (key, merged)
    return merged


def split_plan(merged, pieces, first_motion, tp: ToolPath, merged_tp: ToolPath, run: np.ndarray, plan_type):
    """The plan of ``tp`` from the plan ``merged`` of ``merged_tp`` (:func:`merged_path` of ``run``;
    ``plan_type``: the planner's ``FIRPlan``). A block alone in its run keeps its merged values. In
    a run of several, each block's pulse starts and ends where the input passes its ends along the
    run's line pieces (head, body, tail: lengths ``fraction L``, durations ``fraction T_v``;
    ``pieces = (fraction, piece_tv)`` ``(P,)`` each of the merged plan, ``first_motion`` ``(M_merged,)``
    the first motion piece of each merged block), its arc length scaled to the run's chord; its
    feed is the fastest piece's over its stretch; the run's inner vertices take full overlap ``T_d``
    and the corner instant ``T_d / 2`` after the block's end (eq 11, ``T_k = T_d``). The vertices
    between runs keep the merged overlaps and corner instants; the profile, deviation and rounds are
    the merged plan's. NumPy or JAX alike (a traced plan maps to a traced plan: the same values,
    differentiable through the merged plan's timing)."""
    xp = _xp(merged.start_times, merged.delays, pieces[1])
    M = tp.n_blocks
    first, last = run_bounds(run)
    delays = merged.delays if xp is jnp else np.asarray(merged.delays)
    Td = 0.0
    for i in range(delays.shape[0]):  # summed in order, as the planner's T_d
        Td = Td + delays[i]
    run_start, run_pulse = xp.asarray(merged.start_times), xp.asarray(merged.pulse_times)
    t0, t1 = run_start[run], (run_start + run_pulse)[run]
    feeds = xp.asarray(merged.feeds)[run]
    several = (last - first)[run] > 0  # blocks in runs of two or more (lines)
    if several.any():
        k = np.flatnonzero(several)
        m = run[k]
        L = merged_tp.lengths[m]  # the run's chord [mm]
        cum = np.concatenate([[0.0], np.cumsum(tp.lengths)])
        scale = L / (cum[last + 1] - cum[first])[m]
        c0 = (cum[k] - cum[first[m]]) * scale
        c1 = np.where(k == last[m], L, (cum[k + 1] - cum[first[m]]) * scale)
        p = first_motion[m][:, None] + np.arange(3)[None, :]  # (K, 3) head, body, tail
        frac, tv = np.asarray(pieces[0])[p], pieces[1][p]
        length, duration = frac * L[:, None], frac * tv
        lo = np.concatenate([np.zeros((k.size, 1)), np.cumsum(length, axis=1)[:, :2]], axis=1)
        hi = lo + length

        def time_at(c):  # time [s] after the run's pulse start at which the input passes arc length c
            pos = length > 0
            share = np.where(pos, np.clip((c[:, None] - lo) / np.where(pos, length, 1.0), 0.0, 1.0), 0.0)
            return xp.sum(share * duration, axis=1)

        t0 = _set(t0, k, run_start[m] + xp.where(k == first[m], 0.0, time_at(c0)))
        t1 = _set(t1, k, xp.where(k == last[m], t1[k], run_start[m] + time_at(c1)))
        covers = (hi > c0[:, None]) & (lo < c1[:, None]) & (length > 0)
        speed = L[:, None] / tv
        feeds = _set(feeds, k, xp.where(covers.any(axis=1), xp.max(xp.where(covers, speed, 0.0), axis=1), feeds[k]))
    inner = run[:-1] == run[1:]  # vertices inside a run
    overlaps, centre = xp.full(M - 1, 1.0) * Td, t1[:-1] + 0.5 * Td
    outer = np.flatnonzero(~inner)
    overlaps = _set(overlaps, outer, xp.asarray(merged.overlaps))
    centre = _set(centre, outer, xp.asarray(merged.corner_times))
    return plan_type(device_array(t0), device_array(t1 - t0), device_array(overlaps), device_array(feeds),
                     merged.delays, merged.profile, device_array(centre), device_array(tp.vertices),
                     merged.path_deviation, merged.rounds, tp.axes)


def _xp(*arrays):
    """``jax.numpy`` where one of ``arrays`` is a JAX tracer (a traced plan), NumPy otherwise."""
    return jnp if any(isinstance(a, jax.core.Tracer) for a in arrays) else np


def _set(a, idx, values):
    """``a`` with ``a[idx] = values``: in place on a NumPy array, a new array on a JAX one."""
    if isinstance(a, np.ndarray):
        a[idx] = values
        return a
    return a.at[idx].set(values)


#: most ramp steps cut at each end of one line (:func:`ramp_pieces`)
MAX_RAMP_STEPS = 32


def ramp_pieces(tp: ToolPath, run, feeds: np.ndarray, delays: np.ndarray, limits, arcs: bool = False):
    """Lines (and with ``arcs``, arcs: :func:`_arc_ramps`) that cannot start or stop at their feed
    under axis limits, cut into the steps of a ramp.

    With fixed delays a line starting from rest at feed ``F`` peaks at ``F / T1`` in acceleration
    and ``F / (T1 T2)`` in jerk (Sencer 2015 §2.1); under limits below those one block runs at the
    feed of its own start and stop (``_fir_limits.feed_caps``) all the way. An isolated velocity
    step ``dV`` peaks at ``dV / T1`` and ``dV / (T1 T2)`` (``_fir_limit_spread.FeedSteps``), and
    steps at least ``T_d`` apart do not add. So each end of a straight run (``run`` ``(M,)``,
    :func:`straight_runs`; each block its own where None) whose line cannot start at its feed
    ``feeds`` (and is not held by its velocity limit) is cut into pieces commanded at ``k F / n``,
    ``k = 1 .. n - 1``, ``n = ceil(F / dV)`` (at most :data:`MAX_RAMP_STEPS`), ``dV`` the largest
    step the axes allow along the line, each lasting ``T_d`` at its feed, while the two ends' cuts
    stay apart. The run's own vertices stay: a piece they cut keeps its feed on both sides.

    Returns:
        ``(piece path, block of every piece (P,), PieceFeeds)``, or None (nothing to cut; with
        ``arcs``, no arc to cut: the path would be the one without); ``PieceFeeds.of(feeds)``
        gives the commanded feed of every piece (its recipe holds, so that a traced feed stays traced).
    """
    M = tp.n_blocks
    first, last = run_bounds(np.arange(M) if run is None else run)
    d = np.sort(np.asarray(delays, dtype=np.float64))[::-1]
    Td = float(d.sum())
    V = np.vstack([tp.start, tp.ends])
    chord = V[last + 1] - V[first]
    L = np.linalg.norm(chord, axis=1)
    line = ~tp.is_arc[first] & (L > 0)
    u = np.abs(chord) / np.where(L > 0, L, 1.0)[:, None]
    step_axis = limits.acceleration * d[0]
    if d.size > 1:
        step_axis = np.minimum(step_axis, limits.jerk * d[0] * d[1])
    with np.errstate(divide="ignore"):
        dV = np.min(np.where(u > 0, step_axis[None, :] / u, np.inf), axis=1)
        v_cap = np.min(np.where(u > 0, limits.velocity[None, :] / u, np.inf), axis=1)
    top = np.minimum(feeds[first], v_cap)
    n = np.where(np.isfinite(dV) & (dV > 0), np.minimum(np.ceil(top / np.where(dV > 0, dV, 1.0)), MAX_RAMP_STEPS + 1), 1)
    # a ramp of at least one step whose first piece fits in half the line
    ramp = line & (feed_caps(L, u, d, limits) < top) & (n >= 2) & (top / n * Td < 0.5 * L)
    if arcs:
        arcs = _arc_ramps(tp, feeds, d, limits, arc_limit_caps(tp.radii, d, limits))
        if not arcs[0].size:
            return None
    else:
        arcs = (np.zeros(0, np.int64), np.zeros(0), np.zeros(0, np.int64))
        if not ramp.any():
            return None
    cum = np.concatenate([[0.0], np.cumsum(tp.lengths)])
    # the feed of every piece as min(feeds[src], cap) / den * num (PieceFeeds); first the piece
    # ending at each block's end (its own feed unless a ramp covers it), then the cut pieces
    end_rec = np.stack([np.arange(M, dtype=np.float64), np.full(M, np.inf), np.ones(M), np.ones(M)], axis=1)
    cut_block, cut_frac, cut_rec = [], [], []
    for m in np.flatnonzero(ramp):
        a, b = first[m], last[m]
        k_step = np.arange(1, int(n[m]), dtype=np.float64)
        steps = top[m] / n[m] * k_step  # the feeds of the ramp pieces [mm/s]
        at = np.cumsum(steps * Td)  # where each ends, from the run's end [mm]
        keep = at < 0.5 * L[m] * (1.0 - 1e-9)  # the two ends' cuts apart (not one point rounded twice)
        steps, at, k_step = steps[keep], at[keep], k_step[keep]
        ones = np.ones_like(k_step)
        rec = np.stack([a * ones, v_cap[m] * ones, n[m] * ones, k_step], axis=1)  # (src, cap, den, num) of steps
        rec_stretch = np.concatenate([rec, [[a, np.inf, 1.0, 1.0]], rec[::-1]])
        span = cum[b + 1] - cum[a]
        s_cut = np.concatenate([at, L[m] - at[::-1]]) * (span / L[m])  # along the run's blocks [mm]
        s_end = cum[a + 1: b + 2] - cum[a]  # each block's end along the run
        k = a + np.searchsorted(s_end[:-1], s_cut, side="right")  # the block each cut falls on
        frac = (s_cut - (cum[k] - cum[a])) / tp.lengths[k]
        keep = (frac > 1e-9) & (frac < 1.0 - 1e-9)  # not on a vertex of the run
        cut_block.append(k[keep]), cut_frac.append(frac[keep])
        cut_rec.append(rec_stretch[np.searchsorted(s_cut, s_cut[keep], side="left")])
        end_rec[a: b + 1] = rec_stretch[np.searchsorted(s_cut, s_end * (1.0 - 1e-12), side="left")]
    for b, top_b, n_b in zip(*arcs):  # an arc's ramp: the same steps along its arc length
        k_step = np.arange(1, n_b, dtype=np.float64)
        at = np.cumsum(top_b / n_b * k_step * Td)  # where each step ends, from the arc's end [mm]
        ones = np.ones_like(k_step)
        rec = np.stack([b * ones, top_b * ones, n_b * ones, k_step], axis=1)
        rec_stretch = np.concatenate([rec, [[b, top_b, 1.0, 1.0]], rec[::-1]])
        cut_block.append(np.full(2 * at.size, b)), cut_frac.append(np.concatenate([at, tp.lengths[b] - at[::-1]]) / tp.lengths[b])
        cut_rec.append(rec_stretch[:-1])  # the piece ending at each cut
        end_rec[b] = rec_stretch[-1]
    cut_block, cut_frac, cut_rec = np.concatenate(cut_block), np.concatenate(cut_frac), np.concatenate(cut_rec)
    if not cut_block.size:
        return None
    # the pieces in path order: each block's cut points, then its own end; an arc's pieces are
    # arcs about its centre and axis (the same curve, helical or spiral alike), a line's lines
    block = np.concatenate([cut_block, np.arange(M)])
    order = np.lexsort((np.concatenate([cut_frac, np.full(M, 2.0)]), block))
    on_arc = tp.is_arc[cut_block]
    points = V[cut_block] + cut_frac[:, None] * (V[cut_block + 1] - V[cut_block])
    if on_arc.any():
        k = cut_block[on_arc]
        points[on_arc] = tp.arc_points(k, cut_frac[on_arc] * tp.sweeps[k])
    ends = np.vstack([points, tp.ends])[order]
    rec = np.concatenate([cut_rec, end_rec])[order]
    f_end = np.concatenate([cut_frac, np.ones(M)])[order]
    block = block[order]
    f_start = np.where(np.concatenate([[False], block[1:] == block[:-1]]), np.concatenate([[0.0], f_end[:-1]]), 0.0)
    arc = tp.is_arc[block]
    centers = np.where(arc[:, None], tp.centers[block], np.nan)
    normals = np.where(arc[:, None], tp.normals[block], np.nan)
    sweeps = np.where(arc, (f_end - f_start) * tp.sweeps[block], 0.0)
    recipe = PieceFeeds(rec[:, 0].astype(np.int64), rec[:, 1], rec[:, 2], rec[:, 3])
    return ToolPath(tp.start, ends, centers, normals, sweeps), block, recipe


def _arc_ramps(tp: ToolPath, feeds: np.ndarray, d: np.ndarray, limits, safe: np.ndarray):
    """Ramps of the arc blocks that cannot start or stop at their feed under axis limits:
    ``(block (B,), top feed (B,) [mm/s], steps n (B,))`` of each arc that ramps.

    An arc alone runs at ``safe`` (``_fir_limits.arc_limit_caps``: its start and stop edges on top
    of its centripetal acceleration and its rotation). In motion at a feed ``F`` it needs only the
    steady parts, ``F^2 / R`` and ``F^3 / R^2``; a step ``dV`` at feeds up to ``F`` adds ``dV / T1`` in
    acceleration and ``dV / (T1 T2) + 2 F dV / (R T2)`` in jerk (the step's own edge and the
    centripetal change ``2 F dV / R`` switched on through ``T2``), each bound by the smallest limit
    over the axes (the tangent sweeps the plane). So the arc can ramp to ``F`` in steps of ``F / n``
    where ``F / n <= dV(F)``; for each ``n = 2 .. MAX_RAMP_STEPS + 1`` the largest such ``F`` (at most
    the commanded feed and the velocity limit) is found by bisection, and the ``n`` of least arc time
    ``2 (n - 1) T_d + (L - F T_d (n - 1)) / F`` whose two ramps fit in the arc is kept, where it
    beats the whole arc at ``safe``. A bound, not a guarantee: the planner's exact peaks decide."""
    arc = np.flatnonzero(tp.is_arc)
    if not arc.size:
        return np.zeros(0, np.int64), np.zeros(0), np.zeros(0, np.int64)
    T1 = d[0]
    T2 = d[1] if d.size > 1 else d[0]
    Td = float(d.sum())
    v, a, j = float(np.min(limits.velocity)), float(np.min(limits.acceleration)), float(np.min(limits.jerk))
    R, L = tp.radii[arc], tp.lengths[arc]
    cap = np.minimum(feeds[arc], v)
    n = np.arange(2, MAX_RAMP_STEPS + 2, dtype=np.float64)[None, :]

    def short(F):  # step F / n above what the limits allow at feed F (per arc, per n)
        with np.errstate(invalid="ignore", divide="ignore"):
            acc = T1 * (a - F**2 / R[:, None])
            jerk = (j - F**3 / R[:, None] ** 2) / (1.0 / (T1 * T2) + 2.0 * F / (R[:, None] * T2)) if np.isfinite(j) else np.inf
        return F / n > np.minimum(acc, jerk)

    lo, hi = np.zeros((arc.size, n.size)), np.broadcast_to(cap[:, None], (arc.size, n.size)).copy()
    fits = ~short(hi)
    lo = np.where(fits, hi, lo)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        bad = short(mid)
        lo, hi = np.where(fits | bad, lo, mid), np.where(fits | ~bad, hi, mid)
    top = lo
    ramp_len = top * Td * (n - 1)  # both ends
    with np.errstate(divide="ignore", invalid="ignore"):
        time = np.where((top > 0) & (ramp_len < L[:, None]), 2 * (n - 1) * Td + (L[:, None] - ramp_len) / top, np.inf)
    best = np.argmin(time, axis=1)
    t_best = time[np.arange(arc.size), best]
    with np.errstate(divide="ignore"):
        keep = np.isfinite(t_best) & (t_best < L / safe[arc])
    return arc[keep], top[np.arange(arc.size), best][keep], (best + 2)[keep].astype(np.int64)


class PieceFeeds(NamedTuple):
    """The commanded feed of every piece of a :func:`ramp_pieces` path, ``min(feeds[src], cap) /
    den * num`` from the blocks' commanded feeds (a ramp step ``k top / n`` with ``top`` the run's
    feed capped at its velocity limit; a piece no ramp covers: its block's feed). Held as this
    recipe so that the feeds of a traced plan stay traced (``jax.grad`` through the ramp)."""

    src: np.ndarray  # (P,) block whose commanded feed the piece takes
    cap: np.ndarray  # (P,) velocity cap along the line [mm/s] (inf: none)
    den: np.ndarray  # (P,) steps n of the ramp (1 off the ramp)
    num: np.ndarray  # (P,) step k of the ramp (1 off the ramp)

    def of(self, feeds):
        """``(P,)`` feeds [mm/s] of the pieces from the blocks' ``(M,)`` (NumPy, or JAX if traced)."""
        xp = _xp(feeds)
        return xp.minimum(xp.asarray(feeds)[self.src], self.cap) / self.den * self.num


def join_plan(pieces, tp: ToolPath, block: np.ndarray, plan_type):
    """The plan of ``tp`` from the plan ``pieces`` of its :func:`ramp_pieces` path (``block``: the
    block of every piece): a block's pulse runs from its first piece's start to its last piece's
    end, its feed is its fastest piece's, and each vertex of ``tp`` keeps the overlap and corner
    instant of the piece vertex it is; the profile, deviation and rounds are the pieces' plan's.
    NumPy or JAX alike (a traced plan maps to a traced plan)."""
    xp = _xp(pieces.start_times, pieces.feeds)
    first, last = run_bounds(block)
    start, pulse = xp.asarray(pieces.start_times), xp.asarray(pieces.pulse_times)
    if xp is np:
        feeds = np.maximum.reduceat(np.asarray(pieces.feeds), first)
    else:
        feeds = jax.ops.segment_max(pieces.feeds, jnp.asarray(block), num_segments=tp.n_blocks, indices_are_sorted=True)
    return plan_type(device_array(start[first]), device_array(start[last] + pulse[last] - start[first]),
                     device_array(xp.asarray(pieces.overlaps)[last[:-1]]), device_array(feeds), pieces.delays,
                     pieces.profile, device_array(xp.asarray(pieces.corner_times)[last[:-1]]),
                     device_array(tp.vertices), pieces.path_deviation, pieces.rounds, tp.axes)
