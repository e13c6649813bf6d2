"""Sencer (2009) thesis Fig 3.13: X, Y, Z, A, C tracking errors of the optimized feed (150 mm/s cap) against
constant 15, 40 and 150 mm/s feeds, simulated through the SISO SMC drives (Table 5.2, friction identified from
Fig 5.7, 0.1 ms) with the amplifier limit read from Table 3.1 (``u_max = m A + c V + d_c``), on the public 300 mm
blade-flank path (the thesis' impeller CL data are not public). Model and assumptions:
:mod:`research.control._feed_tracking`. Samples at the amplifier limit are marked.

Made from the config :data:`CONFIG` (the ``[feedrate]`` stage with ``[feedrate.drive]``) through the results store;
:func:`plot` only reads the stored result.
"""

from __future__ import annotations

import numpy as np

from research.figures._style import figure

NAME = "sencer2009_fig3_13_tracking_errors"
REPRODUCES = ("Sencer 2009 thesis Fig 3.13 (tracking errors of the optimized vs constant 15 / 40 mm/s feeds, "
              "actuator saturation; 150 mm/s constant: 'excessively saturated')")
CONFIG = "experiments/figures/sencer2009_fig3_13_tracking_errors.toml"

_LABEL = {"optimized": "optimized (150 mm/s cap)", "constant_15": "constant 15 mm/s", "constant_40": "constant 40 mm/s",
          "constant_150": "constant 150 mm/s"}
_STYLE = {"optimized": "k", "constant_15": "C0", "constant_40": "C2", "constant_150": "C3"}
_AXES = (("x", "X", 1e3, "um"), ("y", "Y", 1e3, "um"), ("z", "Z", 1e3, "um"), ("a", "A", 1e3, "mrad"),
         ("c", "C", 1e3, "mrad"))
_COLUMNS = (("optimized", "constant_15", "constant_40"), ("constant_150",))


def plot(record: dict, arrays: dict):
    """The figure (not saved) from a stored result of :data:`CONFIG`."""
    sc = record["scalars"]
    drive = record["details"]["feedrate"]["drive"]
    fig, ax = figure(5, 2, figsize=(14, 14), sharex="col", width_ratios=[1.6, 1])
    marked = False
    for k, (axis, name, scale, unit) in enumerate(_AXES):
        metric = "drive_axis_error_max" if k < 3 else "drive_rotary_error_max"
        for col, cases in enumerate(_COLUMNS):
            a = ax[k, col]
            for c in cases:
                t, e = arrays[f"feedrate.{c}.drive.t"], arrays[f"feedrate.{c}.drive.axis_error"][:, k] * scale
                a.plot(t, e, _STYLE[c], lw=0.9, label=_LABEL[c] + f", T = {sc[f'{c}.feedrate_cycle_time']:.2f} s")
                sat = arrays[f"feedrate.{c}.drive.saturated"][:, k].astype(bool)
                if sat.any():
                    a.plot(t[sat], e[sat], ".", color="C1", ms=2.5, label=None if marked else "at the amplifier limit")
                    marked = True
            peaks = " / ".join(f"{sc[f'{c}.{metric}.{axis}'] * scale:.3g}" for c in cases)
            sat = " / ".join(f"{100 * sc[f'{c}.drive_saturated_fraction.{axis}']:.2g}" for c in cases)
            a.set_title(f"{name}: max |error| {peaks} {unit}; saturated {sat} % of periods", fontsize=8)
            if col == 1 and np.max(np.abs(arrays[f"feedrate.{cases[0]}.drive.axis_error"][:, k])) * scale > 100:
                a.set_yscale("symlog", linthresh=10.0)  # errors from um to mm: log beyond +-10
            a.set(ylabel=f"{name} error [{unit}]")
    for a in ax[-1]:
        a.set(xlabel="time [s]")
    handles = {}
    for a in ax.ravel():
        for h, lb in zip(*a.get_legend_handles_labels()):
            handles.setdefault(lb, h)
    fig.legend(handles.values(), handles.keys(), loc="outside lower center", ncol=5)
    u = ", ".join(f"{n} {v:.3g}" for (_, n, _, _), v in zip(_AXES, drive["u_max_V"]))
    fig.suptitle("Fig 3.13 (simulation): axis tracking errors through the SISO SMC drives on the blade-flank path.\n"
                 "Left: optimized, 15 and 40 mm/s (titles list them in that order); right: constant 150 mm/s, beyond "
                 "the Table 3.1 limits (X, Y, C on a symlog scale beyond +-10).\n"
                 f"Amplifier limit u_max = m A + c V + d_c from Table 3.1 [V]: {u}")
    return fig
