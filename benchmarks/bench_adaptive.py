"""Planning cost against program length on adaptive-clearing programs (issue "FIR cornering on real
CAM programs": a micro-segment rule that "is linear in the number of segments").

Usage::

    python benchmarks/bench_adaptive.py [--loops 250 500 1000 2000] [--eps-um 50] [--seed 0]

Each program is written as G-code text the way a CAM post writes adaptive clearing, then read with
``parse_gcode``: a Fanuc-style header (``G90 G94 G17``, ``G21``, ``G28 G91 Z0.``, ``T1 M6``,
``G43 Z15. H1``), a helical entry (six half-turn ``G3`` arcs of radius 2.5 mm down to z = -3),
then ``--loops`` trochoidal loops of a G1 step, a ``G3`` arc of radius 0.4-2 mm (centre words),
a G1 link and a ``G2`` R-format return arc, every 100 loops a retract, rapid and plunge; every
number written to 3 decimals of mm, as posts do (so arc radii are rounded by up to about 1.4 um,
LinuxCNC's tolerance). F 2400 mm/min cutting, 800 plunging, rapids at the reader's 15000 mm/min;
T1/T2 = 60/30 ms.

Prints per program: blocks, arcs, cycle time, planning time (the first call on a short part of the
program, compilation, apart), microseconds per block, the check's path samples and how many
candidates reached a full check; then the exponent of planning time against block count (log-log
slope over the sizes; 1 = linear) with its target: at most 1.1 (MISS above). Times are wall time of
one warm call on a shared machine: compare exponents and ratios, not absolute numbers.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from research.paths.gcode import parse_gcode

DELAYS = (0.06, 0.03)  # T1, T2 [s]
HOME = (0.0, 0.0, 50.0)  # the G28 target [mm, program frame]
EXPONENT_TARGET = 1.1  # linear in the block count, with 10 % for the machine's noise


def _f3(v: float) -> str:
    """A coordinate as a post writes it: 3 decimals, trailing zeros dropped, ``0.`` for zero."""
    return f"{v:.3f}".rstrip("0").rstrip(".") if abs(v) >= 5e-4 else "0."


def adaptive_program(seed: int, loops: int) -> str:
    """G-code text of a seeded adaptive-clearing program (module docstring)."""
    rng = np.random.default_rng(seed)
    out = ["%", "O1001 (ADAPTIVE)", "N10 G90 G94 G17", "N15 G21", "N20 G28 G91 Z0.", "N25 G90", "T1 M6",
           "S12000 M3", "G54", "M8", "G0 X0. Y0.", "G43 Z15. H1", "G0 Z5."]
    r = 2.5
    out.append(f"G1 X{_f3(r)} Y0. Z1. F800.")
    x, y, z = r, 0.0, 1.0
    for _ in range(6):  # helical entry: half turns down to z = -3
        z -= 0.6667
        out.append(f"G3 X{_f3(-x)} Y{_f3(-y)} Z{_f3(z)} I{_f3(-x)} J{_f3(-y)}")
        x, y = -x, -y
    out.append(f"G1 X{_f3(x)} Y0. F2400.")
    for loop in range(loops):
        rr, step = rng.uniform(0.4, 2.0), rng.uniform(0.2, 0.6)
        x, y = round(x + step, 3), round(y, 3)
        out.append(f"G1 X{_f3(x)} Y{_f3(y)}")
        cx, cy = x, y + rr
        ex, ey = round(cx + rr * np.sin(2.5), 3), round(cy - rr * np.cos(2.5), 3)
        out.append(f"G3 X{_f3(ex)} Y{_f3(ey)} I{_f3(round(cx - x, 3))} J{_f3(round(cy - y, 3))}")
        x, y = ex, ey
        x, y = round(x + 0.3, 3), round(y - 0.2, 3)
        out.append(f"G1 X{_f3(x)} Y{_f3(y)}")
        tx, ty = round(x + 0.5, 3), 0.0
        out.append(f"G2 X{_f3(tx)} Y{_f3(ty)} R{_f3(0.5 * np.hypot(tx - x, ty - y) + 0.3)}")
        x, y = tx, ty
        if loop % 100 == 99:
            out += ["G0 Z15.", f"G0 X{_f3(x + 2)} Y{_f3(y + 5)}", "G0 Z5.", f"G1 Z{_f3(z)} F800.",
                    f"G1 X{_f3(x)} Y{_f3(y)} F2400."]
    out += ["G0 Z15.", "M9", "G28 G91 Z0.", "G90", "M5", "M30", "%"]
    return "\n".join(out) + "\n"


def _counting_checks():
    """Wrap ``RoundChecks`` to count path samples and candidates checked; returns the counter."""
    import research.interpolators._fir_verify as verify

    count = {"samples": 0, "candidates": 0}
    check, init = verify.RoundChecks.samples_check, verify.RoundChecks.__init__

    def samples_check(self):
        result = check(self)
        count["samples"] += self.samples
        return result

    def __init__(self, *args, **kwargs):
        count["candidates"] += 1
        init(self, *args, **kwargs)

    verify.RoundChecks.samples_check, verify.RoundChecks.__init__ = samples_check, __init__
    return count


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--loops", type=int, nargs="+", default=[250, 500, 1000, 2000], help="trochoidal loops per program")
    ap.add_argument("--eps-um", type=float, default=50.0, help="cornering tolerance [um]")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    from research.interpolators import plan_fir

    count = _counting_checks()
    eps = args.eps_um * 1e-3
    print(f"load {os.getloadavg()[0]:.1f}; eps {args.eps_um:g} um, T1/T2 = {DELAYS[0] * 1e3:g}/{DELAYS[1] * 1e3:g} ms")
    print(f"{'loops':>6} {'blocks':>7} {'arcs':>6} {'cycle [s]':>10} {'plan [s]':>9} {'us/block':>9} "
          f"{'samples':>10} {'candidates':>10}")
    blocks, times = [], []
    for loops in args.loops:
        prog = parse_gcode(adaptive_program(args.seed, loops), source=f"adaptive-{loops}", home=HOME)
        tp = prog.blocks
        t0 = time.perf_counter()
        plan_fir(tp.part(0, 100), prog.block_feeds[:100], DELAYS, eps)
        compile_s = time.perf_counter() - t0
        count["samples"] = count["candidates"] = 0
        t0 = time.perf_counter()
        plan = plan_fir(tp, prog.block_feeds, DELAYS, eps, pauses=prog.block_pauses)
        dt = time.perf_counter() - t0
        blocks.append(tp.n_blocks)
        times.append(dt)
        print(f"{loops:>6} {tp.n_blocks:>7} {int(tp.is_arc.sum()):>6} {float(plan.cycle_time):>10.3f} {dt:>9.3f} "
              f"{1e6 * dt / tp.n_blocks:>9.0f} {count['samples']:>10} {count['candidates']:>10}"
              f"   (first call on 100 blocks {compile_s:.2f} s)", flush=True)
    if len(blocks) > 1:
        slope = float(np.polyfit(np.log(blocks), np.log(times), 1)[0])
        verdict = "PASS" if slope <= EXPONENT_TARGET else "MISS"
        print(f"planning time ~ blocks^{slope:.2f} (target <= {EXPONENT_TARGET}: {verdict})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
