"""Sencer 2009 thesis ch 6 (§6.5.1, Table 6.1): (a-d) Fig 6.7-style FRFs of the Table 6.1 P-PI virtual drive
(truth, eq 6.9 as printed, LS, PSO), tracking ``x/x_r`` and disturbance ``x/w``; (e-h) Fig 6.8-style PSO
convergence (objective eq 6.18, wn, zeta, p of the best particle, the true values dashed); (i-j) the real EMPS
ball-screw axis (third-party data, not the thesis' axis): eq 6.3 fitted on t < 12 s by bounded variable
projection and output error, free-run simulation over the record, the held-out last 3 s scored (tracking-error
fit %): measured and simulated tracking error, and the residual ``x - x_sim``.

Made from the config :data:`CONFIG` through the results store; :func:`plot` only reads the stored result.
"""

from __future__ import annotations

import numpy as np

from research.figures._style import mosaic

NAME = "sencer2009_ch6_identification"
REPRODUCES = ("Sencer 2009 thesis Table 6.1 / Fig 6.7 / Fig 6.8 (virtual drive identified by LS and PSO) and the "
              "EMPS real-axis validation")
CONFIG = "experiments/figures/sencer2009_ch6_identification.toml"
HZ = 2 * np.pi
LABELS = {"ls_thesis": "LS, eq 6.9 as printed", "ls": "LS (trapezoid, prefilter)", "pso": "PSO (16 swarms)",
          "optimistix": "optimistix bounded fit"}
STYLES = {"ls_thesis": "--", "ls": "-", "pso": ":", "optimistix": "-."}
#: thesis Table 6.1 (p 119): the printed Actual and LS / PSO estimates, wn [Hz], zeta, p [Hz]
THESIS = {"actual": (30.6, 0.45, 10.8), "estimate": (31.3, 0.39, 11.4)}


def plot(record: dict, arrays: dict):
    """The figure (not saved) from a stored result of :data:`CONFIG`."""
    s, cfg = record["scalars"], record["config"]["identification_ch6"]
    methods = record["details"]["identification_ch6"]["methods"]
    f = arrays["ident.f"]
    layout = [["tm", "tm", "dm", "dm"], ["tp", "tp", "dp", "dp"], ["o", "w", "z", "p"]]
    emps = "emps.t" in arrays
    if emps:
        layout += [["e", "e", "r", "r"]]
    fig, ax = mosaic(layout, figsize=(14, 12.5 if emps else 9.5))
    curves = [("actual", "actual (Table 6.1)", {"color": "k", "lw": 2.2})] + [
        (m, LABELS[m], {"ls": STYLES[m]}) for m in methods]
    for key, label, kw in curves:
        for col, part in (("t", "tracking"), ("d", "disturbance")):
            g = arrays[f"ident.{key}.{part}"]
            ax[col + "m"].loglog(f, np.abs(g), label=label, **kw)
            ax[col + "p"].semilogx(f, np.degrees(np.unwrap(np.angle(g))), **kw)
    for col in "td":
        ax[col + "m"].axvline(cfg["agreement_hz"], color="grey", ls=":", lw=0.8)
        ax[col + "p"].axvline(cfg["agreement_hz"], color="grey", ls=":", lw=0.8)
        ax[col + "p"].set(xlabel="frequency [Hz]", ylabel="phase [deg]")
    ax["tm"].set(ylabel="|x/x_r| [mm/mm]", title="(a) tracking x/x_r (dotted: 30 Hz, the thesis' agreement range)")
    ax["dm"].set(ylabel="|x/w| [mm/(mm/s$^2$)]", title="(b) disturbance x/w")
    ax["tp"].set_title("(c) tracking phase")
    ax["dp"].set_title("(d) disturbance phase")
    ax["dm"].legend(loc="upper left", fontsize=7)
    rows = [f"{LABELS.get(k, k)}: wn {s[f'{k}.identified_wn_hz']:.2f} Hz, zeta {s[f'{k}.identified_zeta']:.3f}, "
            f"p {s[f'{k}.identified_p_hz']:.2f} Hz, dc {s[f'{k}.identified_dc']:.1f} mm/s$^2$"
            for k in ["actual"] + methods]
    a, e = THESIS["actual"], THESIS["estimate"]
    fig.suptitle(f"Table 6.1 P-PI virtual drive, {cfg['n_moves']} moves, {cfg['resolution_um']:g} um encoder; thesis: "
                 f"actual {a[0]} Hz / {a[1]} / {a[2]} Hz, LS = PSO {e[0]} Hz / {e[1]} / {e[2]} Hz\n" + "\n".join(rows),
                 fontsize=8)
    if "ident.pso.history" in arrays:
        h = arrays["ident.pso.history"]
        it = np.arange(1, h.shape[0] + 1)
        true = (None, s["actual.identified_wn_hz"] * HZ, s["actual.identified_zeta"], s["actual.identified_p_hz"] * HZ)
        for k, (key, lab) in enumerate(zip("owzp", ("objective eq 6.18 [mm$^2$]", "$\\omega_n$ [rad/s]", "$\\zeta$ [-]",
                                                     "p [rad/s]"))):
            ax[key].plot(it, h[:, k], label="PSO best particle")
            if true[k] is not None:
                ax[key].axhline(true[k], color="k", ls="--", lw=0.8, label="true")
            ax[key].set(xlabel="iteration", ylabel=lab)
        ax["o"].set_yscale("log")
        ax["w"].legend(loc="upper right", fontsize=7)
        ax["o"].set_title(f"(e) PSO: within 1 % from iteration {s['pso_settle_iteration']:.0f}", fontsize=9)
        ax["w"].set_title("(f)")
        ax["z"].set_title("(g)")
        ax["p"].set_title("(h)")
    if emps:
        t, ref, act = arrays["emps.t"], arrays["emps.reference"], arrays["emps.actual"]
        split = record["details"]["identification_ch6"]["emps"]["split_s"]
        ax["e"].plot(t, 1e3 * (ref - act), color="k", lw=1.4, label="measured")
        for name, lab in (("vp", "bounded VP"), ("oe", "output error")):
            sim = arrays[f"emps.{name}.simulated"]
            ax["e"].plot(t, 1e3 * (ref - sim), lw=0.9, label=f"{lab}: fit {s[f'emps.{name}.emps_fit_estimation']:.1f} % "
                                                              f"est., {s[f'emps.{name}.emps_fit_validation']:.1f} % val.")
            ax["r"].plot(t, 1e3 * (act - sim), lw=0.9,
                         label=f"{lab}: RMS {s[f'emps.{name}.emps_rms_validation'] * 1e3:.1f} um (val.)")
        for key in "er":
            ax[key].axvline(split, color="grey", ls=":")
            lo, hi = ax[key].get_ylim()
            ax[key].set_ylim(lo, hi + 0.45 * (hi - lo))  # headroom: the legend above the data
            ax[key].legend(loc="upper left", fontsize=7, ncol=2)
            ax[key].set_xlabel("time [s]")
        ax["e"].set(ylabel="tracking error $x_r - x$ [um]",
                    title=f"(i) EMPS axis: eq 6.3 fitted on t < {split:g} s, free run, validated after (dotted)")
        ax["r"].set(ylabel="residual $x - x_{sim}$ [um]", title="(j) EMPS residual")
    return fig
