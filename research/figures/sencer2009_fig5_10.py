"""Sencer (2009) thesis Fig 5.10: orientation contour error (angle between the actual tool axis and the
reference orientation path, §4.5 / eq 5.40) at 50 mm/s for the coupling weights W = diag(w, w),
w = 0, 3, 4, 5, and its mean against w (simulation; the thesis' curves are measured). Panels (c, d): the
thesis Fig 4.7 check on the same drives with W = 0 (whose A, C loops are the SISO ones): the eq 4.34/4.35
orientation contour error estimate against the exact one and their difference (thesis: below 6 urad).

Made from the config :data:`CONFIG` (four ``[[control.cases]]``) through the results store; :func:`plot`
only reads the stored result.
"""

from __future__ import annotations

from research.figures._style import mosaic

NAME = "sencer2009_fig5_10_orientation_weights"
REPRODUCES = ("Sencer 2009 thesis Fig 5.10 (orientation contour error for W = 0, 3, 4, 5 at 50 mm/s) and Fig 4.7 "
              "(eq 4.35 estimate within 6 urad)")
CONFIG = "experiments/figures/sencer2009_fig5_10_orientation_weights.toml"

_WEIGHTS = (("w0", 0.0, "k"), ("w3", 3.0, "C0"), ("w4", 4.0, "C1"), ("w5", 5.0, "C2"))


def plot(record: dict, arrays: dict):
    """The figure (not saved) from a stored result of :data:`CONFIG`."""
    s = record["scalars"]
    bound = next(p for p in record["config"]["paper"] if p["key"] == "w0.orientation_estimate_error_max")
    fig, ax = mosaic([["ori", "ori", "mean"], ["est", "est", "diff"]], figsize=(13, 8))
    for label, w, colour in _WEIGHTS:
        ax["ori"].plot(arrays[f"control.{label}.t"], arrays[f"control.{label}.orientation_error"] * 1e3, color=colour,
                       lw=0.8, label=f"W = diag({w:g}, {w:g}) 1/s: mean {s[f'{label}.orientation_error_mean'] * 1e3:.3f} mrad")
    top = 1.4 * max(arrays[f"control.{label}.orientation_error"].max() for label, _, _ in _WEIGHTS) * 1e3
    ax["ori"].set(xlabel="time [s]", ylabel="orientation contour error [mrad]", ylim=(0, top),
                  title="(a) Fig 5.10a: orientation contour error (eq 5.40), 50 mm/s (simulation)")
    ax["ori"].legend(loc="upper left", fontsize=7)
    w = [w for _, w, _ in _WEIGHTS]
    ax["mean"].plot(w, [s[f"{label}.orientation_error_mean"] * 1e3 for label, _, _ in _WEIGHTS], "ko-")
    ax["mean"].set(xlabel="coupling weight w, W = diag(w, w) [1/s]", ylabel="mean orientation contour error [mrad]",
                   xticks=w, title="(b) Fig 5.10b: mean against W\n(the thesis prints no values: 'a steady decline')")
    t = arrays["control.w0.t"]
    exact, estimate = arrays["control.w0.orientation_error"], arrays["control.w0.orientation_estimate"]
    ax["est"].plot(t, exact * 1e3, "k", lw=1.2, label="exact (closest reference orientation)")
    ax["est"].plot(t, estimate * 1e3, "C1--", lw=0.9, label="estimate |J_o eps_R|, eq 4.34 / 4.35")
    ax["est"].set(xlabel="time [s]", ylabel="orientation contour error [mrad]", ylim=(0, top),
                  title="(c) Fig 4.7: exact and estimated orientation contour error, W = 0 (A, C as SISO), 50 mm/s")
    ax["est"].legend(loc="upper left", fontsize=7)
    d = (estimate - exact) * 1e6
    limit = (bound["value"] + bound["tolerance"]) * 1e6
    ax["diff"].plot(t, d, "k", lw=0.8)
    for sign in (1, -1):
        ax["diff"].axhline(sign * limit, color="C3", ls="--", lw=1, label=f"thesis: below {limit:g} urad" if sign > 0 else None)
    ax["diff"].set(xlabel="time [s]", ylabel="estimate - exact [urad]", ylim=(-1.3 * limit, 1.3 * limit),
                   title=f"(d) Fig 4.7c-d: discrepancy, max {s['w0.orientation_estimate_error_max'] * 1e6:.2f} urad")
    ax["diff"].legend(loc="lower left", fontsize=7)
    fig.suptitle("Sencer 2009 Fig 5.10 / 4.7: orientation contour controller (eq 5.22-5.27) on the Fig 5.5 path, "
                 "Table 5.1 drives (simulation)", fontsize=10)
    return fig
