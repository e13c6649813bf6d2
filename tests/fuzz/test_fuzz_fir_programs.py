"""Fuzz test of the FIR planner on random G-code programs, as a CAM post or a hand-written program
gives them: lines of 5 um - 10 mm in 3-D, arcs of R 0.3-20 mm in the G17, G18 and G19 planes (I/J/K
or R words, helical, full circles), incremental moves (``G91``), rapids, ``G64 P`` tolerances changed
mid-program, ``G61`` (exact path: a ``G64`` is given before an arc, see ``stages.interpolate``),
``G4`` dwells and ``M0`` stops, feeds of 300-12,000 mm/min, all written to 4 decimals.

Each program is read with ``parse_gcode`` and planned with its feeds, ``G64 P`` tolerances (a drawn
eps elsewhere), pauses and, for 40 % of them, per-axis limits at 0.05-1x the FIR envelope's
acceleration and jerk, under one of four delay sets (two and three filters), at the planners'
default check period. Checked against independent computations: every sample of the 0.2 ms
trajectory within the tolerance of the blocks its window averages (the largest of those whose
reference pulses meet ``[t - T_d, t]``; 1e-3 of it more, the share ``plan_fir`` allows between its
samples) of the path (``ToolPath.distance``), the end point reached (1e-8 mm) and, with limits, the
sampled peaks within them (``metrics.limit_ratios``, 1e-6).

The same programs through ``plan_fir_mirror`` (its filters' input moved off the path): the same
checks (against the program's largest tolerance where its plan's blocks are arcs' chords, which
are not the program's blocks), and never slower than ``plan_fir``.

Examples: ``RESEARCH_FUZZ_EXAMPLES_FIR`` (default 6 here, the file runs in about a minute); a session
ran 830 programs of 3-300 blocks with no failure (README, 2026-12-04 fifth), another 100 through
``plan_fir_mirror`` (2026-12-05, second); with the local tolerance and default check periods, 400
through ``plan_fir`` and 150 through the mirror (2026-12-05, eleventh).
"""

from __future__ import annotations

import os

import numpy as np
import pytest

from research.interpolators import plan_fir, plan_fir_mirror
from research.limits import AxisLimits
from research.metrics import limit_ratios
from research.paths.gcode import parse_gcode

EXAMPLES = int(os.environ.get("RESEARCH_FUZZ_EXAMPLES_FIR", "6"))
DELAY_SETS = ((0.06, 0.03), (0.02, 0.01), (0.03, 0.02, 0.005), (0.01, 0.004))


def _f4(v: float) -> str:
    return f"{v:.4f}"


def random_program(rng: np.random.Generator, blocks: int) -> str:
    """G-code text of a seeded random program (module docstring)."""
    out = ["G21 G90 G17 G94", "G0 X0 Y0 Z0", f"G1 X0 Y0 Z0 F{rng.uniform(300, 12000):.0f}"]
    p, plane, exact = np.zeros(3), 17, False
    for _ in range(blocks):
        r = rng.random()
        if r < 0.05:
            out.append(f"G64 P{rng.choice([0.005, 0.02, 0.05, 0.2])}")
            exact = False
        elif r < 0.07:
            out.append("G61")
            exact = True
        elif r < 0.09:
            out.append(f"G4 P{rng.uniform(0, 0.3):.3f}")
        elif r < 0.10:
            out.append("M0")
        elif r < 0.14:
            plane = int(rng.choice([17, 18, 19]))
            out.append(f"G{plane}")
        elif r < 0.50:
            length = float(rng.choice([0.005, 0.02, 0.1, 0.5, 2.0, 10.0]))
            d = rng.normal(size=3)
            d[2] *= rng.choice([0.0, 0.2, 1.0])
            q = np.round(p + length * d / np.linalg.norm(d), 4)
            if np.allclose(q, p):
                continue
            if rng.random() < 0.15:
                dq = q - p
                out += [f"G91 G1 X{_f4(dq[0])} Y{_f4(dq[1])} Z{_f4(dq[2])}", "G90"]
            else:
                g = "G0" if rng.random() < 0.05 else "G1"
                out.append(f"{g} X{_f4(q[0])} Y{_f4(q[1])} Z{_f4(q[2])} F{rng.uniform(300, 12000):.0f}")
            p = q
        else:
            if exact:
                out.append("G64")
                exact = False
            ax = {17: (0, 1, 2), 18: (2, 0, 1), 19: (1, 2, 0)}[plane]
            radius, a0 = float(rng.choice([0.3, 1.0, 5.0, 20.0])), rng.uniform(-np.pi, np.pi)
            c = p.copy()
            c[ax[0]] += radius * np.cos(a0)
            c[ax[1]] += radius * np.sin(a0)
            sweep = rng.uniform(0.1, 2 * np.pi) if rng.random() < 0.9 else 2 * np.pi
            ccw = rng.random() < 0.5
            b = a0 + np.pi + (sweep if ccw else -sweep)
            q = c.copy()
            q[ax[0]] += radius * np.cos(b)
            q[ax[1]] += radius * np.sin(b)
            q[ax[2]] = p[ax[2]] + (rng.uniform(-1, 1) if rng.random() < 0.3 else 0.0)
            q = np.round(q, 4)
            if sweep < np.pi and rng.random() < 0.3:
                words = f"R{_f4(radius)}"
            else:
                off = c - p
                names = {17: ("I", "J"), 18: ("K", "I"), 19: ("J", "K")}[plane]
                words = f"{names[0]}{_f4(off[ax[0]])} {names[1]}{_f4(off[ax[1]])}"
            out.append(f"{'G3' if ccw else 'G2'} X{_f4(q[0])} Y{_f4(q[1])} Z{_f4(q[2])} {words}")
            p = q
    out.append("M30")
    return "\n".join(out) + "\n"


