"""Thesis ch 6 identification figures: Fig 6.7-style FRFs of the Table 6.1 virtual drive (truth, LS as printed
in eq 6.9, LS, PSO, optimistix), Fig 6.8-style PSO convergence, and the real EMPS axis (fit on 12 s, held-out
validation on the last 3 s, measured vs simulated tracking error and residuals)."""

from __future__ import annotations

import pathlib

import numpy as np

from research.drives import (
    ClosedLoopModel,
    Encoder,
    frequency_response,
    table_6_1_closed_loop,
)
from research.figures._style import figure, save
from research.identification import (
    EMPS_SPLIT_S,
    ASSUMED_FRICTION,
    ProjectedProblem,
    PSOSettings,
    RegressionOptions,
    bounded_fit,
    build_regression,
    identification_program,
    identify_emps,
    least_squares,
    particle_swarm,
    synthetic_log,
)

NAME = "sencer2009_ch6_identification"
REPRODUCES = ("Sencer 2009 thesis Fig 6.7/6.8 style (Table 6.1 virtual drive: FRFs of LS/PSO/optimistix, PSO "
              "convergence) and the EMPS real-axis validation (fit % on the held-out last 3 s)")
#: the EMPS file, read in place (third-party data, never copied into the repository)
EMPS_PATH = pathlib.Path(__file__).resolve().parents[3] / "shared" / "data" / "emps" / "emps_estimation_first15s.mat"
HZ = 2 * np.pi


def _virtual(out_dir: pathlib.Path, fast: bool) -> list[pathlib.Path]:
    base = table_6_1_closed_loop()
    truth = ClosedLoopModel(base.a1, base.a2, base.a3, base.b0, base.b1, base.b2, ASSUMED_FRICTION)
    ref = identification_program(0, n_moves=20 if fast else 70).trajectory()
    log = synthetic_log(truth, ref, encoder=Encoder(5e-5), seed=1)
    prob = ProjectedProblem.from_regression(build_regression(log))
    fits = {
        "LS, eq 6.9 as printed": least_squares(log, RegressionOptions.thesis()),
        "LS (trapezoid, prefilter)": least_squares(prob.regression),
        "PSO (16 swarms)": particle_swarm(prob, seed=0, settings=PSOSettings(swarms=4 if fast else 16)),
        "optimistix LM": bounded_fit(prob),
    }
    f = np.logspace(0, 2, 60 if fast else 300)
    fig, ax = figure(2, 2, figsize=(10, 6), sharex=True)
    tru = frequency_response(truth, f)
    curves = [("actual", tru, {"color": "k", "lw": 2.2})] + [
        (k, frequency_response(r.model(), f), {"ls": s}) for (k, r), s in zip(fits.items(), ("--", "-", ":", "-."))
    ]
    for name, fr, kw in curves:
        for col, g in enumerate((np.asarray(fr.tracking), np.asarray(fr.disturbance))):
            ax[0, col].loglog(f, np.abs(g), label=name, **kw)
            ax[1, col].semilogx(f, np.degrees(np.unwrap(np.angle(g))), **kw)
    for col in (0, 1):
        ax[1, col].set_ylabel("Phase [deg]")
    ax[0, 0].set_ylabel("Magnitude")
    ax[0, 0].set_title("a) tracking $x/x_r$ [mm/mm]")
    ax[0, 1].set_title("b) disturbance $x/w$ [mm/(mm/s$^2$)]")
    ax[1, 0].set_xlabel("Frequency [Hz]")
    ax[1, 1].set_xlabel("Frequency [Hz]")
    ax[0, 0].legend()
    lines = [f"{k}: wn {r.pole_parameters()[0] / HZ:.2f} Hz, zeta {r.pole_parameters()[1]:.3f}, "
             f"p {r.pole_parameters()[2] / HZ:.2f} Hz, dc {r.dc:.1f}" for k, r in fits.items()]
    fig.suptitle(f"Table 6.1 P-PI virtual drive (true wn 30.57 Hz, zeta 0.445, p 10.73 Hz, assumed dc {ASSUMED_FRICTION:g} mm/s$^2$)\n"
                 + "\n".join(lines), fontsize=7)
    p1 = out_dir / f"{NAME}_frf.png"
    save(fig, p1)

    h = fits["PSO (16 swarms)"].history
    fig, ax = figure(1, 4, figsize=(11, 2.6))
    for a, y, lab in zip(ax, (h[:, 0], h[:, 1], h[:, 2], h[:, 3]),
                         ("objective eq 6.18 [mm$^2$]", "$\\omega_n$ [rad/s]", "$\\zeta$ [-]", "p [rad/s]")):
        a.plot(np.arange(1, len(y) + 1), y)
        a.set_xlabel("Iteration")
        a.set_title(lab)
    ax[0].set_yscale("log")
    p2 = out_dir / f"{NAME}_pso.png"
    save(fig, p2)
    return [p1, p2]


def _emps(out_dir: pathlib.Path, fast: bool) -> list[pathlib.Path]:
    vp, oe = identify_emps(EMPS_PATH, max_steps=4 if fast else 20)
    log = vp.log
    fig, ax = figure(3, 1, figsize=(10, 7.5), sharex=True)
    ax[0].plot(log.t, log.reference, label="reference $q_g$")
    ax[0].plot(log.t, log.actual, "--", label="measured $q_m$")
    ax[0].set_ylabel("position [mm]")
    ax[1].plot(log.t, 1e3 * log.tracking_error, color="k", lw=1.6, label="measured")
    for rep, name in ((vp, "bounded VP"), (oe, "output error")):
        v = rep.fits["validation"]["tracking_error"]
        e = rep.fits["estimation"]["tracking_error"]
        ax[1].plot(log.t, 1e3 * (log.reference - rep.simulated), label=f"{name}: fit {e:.1f} % est., {v:.1f} % val.")
        ax[2].plot(log.t, 1e3 * rep.residual(), label=f"{name}: RMS {rep.rms_error_um['validation']:.1f} um (val.)")
    ax[1].set_ylabel("tracking error [um]")
    ax[2].set_ylabel("residual $x - x_{sim}$ [um]")
    ax[2].set_xlabel("time [s]")
    for a in ax:
        a.axvline(EMPS_SPLIT_S, color="grey", ls=":")
        a.legend(loc="upper left")
    ax[0].set_title("EMPS ball-screw axis: eq 6.3 fitted on t < 12 s, free-run simulation, validation 12-15 s "
                    "(tracking-error fit %)")
    p = out_dir / f"{NAME}_emps.png"
    save(fig, p)
    return [p]


def make_figure(out_dir: pathlib.Path, fast: bool = False) -> list[pathlib.Path]:
    """Write the FRF, PSO-convergence and (when the EMPS file is present) EMPS figures into ``out_dir``.

    Args:
        out_dir: destination folder (created if missing).
        fast: shorter program, fewer swarms and solver steps (for tests).
    Returns:
        the written PNG paths.
    """
    out_dir = pathlib.Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = _virtual(out_dir, fast)
    if EMPS_PATH.exists():
        paths += _emps(out_dir, fast)
    return paths
