"""Sencer (2009) thesis Fig 3.10-3.12: axis limits reflected on the feed, optimized against
constant feed, and the axis profiles, on the public 300 mm blade-flank path (the thesis' impeller
CL data are not public) and on the thesis' eq 4.36 path, under the Table 3.1 limits (A / C jerk read
as rad/s^3, see :func:`research.optimal.table31_limits`), programmed feed 150 mm/s.

- ``*_fig3_10.png``: per-axis feed limits from the velocity (eq 3.42), acceleration (eq 3.50) and jerk
  (eq 3.54) limits, with the optimized feed.
- ``*_fig3_11.png``: optimized B-spline feed (eq 3.31-3.58) against the constant 15 mm/s feed and the
  150 mm/s cap, the stretches where each axis limit binds shaded.
- ``*_fig3_12.png``: axis velocity, acceleration and jerk against time, optimized (solid) and constant
  15 mm/s (dashed), with the limits.

The constant-feed time is L/F plus the S-curve start and stop (20.000 + 0.259 s on the 300 mm
blade path); the thesis' 20.18 s is L/F = 20 s on its 300 mm impeller path plus ramps it does not
describe, so the agreement is by construction of the path length, not a reproduction.

``fast=True`` solves a 40-control-point schedule of the blade path only (seconds); the full run uses
the thesis' n = 276 control points.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from research.figures._style import figure, save
from research.optimal import (
    axis_feed_limits,
    constant_feed,
    optimize_feedrate,
    table31_limits,
)
from research.paths.five_axis_library import blade_flank_path, eq436_spline

NAME = "sencer2009_fig3_11_feed_optimization"
REPRODUCES = ("Sencer 2009 thesis Fig 3.10-3.12 (feed limited by each axis, optimized vs constant 15 mm/s feed, "
              "axis profiles; thesis: 20.18 s constant vs 4.664 s optimized on its 300 mm impeller path)")

FEED = 150.0  # mm/s, programmed feed of the thesis' CL file (§3.6)
CONSTANT = 15.0  # mm/s, the thesis' conservative constant feed
AXES = ("x", "y", "z", "a", "c")
COLOURS = dict(zip(AXES, ("tab:blue", "tab:red", "tab:green", "tab:purple", "tab:orange")))


def make_figure(out_dir: Path, fast: bool = False) -> list[Path]:
    """Write the figures to ``out_dir``; returns the files written."""
    out_dir = Path(out_dir)
    limits = table31_limits()
    cases = [("blade", blade_flank_path(), 40 if fast else 276)]
    if not fast:
        cases.append(("eq436", eq436_spline(), None))
    written = []
    for tag, path, n in cases:
        opt = optimize_feedrate(path, limits, FEED, control_points=n, refinements=1 if fast else 3,
                                sample_period=5e-3 if fast else 1e-3)
        const = constant_feed(path, limits, CONSTANT, sample_period=5e-3 if fast else 1e-3)
        written += [_fig3_10(out_dir, tag, path, limits, opt), _fig3_11(out_dir, tag, path, limits, opt, const),
                    _fig3_12(out_dir, tag, limits, opt, const)]
    return written


def _fig3_10(out_dir, tag, path, limits, opt) -> Path:
    s = np.linspace(0.0, path.length, 1500)
    env = axis_feed_limits(path, limits, s)
    fig, ax = figure(3, 1, figsize=(8, 8), sharex=True)
    for k, (kind, eq) in enumerate((("velocity", "3.42"), ("acceleration", "3.50"), ("jerk", "3.54"))):
        for i, name in enumerate(AXES):
            ax[k].plot(s, env[kind][:, i], color=COLOURS[name], label=f"{name.upper()} axis limit")
        ax[k].plot(opt.s, opt.feed, "k", lw=1.6, label="optimized feed")
        ax[k].set(ylim=(0, 1200), ylabel="feed [mm/s]", title=f"({'abc'[k]}) feed limited by the axis {kind} limits (eq {eq})")
    ax[0].legend(ncol=3)
    ax[2].set(xlabel="displacement s [mm]")
    out = out_dir / f"{NAME}_{tag}_fig3_10.png"
    save(fig, out)
    return out


def _fig3_11(out_dir, tag, path, limits, opt, const) -> Path:
    fig, ax = figure(figsize=(9, 4.5))
    s = np.linspace(0.0, path.length, 1500)
    env = axis_feed_limits(path, limits, s)
    for kind, style in (("velocity", ":"), ("acceleration", "--"), ("jerk", "-.")):
        ax.plot(s, np.minimum(env[kind].min(axis=1), 400), "0.5", ls=style, lw=1, label=f"{kind} constraints (min over axes)")
    ax.plot(opt.s, opt.feed, "k", lw=1.8, label=f"optimized feed, T = {opt.cycle_time:.3f} s")
    ax.plot(const.s, const.feed, "C0", lw=1.4, label=f"constant feed {CONSTANT:g} mm/s, T = {const.cycle_time:.2f} s")
    ax.axhline(FEED, color="C3", lw=1, label=f"feed limit {FEED:g} mm/s")
    for b in opt.binding:
        if b.axis != "feed":
            ax.axvspan(b.s_start, max(b.s_end, b.s_start + 0.3), color=COLOURS[b.axis], alpha=0.12, lw=0)
    ax.set(xlabel="displacement s [mm]", ylabel="feed [mm/s]", ylim=(0, 260),
           title=f"Fig 3.11 style, {path.name}: optimized vs constant feed (shaded: binding axis limit, colour = axis)")
    ax.legend(loc="upper right")
    out = out_dir / f"{NAME}_{tag}_fig3_11.png"
    save(fig, out)
    return out


def _fig3_12(out_dir, tag, limits, opt, const) -> Path:
    fig, ax = figure(3, 2, figsize=(11, 8), sharex=True)
    rows = (("v", "velocity", "/s"), ("a", "acceleration", "/s^2"), ("j", "jerk", "/s^3"))
    for r, (attr, kind, unit) in enumerate(rows):
        lim = getattr(limits, kind)
        for c, (axes, scale, u) in enumerate((((0, 1, 2), 1.0, "mm"), ((3, 4), 180 / np.pi, "deg"))):
            a = ax[r, c]
            for i in axes:
                a.plot(opt.trajectory.t, np.asarray(getattr(opt.trajectory, attr))[:, i] * scale, color=COLOURS[AXES[i]],
                       label=f"{AXES[i].upper()} optimized")
                a.plot(const.trajectory.t, np.asarray(getattr(const.trajectory, attr))[:, i] * scale, color=COLOURS[AXES[i]],
                       ls="--", lw=0.8)
                a.axhline(lim[i] * scale, color=COLOURS[AXES[i]], lw=0.6, ls=":")
                a.axhline(-lim[i] * scale, color=COLOURS[AXES[i]], lw=0.6, ls=":")
            a.set(ylabel=f"{kind} [{u}{unit}]", xlim=(0, const.cycle_time))
            if r == 0:
                a.set_title(("Cartesian", "rotary")[c] + " axes: optimized (solid), 15 mm/s (dashed), limits (dotted)")
                a.legend(ncol=3)
    for a in ax[-1]:
        a.set(xlabel="time [s]")
    out = out_dir / f"{NAME}_{tag}_fig3_12.png"
    save(fig, out)
    return out
