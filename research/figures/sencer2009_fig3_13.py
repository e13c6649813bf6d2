"""Sencer (2009) thesis Fig 3.13: X, Y, Z, A, C tracking errors of the optimized feed (150 mm/s cap) against
constant 15, 40 and 150 mm/s feeds, simulated through the SISO SMC drives (Table 5.2, friction from
Fig 5.7, 0.1 ms) with the amplifier limit read from Table 3.1 (``u_max = m A + c V + d_c``), on the
public 300 mm blade-flank path of the Fig 3.11 module (the thesis' impeller CL data are not public).
Model and assumptions: :mod:`research.control._feed_tracking`. Samples at the amplifier limit are
marked. The runs are results-store entries (``.cache/results/store``); the figure only reads them.

``fast=True``: the 40-control-point schedule of the Fig 3.11 module's fast variant, the 0.25 ms control
period and the isolated-reversal friction estimate of the Fig 5 modules' fast variant
(:func:`research.figures.sencer2009_fig5_results.coulomb`); the full run uses the n = 276 schedule,
0.1 ms and the identified friction.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from research.figures._style import figure, save

NAME = "sencer2009_fig3_13_tracking_errors"
REPRODUCES = ("Sencer 2009 thesis Fig 3.13 (tracking errors of the optimized vs constant 15 / 40 mm/s feeds, "
              "actuator saturation; 150 mm/s constant: 'excessively saturated')")
CASES = ("optimized", "15", "40", "150")
_LABEL = {"optimized": "optimized (150 mm/s cap)", "15": "constant 15 mm/s", "40": "constant 40 mm/s",
          "150": "constant 150 mm/s"}
_STYLE = {"optimized": "k", "15": "C0", "40": "C2", "150": "C3"}
_AXES = (("X", 1e3, "um"), ("Y", 1e3, "um"), ("Z", 1e3, "um"), ("A", 1e3, "mrad"), ("C", 1e3, "mrad"))


def stored(case: str, fast: bool = False) -> dict:
    """One stored run: ``{"t", "axis_error", "saturated"}`` arrays and its ``"summary"`` (max errors,
    saturated fraction per axis, u_max, feed-forward demand per axis, diverged, cycle time)."""
    from research.control import CONTROL_PERIOD, thesis_plant
    from research.control._feed_tracking import amplifier_limits, feed_tracking
    from research.experiments.runner import DEFAULT_CACHE
    from research.experiments.store import ResultStore, result_key
    from research.figures import sencer2009_fig5_results as ch5
    from research.optimal import constant_feed, optimize_feedrate, table31_limits
    from research.paths.five_axis_library import blade_flank_path

    from research.errors import ParameterError

    if case not in CASES:
        raise ParameterError(f"case must be one of {CASES}, got {case!r}")
    T = ch5.FAST_PERIOD if fast else CONTROL_PERIOD
    config = dict(study="sencer2009_fig3_13", case=case, fast=bool(fast), T=T)
    store, key = ResultStore(Path(DEFAULT_CACHE) / "store"), result_key(config, kind="sencer2009_ch3")
    entry = store.get(key)
    if entry is None:
        path, limits = blade_flank_path(), table31_limits()
        if case == "optimized":
            sched = optimize_feedrate(path, limits, 150.0, control_points=40 if fast else 276,
                                      refinements=1 if fast else 3, sample_period=5e-3 if fast else 1e-3)
        else:
            sched = constant_feed(path, limits, float(case), sample_period=1e-3)
        plant = thesis_plant(ch5.coulomb(T, fast))
        u_max = amplifier_limits(plant, limits)
        run = feed_tracking(sched.trajectory, plant, u_max, T=T)
        tr = sched.trajectory
        demand = np.abs(np.asarray(plant.m) * np.asarray(tr.a) + np.asarray(plant.c) * np.asarray(tr.v)).max(axis=0) \
            + np.asarray(plant.coulomb)
        summary = dict(max_error=run.max_error().tolist(), saturated_fraction=run.saturated_fraction.tolist(),
                       u_max=run.u_max.tolist(), feedforward_demand=demand.tolist(), diverged=run.diverged,
                       cycle_time=float(sched.cycle_time),
                       acceleration_ratio=np.asarray(sched.check.acceleration_ratio).tolist())
        entry = store.put(key, dict(config, summary=summary),
                          dict(t=run.t, axis_error=run.axis_error, saturated=run.saturated.astype(np.int8)))
    out = dict(entry.arrays())
    out["summary"] = entry.record["summary"]
    return out


def make_figure(out_dir: Path, fast: bool = False) -> list[Path]:
    """Write the Fig 3.13 panels to ``out_dir``; returns the files written."""
    out_dir = Path(out_dir)
    runs = {c: stored(c, fast) for c in CASES}
    fig, ax = figure(5, 2, figsize=(13, 12), sharex="col")
    for k, (name, scale, unit) in enumerate(_AXES):
        for col, cases in enumerate((("optimized", "15", "40"), ("150",))):
            a = ax[k, col]
            for c in cases:
                r = runs[c]
                e = r["axis_error"][:, k] * scale
                s = r["summary"]
                a.plot(r["t"], e, _STYLE[c], lw=0.9,
                       label=f"{_LABEL[c]}: max {s['max_error'][k] * scale:.3g} {unit}, T = {s['cycle_time']:.2f} s")
                sat = r["saturated"][:, k].astype(bool)
                if sat.any():
                    a.plot(r["t"][sat], e[sat], ".", color="C1", ms=2,
                           label=f"actuator saturation ({100 * s['saturated_fraction'][k]:.1f} % of periods)")
            a.set(ylabel=f"{name} error [{unit}]")
            a.legend(fontsize=7, loc="upper right")
    ax[0, 0].set_title("linear region: optimized and constant 15 / 40 mm/s feeds")
    ax[0, 1].set_title("constant 150 mm/s: beyond the Table 3.1 limits")
    for a in ax[-1]:
        a.set(xlabel="time [s]")
    fig.suptitle("Fig 3.13 (simulation): axis tracking errors, SISO SMC drives, u_max = m A + c V + d_c from Table 3.1")
    out = out_dir / f"{NAME}.png"
    save(fig, out)
    return [out]
