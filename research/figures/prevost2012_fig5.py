"""Prévost, Lavernhe, Lartigue (HSM 2012) Fig 5: execution errors on the Application 1 B-spline at
10 m/min, before (left) and after (middle) CEC compensation, and the total error after (right).

Setup (:func:`research.contour.prevost2012_application1`): stand-in FIR interpolator T1 = 24 ms,
T2 = 12 ms at the paper's Ts = 6 ms, thesis Table 6.1 P-PI drive on both axes (stand-in). Errors are
signed contour errors against the arc length of the CAM B-spline. The compensation is the paper's
single mirror pass (eq 4); the title of (c) adds the iterated mirror to 2 um (an extension).
Dotted: the axis reversals of the B-spline (100.2, 189.7 mm; the paper says 100 and 175); dashed:
its curvature maxima (84.8, 196.2 mm), where the peaks sit with this drive.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from research.contour import (
    execution_errors,
    mirror_compensation,
    mirror_single_pass,
    prevost2012_application1,
    simulate_setpoint,
)
from research.figures._style import mosaic, save

NAME = "prevost2012_fig5_cec_bspline"
REPRODUCES = "Prévost 2012 Fig 5 (e1, e2, eT on the Application 1 B-spline, before and after CEC)"


def make_figure(out_dir: Path, fast: bool = False) -> list[Path]:
    """Write the figure to ``out_dir``; returns the files written (``fast`` changes nothing: one run)."""
    case = prevost2012_application1()
    before = execution_errors(case.cam_path, case.setpoint, simulate_setpoint(case.setpoint, case.drive))
    res = mirror_single_pass(case.problem, limits=case.limits, control_limit=case.control_limit)
    iterated = mirror_compensation(case.problem, method="fixed_point", tolerance=2e-3, throw=False)
    after = execution_errors(case.cam_path, res.setpoint, res.response)
    s = case.cam_path.arc_length(case.cam_path.project(np.asarray(res.response.position))[1])
    s0 = case.cam_path.arc_length(case.cam_path.project(np.asarray(case.setpoint.q))[1])
    fig, ax = mosaic([["before", "after", "total"]], figsize=(14, 4), sharey=False)
    for key, ex, abscissa, title in (("before", before, s0, "(a) before compensation"),
                                     ("after", after, s, "(b) after CEC (one mirror pass, the paper's method)")):
        a = ax[key]
        a.plot(abscissa, ex.e1 * 1e3, "r", label="e1 interpolation")
        a.plot(abscissa, ex.e2 * 1e3, "g", label="e2 feed drive")
        a.plot(abscissa, ex.eT * 1e3, "b", label="eT total")
        m = ex.max_abs()
        a.set(xlabel="curvilinear abscissa [mm]", ylabel="error [um]",
              title=f"{title}\nmax |e1|, |e2|, |eT| = {m['e1'] * 1e3:.1f}, {m['e2'] * 1e3:.1f}, {m['eT'] * 1e3:.2f} um")
        a.legend(loc="lower left")
    a = ax["total"]
    a.plot(s, after.eT * 1e3, "b", label="eT after")
    for rev in (100.17, 189.66):  # Y and X velocity reversals of the B-spline [mm]
        a.axvline(rev, color="k", ls=":", lw=0.8)
    for peak in (84.79, 196.15):  # curvature maxima of the B-spline [mm]
        a.axvline(peak, color="C3", ls="--", lw=0.8)
    a.set(xlabel="curvilinear abscissa [mm]", ylabel="eT [um]",
          title=f"(c) eT after one pass: max {res.after.max * 1e3:.2f} um (iterated mirror, extension: "
                f"{iterated.after.max * 1e3:.2f} um in {iterated.steps} steps)\n"
                f"dotted: axis reversals, dashed: curvature maxima; limits: {res.limits.summary()}")
    out = Path(out_dir) / f"{NAME}.png"
    save(fig, out)
    return [out]