def _drawn(seed: int):
    """``(path, feeds, delays, tolerances, limits, pauses)`` of the seeded program (module docstring)."""
    rng = np.random.default_rng(seed)
    text = random_program(rng, int(rng.integers(3, 40)))
    eps = float(np.exp(rng.uniform(np.log(0.003), np.log(0.3))))
    delays = DELAY_SETS[int(rng.integers(len(DELAY_SETS)))]
    prog = parse_gcode(text, source=f"fuzz-{seed}.ngc")
    tp = prog.blocks
    tol = np.where(np.isfinite(prog.block_tolerance), prog.block_tolerance, eps)
    limits = None
    if rng.random() < 0.4:
        env = AxisLimits.fir_envelope(tp.dim, float(np.max(prog.block_feeds)), delays)
        s = float(np.exp(rng.uniform(np.log(0.05), 0.0)))
        limits = AxisLimits(env.velocity, s * env.acceleration, s * env.jerk)
    return tp, prog.block_feeds, delays, tol, limits, prog.block_pauses


def _local_tolerance(plan, tol: np.ndarray, t: np.ndarray) -> np.ndarray:
    """``(N,)`` the largest tolerance [mm] of the blocks whose reference pulses meet the window
    ``[t - T_d, t]`` of each sample time ``t`` [s]: the output averages the reference over that
    window (eq 1-4), so those blocks are the only ones it may round. A direct range maximum."""
    starts, Td = np.asarray(plan.start_times), float(np.sum(np.asarray(plan.delays)))
    first = np.clip(np.searchsorted(starts, t - Td, side="right") - 1, 0, starts.size - 1)
    last = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, starts.size - 1)
    return np.array([tol[i: max(j, i) + 1].max() for i, j in zip(first, last)])


def _check(plan, tp, tol, limits, local: bool = True) -> None:
    """The module docstring's checks; ``local``: each sample against the tolerance of the blocks
    its window averages (``plan``'s blocks are the program's), else against the program's largest."""
    traj = plan.trajectory(2e-4)
    q, t = np.asarray(traj.q), np.asarray(traj.t)
    tol = np.asarray(tol, dtype=np.float64)
    allowed = _local_tolerance(plan, tol, t) if local else np.max(tol)
    assert np.all(tp.distance(q) <= allowed * (1 + 1e-3) + 1e-9)
    assert np.linalg.norm(q[-1] - tp.ends[-1]) < 1e-8
    if limits is not None:
        assert all(np.all(r <= 1 + 1e-6) for r in limit_ratios(plan.trajectory(1e-3), limits).values())


@pytest.mark.parametrize("seed", range(EXAMPLES))
def test_random_programs_keep_tolerance_limits_and_end_point(seed):
    tp, feeds, delays, tol, limits, pauses = _drawn(seed)
    _check(plan_fir(tp, feeds, delays, tol, limits=limits, pauses=pauses), tp, tol, limits)


@pytest.mark.parametrize("seed", range(EXAMPLES))
def test_random_programs_through_the_mirror_keep_tolerance_limits_and_end_point(seed):
    tp, feeds, delays, tol, limits, pauses = _drawn(seed)
    m = plan_fir_mirror(tp, feeds, delays, tol, limits=limits, pauses=pauses)
    _check(m.plan, tp, tol, limits, local=m.plan.start_times.shape[0] == tp.n_blocks)
    assert m.cycle_time <= m.plain_cycle_time * (1 + 1e-12)
