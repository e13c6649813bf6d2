"""Closed-loop identification benchmark (issue 4): PSO against optimistix on the same data and objective.

Usage::

    python benchmarks/bench_identification.py [--quick] [--emps PATH]

Data: the thesis Table 6.1 (P-PI) and Table 6.2 (PID) virtual drives run on the §6.5 program (seed 0,
0.05 um encoder, dc = 585.3 mm/s^2) and, when the file is present, the EMPS estimation part (t < 12 s).
Objective: eq 6.18 with eq 6.21 inside (variable projection), evaluated through the same QR-reduced
:class:`ProjectedProblem` by both solvers (identical to the N-sample objective, checked by the tests).

Rows per data set:

* LS (eq 6.12) solve time, and the time to build the eq 6.9 regression and its QR (shared by all methods);
* PSO, thesis settings (1 swarm of 200, 100 iterations), and PSO with 16 swarms (what the tests use);
* PSO, 1 swarm, evaluating eq 6.21 on all N samples per particle (the thesis' cost model);
* optimistix Levenberg-Marquardt (grid starts + bounded variable projection): first call (compilation
  included) and warm (median of 5 calls).

Target: optimistix warm >= 50x faster than the thesis PSO at equal or lower loss (loss within 1e-9
relative counts as equal). Each target line prints PASS or MISS as measured; nothing is tuned to pass.
"""

from __future__ import annotations

import argparse
import pathlib
import time

import numpy as np

from research.drives import (
    ClosedLoopModel,
    Encoder,
    table_6_1_closed_loop,
    table_6_2_closed_loop,
)
from research.identification import (
    THESIS_LS_DC,
    ProjectedProblem,
    PSOSettings,
    bounded_fit,
    build_regression,
    identification_program,
    least_squares,
    load_emps,
    particle_swarm,
    synthetic_log,
)
from research.identification._projection import PoleBounds
from research.identification._pso import _swarm

EMPS_DEFAULT = pathlib.Path(__file__).resolve().parents[2] / "shared" / "data" / "emps" / "emps_estimation_first15s.mat"


def _timed(fn, repeat=1):
    times, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return out, float(np.median(times))


def bench(name: str, log, quick: bool) -> None:
    (prob, t_build) = _timed(lambda: ProjectedProblem.from_regression(build_regression(log)))
    ls, t_ls = _timed(lambda: least_squares(prob.regression), repeat=5)
    pso1, t_pso1 = _timed(lambda: particle_swarm(prob, seed=0))
    pso16, t_pso16 = _timed(lambda: particle_swarm(prob, seed=0, settings=PSOSettings(swarms=16)))
    lm_cold, t_cold = _timed(lambda: bounded_fit(prob))
    lm, t_warm = _timed(lambda: bounded_fit(prob), repeat=5)
    print(f"\n== {name}: N = {prob.regression.Y.size} regression rows ==")
    print(f"  build eq 6.9 regression + QR : {1e3 * t_build:9.2f} ms (shared by every method)")
    print(f"  LS eq 6.12                   : {1e3 * t_ls:9.2f} ms   loss {ls.loss:.9g}   stable {ls.stable}")
    print(f"  PSO thesis (1 x 200 x 100)   : {1e3 * t_pso1:9.2f} ms   loss {pso1.loss:.9g}")
    print(f"  PSO 16 swarms                : {1e3 * t_pso16:9.2f} ms   loss {pso16.loss:.9g}")
    if not quick:
        full, t_full = _timed(lambda: _swarm(prob.loss_full, PoleBounds.thesis(), PSOSettings(), 0))
        print(f"  PSO thesis, N-sample eq 6.21 : {1e3 * t_full:9.2f} ms   loss {full[1]:.9g}")
    print(f"  optimistix LM, first call    : {1e3 * t_cold:9.2f} ms   loss {lm_cold.loss:.9g} (compilation included)")
    print(f"  optimistix LM, warm          : {1e3 * t_warm:9.2f} ms   loss {lm.loss:.9g}   steps {lm.iterations}")
    for label, t_p, f_p in (("thesis PSO", t_pso1, pso1.loss), ("16-swarm PSO", t_pso16, pso16.loss)):
        ratio = t_p / t_warm
        equal_or_lower = lm.loss <= f_p * (1 + 1e-9)
        verdict = "PASS" if ratio >= 50 and equal_or_lower else "MISS"
        print(f"  target optimistix >= 50x faster than {label} at <= loss: {ratio:7.1f}x, "
              f"loss ratio {lm.loss / f_p:.9f} -> {verdict}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="skip the N-sample PSO and use a 30-move program")
    ap.add_argument("--emps", type=pathlib.Path, default=EMPS_DEFAULT, help="EMPS .mat file (skipped if absent)")
    args = ap.parse_args()
    ref = identification_program(0, n_moves=30 if args.quick else 70).trajectory()
    for table, base in (("Table 6.1 P-PI", table_6_1_closed_loop()), ("Table 6.2 PID", table_6_2_closed_loop())):
        truth = ClosedLoopModel(base.a1, base.a2, base.a3, base.b0, base.b1, base.b2, THESIS_LS_DC)
        bench(table, synthetic_log(truth, ref, encoder=Encoder(5e-5), seed=1), args.quick)
    if args.emps.exists():
        est, _ = load_emps(args.emps).split(12.0)
        bench("EMPS t < 12 s", est, args.quick)
    else:
        print(f"\nEMPS skipped: {args.emps} not found")


if __name__ == "__main__":
    main()
