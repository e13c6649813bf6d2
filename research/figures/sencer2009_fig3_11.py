"""Sencer (2009) thesis Fig 3.10-3.12 on the public 300 mm blade-flank path (the thesis' impeller CL data are
not public), Table 3.1 limits, feed cap 150 mm/s, in one figure:

- (a) Fig 3.11: the optimized B-spline feed (eq 3.31-3.58) against the constant 15 mm/s feed, under the axis
  constraints reflected on the feed (min over the axes), the stretches where an axis limit binds shaded;
- (b)-(d) Fig 3.10: each axis' velocity (eq 3.42), acceleration (eq 3.50) and jerk (eq 3.54) limit on the feed;
- (e)-(j) Fig 3.12: axis velocity, acceleration and jerk against time, optimized (solid) and 15 mm/s (dashed),
  with the limits.

Made from the config :data:`CONFIG` (the ``[feedrate]`` stage) through the results store; :func:`plot` only reads
the stored result.
"""

from __future__ import annotations

import numpy as np

from research.figures._style import mosaic

NAME = "sencer2009_fig3_11_feed_optimization"
REPRODUCES = ("Sencer 2009 thesis Fig 3.10-3.12 (feed limited by each axis, optimized vs constant 15 mm/s feed, "
              "axis profiles; thesis: 20.18 s constant vs 4.664 s optimized on its 300 mm impeller path)")
CONFIG = "experiments/figures/sencer2009_fig3_11_feed_optimization.toml"

AXES = ("x", "y", "z", "a", "c")
COLOURS = dict(zip(AXES, ("tab:blue", "tab:red", "tab:green", "tab:purple", "tab:orange")))
KINDS = (("velocity", "3.42", "v", "/s"), ("acceleration", "3.50", "a", "/s^2"), ("jerk", "3.54", "j", "/s^3"))
CONSTANT = "constant_15"


def plot(record: dict, arrays: dict):
    """The figure (not saved) from a stored result of :data:`CONFIG`."""
    from matplotlib.patches import Patch

    d = record["details"]["feedrate"]
    sc = record["scalars"]
    feed_cap = d["feed_mm_per_s"]
    limits = d["limits"]
    fig, ax = mosaic([["f", "f", "f"], ["lv", "la", "lj"], ["cv", "ca", "cj"], ["rv", "ra", "rj"]],
                     figsize=(14, 15), height_ratios=[1.1, 1, 1, 1])
    s_env = arrays["feedrate.envelope.s"]
    s_opt, f_opt = arrays["feedrate.optimized.s"], arrays["feedrate.optimized.feed"]
    # (a) Fig 3.11
    a = ax["f"]
    for (kind, *_), style in zip(KINDS, (":", "--", "-.")):
        a.plot(s_env, np.min(arrays[f"feedrate.envelope.{kind}"], axis=1), color="0.45", ls=style, lw=1,
               label=f"{kind} constraints (min over the axes)")
    a.plot(s_opt, f_opt, "k", lw=1.8, label=f"optimized feed, T = {sc['optimized.feedrate_cycle_time']:.3f} s")
    a.plot(arrays[f"feedrate.{CONSTANT}.s"], arrays[f"feedrate.{CONSTANT}.feed"], "C0", lw=1.4,
           label=f"constant feed 15 mm/s, T = {sc[CONSTANT + '.feedrate_cycle_time']:.2f} s")
    a.axhline(feed_cap, color="C3", lw=1, label=f"feed limit {feed_cap:g} mm/s")
    bound = set()
    for b in d["schedules"]["optimized"]["binding"]:
        if b["axis"] != "feed":
            a.axvspan(b["s_start_mm"], max(b["s_end_mm"], b["s_start_mm"] + 0.3), color=COLOURS[b["axis"]], alpha=0.15,
                      lw=0)
            bound.add((b["axis"], b["kind"]))
    handles, _ = a.get_legend_handles_labels()
    handles += [Patch(color=COLOURS[x], alpha=0.3, label=f"shaded: {x.upper()} {k} limit binds") for x, k in sorted(bound)]
    a.set(xlabel="displacement s [mm]", ylabel="feed [mm/s]", ylim=(0, 300), xlim=(0, s_env[-1]),
          title=f"(a) Fig 3.11: optimized vs constant feed along the {d['path']} path ({d['path_length_mm']:.0f} mm), "
                "Table 3.1 limits")
    a.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.005, 1.0), fontsize=7)
    # (b)-(d) Fig 3.10
    for k, (key, (kind, eq, _, _), letter) in enumerate(zip(("lv", "la", "lj"), KINDS, "bcd")):
        a = ax[key]
        env = arrays[f"feedrate.envelope.{kind}"]
        for i, name in enumerate(AXES):
            a.plot(s_env, env[:, i], color=COLOURS[name], lw=1, label=f"{name.upper()} axis limit")
        a.plot(s_opt, f_opt, "k", lw=1.4, label="optimized feed")
        a.set(xlabel="displacement s [mm]", ylabel="feed [mm/s]", ylim=(0, 1200), xlim=(0, s_env[-1]),
              title=f"({letter}) Fig 3.10{'abc'[k]}: axis {kind} limits (eq {eq})")
    ax["lj"].legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7)
    # (e)-(j) Fig 3.12
    t_end = sc[CONSTANT + ".feedrate_cycle_time"]
    for row, axes_i, scale, unit in (("c", (0, 1, 2), 1.0, "mm"), ("r", (3, 4), 180 / np.pi, "deg")):
        for k, (kind, _, attr, per) in enumerate(KINDS):
            a = ax[row + attr]
            lim = limits[kind]
            for i in axes_i:
                c = COLOURS[AXES[i]]
                a.plot(arrays["feedrate.optimized.t"], arrays[f"feedrate.optimized.{attr}"][:, i] * scale, color=c, lw=1,
                       label=f"{AXES[i].upper()} optimized")
                a.plot(arrays[f"feedrate.{CONSTANT}.t"], arrays[f"feedrate.{CONSTANT}.{attr}"][:, i] * scale, color=c,
                       ls="--", lw=0.8, label=f"{AXES[i].upper()} constant 15 mm/s")
                for sign in (1, -1):
                    a.axhline(sign * lim[i] * scale, color=c, lw=0.7, ls=":")
            letter = "efghij"[k + (3 if row == "r" else 0)]
            a.set(xlabel="time [s]", ylabel=f"{kind} [{unit}{per}]", xlim=(0, t_end),
                  title=f"({letter}) Fig 3.12: {('X Y Z', 'A C')[row == 'r']} {kind} (dotted: limits)")
        ax[row + "j"].legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7)
    return fig
