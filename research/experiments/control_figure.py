"""Figure of a ``[control]`` run (thesis ch 5 layout of Fig 5.7 / 5.8): tool-tip contour error, orientation
contour error, linear and rotary axis tracking errors and control voltages along time."""

from __future__ import annotations

import numpy as np

from research.experiments.plot_style import figure

AXES = ("x", "y", "z", "a", "c")


def plot_control(arrays: dict, details: dict, title: str = ""):
    """Return a matplotlib figure (not saved) from the arrays and details of the control stage.

    Args:
        arrays: ``control.t`` [s], ``control.tip_contour_error`` [mm], ``control.orientation_error`` [rad],
            ``control.axis_error`` ``(M, 5)`` [mm, rad], ``control.u`` ``(M, 5)`` [V].
        details: the stage's details (``controller``, ``summary``); with ``cases`` (a table with
            ``[[control.cases]]``), the arrays are ``control.<label>.<name>`` and every case is drawn in two
            panels (tool-tip and orientation contour error).
        title: figure title.
    """
    if "cases" in details:
        return _plot_cases(arrays, details, title)
    t = np.asarray(arrays["control.t"])
    fig, ax = figure(2, 2, figsize=(10, 7), sharex=True)
    s = details["summary"]
    a = ax[0, 0]
    a.plot(t, 1e3 * np.asarray(arrays["control.tip_contour_error"]), "k")
    a.set(ylabel="tool-tip contour error [um]",
          title=f"{details['controller']}: max {1e3 * s['contour_max']:.1f} um, mean {1e3 * s['contour_mean']:.1f} um")
    a = ax[0, 1]
    a.plot(t, 1e6 * np.asarray(arrays["control.orientation_error"]), "k")
    a.set(ylabel="orientation contour error [urad]", title=f"max {1e6 * s['orientation_max']:.1f} urad")
    e = np.asarray(arrays["control.axis_error"])
    a = ax[1, 0]
    for k in range(3):
        a.plot(t, 1e3 * e[:, k], f"C{k}", label=AXES[k])
    a2 = a.twinx()
    for k in (3, 4):
        a2.plot(t, 1e3 * e[:, k], f"C{k}", ls="--", label=AXES[k])
    a.set(xlabel="time [s]", ylabel="linear axis error X Y Z [um]", title="axis tracking errors")
    a2.set_ylabel("rotary axis error A C [mrad] (dashed)")
    lines = a.get_lines() + a2.get_lines()
    a.legend(lines, [ln.get_label() for ln in lines], loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=5)
    a = ax[1, 1]
    u = np.asarray(arrays["control.u"])
    for k in range(5):
        a.plot(t, u[:, k], f"C{k}", label=AXES[k])
    a.set(xlabel="time [s]", ylabel="control voltage [V]", title="control effort")
    a.legend(loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=5)
    if title:
        fig.suptitle(title)
    return fig


def _plot_cases(arrays: dict, details: dict, title: str):
    """Tool-tip and orientation contour error of every case of a ``[control]`` table with cases (log scales: the
    cases' errors often span decades)."""
    fig, ax = figure(2, 1, figsize=(10, 7), sharex=True)
    for label in details["labels"]:
        s = details["cases"][label]["summary"]
        t = np.asarray(arrays[f"control.{label}.t"])
        ax[0].semilogy(t, np.maximum(1e3 * np.asarray(arrays[f"control.{label}.tip_contour_error"]), 1e-4), lw=0.8,
                       label=f"{label}: max {1e3 * s['contour_max']:.3g} um, mean {1e3 * s['contour_mean']:.3g} um")
        ax[1].semilogy(t, np.maximum(1e6 * np.asarray(arrays[f"control.{label}.orientation_error"]), 1e-2), lw=0.8,
                       label=f"{label}: max {1e6 * s['orientation_max']:.3g} urad")
    ax[0].set(ylabel="tool-tip contour error [um] (log scale)", title="tool-tip contour error per case")
    ax[1].set(xlabel="time [s]", ylabel="orientation contour error [urad] (log scale)",
              title="orientation contour error per case")
    for a in ax:
        a.legend(loc="lower right", fontsize=7, ncol=2)
    if title:
        fig.suptitle(title)
    return fig
