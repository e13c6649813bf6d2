"""Prévost, Lavernhe, Lartigue (HSM 2012) Fig 5: execution errors on the Application 1 B-spline at
10 m/min, before (a) and after (b) one CEC mirror pass, and the total error after (c), against the
curvilinear abscissa of the actual position on the B-spline.

Setup (the config; :func:`research.contour.prevost2012_application1` holds the same stand-ins): FIR
interpolator T1 = 24 ms, T2 = 12 ms at the paper's Ts = 6 ms, thesis Table 6.1 P-PI drive on both axes.
Errors are signed contour errors (positive to the left of travel) against the B-spline itself. Dotted: the
axis reversals of the B-spline (from the stored result: 100.2 and 189.7 mm; the paper says 100 and 175);
grey: the paper's 5 um bound after compensation.

Made from the config :data:`CONFIG` through the results store; :func:`plot` only reads the stored result.
"""

from __future__ import annotations

from research.figures._style import mosaic

NAME = "prevost2012_fig5_cec_bspline"
REPRODUCES = "Prévost 2012 Fig 5 (e1, e2, eT on the Application 1 B-spline, before and after CEC)"
CONFIG = "experiments/figures/prevost2012_fig5_cec_bspline.toml"
PAPER_AFTER_UM = 5.0  # §4.1: eT after compensation "2 um (5 um in the critical zones of axis inversions)"


def plot(record: dict, arrays: dict):
    """The figure (not saved) from a stored result of :data:`CONFIG`."""
    s = record["scalars"]
    ic = record["config"]["interpolator"][0]
    label = ic.get("label") or ic["kind"]
    arrays = {k.removeprefix(f"{label}."): v for k, v in arrays.items()}
    reversals = {k.split(".", 1)[1]: v for k, v in s.items() if k.startswith("axis_reversal_abscissa.")}
    fig, ax = mosaic([["before", "after", "total"]], figsize=(15, 4.6), sharey=False)
    for when, title in (("before", "(a) before compensation"), ("after", "(b) after one CEC mirror pass (eq 4)")):
        a, x = ax[when], arrays[f"cec.s_{when}"]
        for e, color, label in (("e1", "r", "e1 interpolation"), ("e2", "g", "e2 feed drive"), ("eT", "b", "eT total")):
            a.plot(x, arrays[f"cec.{e}_{when}"] * 1e3, color, lw=1, label=label)
        a.set(xlabel="curvilinear abscissa s [mm]", ylabel="signed error [um] (+: left of travel)",
              title=f"{title}\nmax |e1|, |e2|, |eT| = {s[f'cec_interpolation_error_{when}'] * 1e3:.1f}, "
                    f"{s[f'cec_drive_error_{when}'] * 1e3:.1f}, {s[f'cec_error_{when}'] * 1e3:.1f} um")
        a.legend(loc="lower right", fontsize=7)
    a = ax["total"]
    a.plot(arrays["cec.s_after"], arrays["cec.eT_after"] * 1e3, "b", lw=1, label="eT after one pass")
    for bound in (PAPER_AFTER_UM, -PAPER_AFTER_UM):
        a.axhline(bound, color="grey", ls="--", lw=0.8, label="paper: 5 um at the axis inversions" if bound > 0 else None)
    for axis, at in reversals.items():
        for b in (ax["before"], ax["after"], a):
            b.axvline(at, color="k", ls=":", lw=0.8)
        a.annotate(f"{axis} reverses\n{at:.1f} mm", (at, -PAPER_AFTER_UM * 1.15), fontsize=7, ha="center", va="top")
    a.set(xlabel="curvilinear abscissa s [mm]", ylabel="eT [um]", ylim=(-PAPER_AFTER_UM * 1.6, PAPER_AFTER_UM * 1.3),
          title=f"(c) eT after one pass: max {s['cec_error_after'] * 1e3:.2f} um (paper: 2 um, 5 um at inversions)\n"
                f"before {s['cec_error_before'] * 1e3:.1f} um (paper: 70 um); stand-in FIR 24/12 ms, Table 6.1 P-PI drive")
    a.legend(loc="upper right", fontsize=7)
    return fig
