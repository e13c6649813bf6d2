"""Sencer 2015 Fig 6: FIR cornering against geometric smoothing (and the time-optimal OCP).

The diamond at F = 250 mm/s, eps = 500 um, T1 = 148 ms and T2 = 89 ms (§4). Geometric smoothing
and the OCP are held to the FIR's own per-axis peak velocity, acceleration and jerk (limit
convention "a" of :mod:`research.experiments.optimality`). Each reference runs through the Table
6.1 P-PI drive (friction compensated, dc = 0) carrying the two beams of §4, 11.4 Hz on X and
6.8 Hz on Y (2 % damping assumed; the paper gives none): (b) feed, (c-d) axis acceleration,
(e-f) beam deflection. The FIR delays sit on the spectral zeros of the beams (eq 10), so the FIR
leaves them almost still once the motion ends.

Measured (Ts = 1 ms): cycle time FIR 1.790 s, blend 2.013 s, OCP 1.709 s; residual beam vibration
(X, Y) FIR 12.5, 12.9 um, blend 108, 593 um, OCP 143, 347 um. The paper shows the same ordering of
FIR against blend in Fig 6b and 6e-f (no numbers printed).
"""

from __future__ import annotations

from pathlib import Path

import equinox as eqx
import numpy as np

from research.drives import FlexibleMode, simulate, table_6_1_closed_loop
from research.experiments.optimality import PAPER, study_limits
from research.figures._style import mosaic, save
from research.interpolators import blend_interpolate, fir_interpolate
from research.paths import named_path
from research.trajectory import Trajectory

NAME = "sencer2015_fig6_cornering_comparison"
REPRODUCES = "Sencer 2015 Fig 6 (diamond: FIR vs geometric smoothing, feed, acceleration, beam vibration) + OCP"
BEAMS_HZ = (11.4, 6.8)  # X, Y first bending modes, §4
BEAM_DAMPING = 0.02
SETTLE = 1.5  # s of rest simulated after the longest motion


def comparison(sample_period: float = 1e-3, *, include_ocp: bool = True) -> dict:
    """Trajectories, drive responses and residual vibration of FIR, geometric blend and (optionally)
    the OCP.

    Returns:
        ``{method: {"trajectory", "deflection" (N, 2) [mm], "cycle_time" [s],
        "residual_vibration" (2,) [mm]}}``; the residual vibration is the peak beam deflection from
        50 ms after the motion ends to the end of the :data:`SETTLE` window.
    """
    path = named_path("diamond")
    F, delays, eps = PAPER["feed"], PAPER["delays"], PAPER["tolerance"]
    fir = fir_interpolate(path, F, delays, eps, sample_period)
    limits = study_limits("a", path, fir, F, delays)
    methods = {
        "FIR overlap": fir,
        "geometric blend": blend_interpolate(path, F, eps, limits, sample_period),
    }
    if include_ocp:
        from research.optimal import time_optimal

        methods["time-optimal OCP"] = time_optimal(path, limits, eps, feed=F, warm_start=fir,
                                                   sample_period=sample_period).trajectory
    horizon = max(float(t.duration) for t in methods.values()) + SETTLE
    drive = eqx.tree_at(lambda m: m.dc, table_6_1_closed_loop(), 0.0)
    modes = [FlexibleMode.from_hz(f, BEAM_DAMPING) for f in BEAMS_HZ]
    out = {}
    for name, traj in methods.items():
        held = _hold_until(traj, horizon)
        deflection = np.asarray(simulate(drive, held, modes=modes).deflection)
        after = np.asarray(held.t) > float(traj.duration) + 0.05
        out[name] = {
            "trajectory": held,
            "deflection": deflection,
            "cycle_time": float(traj.duration),
            "residual_vibration": np.abs(deflection[after]).max(axis=0),
        }
    return out


def make_figure(out_dir: Path, fast: bool = False) -> list[Path]:
    """Write the figure to ``out_dir``; returns the files written (``fast``: without the OCP)."""
    data = comparison(1e-3, include_ocp=not fast)
    fig, ax = mosaic([["path", "feed", "feed"], ["ax", "ay", "ay2"], ["dx", "dy", "dy2"]], figsize=(14, 10))
    ax["ay2"].remove()
    ax["dy2"].remove()
    path = named_path("diamond")
    ax["path"].plot(path.points[:, 0], path.points[:, 1], "k:", lw=0.8)
    for (name, d), colour in zip(data.items(), ("C0", "C1", "C2")):
        tr = d["trajectory"]
        t, q, v, a = (np.asarray(x) for x in (tr.t, tr.q, tr.v, tr.a))
        ax["path"].plot(q[:, 0], q[:, 1], color=colour, lw=0.8, label=name)
        ax["feed"].plot(t, np.linalg.norm(v, axis=1), color=colour, label=f"{name}: {d['cycle_time']:.3f} s")
        ax["ax"].plot(t, a[:, 0], color=colour, lw=0.8, label=name)
        ax["ay"].plot(t, a[:, 1], color=colour, lw=0.8, label=name)
        r = d["residual_vibration"] * 1e3
        ax["dx"].plot(t, d["deflection"][:, 0] * 1e3, color=colour, lw=0.8, label=f"{name}: residual {r[0]:.2f} um")
        ax["dy"].plot(t, d["deflection"][:, 1] * 1e3, color=colour, lw=0.8, label=f"{name}: residual {r[1]:.2f} um")
    ax["path"].set(xlabel="x [mm]", ylabel="y [mm]", title="(a) diamond, eps = 500 um")
    ax["path"].set_aspect("equal", adjustable="datalim")
    ax["feed"].set(xlabel="time [s]", ylabel="feed [mm/s]", title="(b) feed, F = 250 mm/s")
    ax["ax"].set(xlabel="time [s]", ylabel="a_x [mm/s^2]", title="(c) X acceleration")
    ax["ay"].set(xlabel="time [s]", ylabel="a_y [mm/s^2]", title="(d) Y acceleration")
    ax["dx"].set(xlabel="time [s]", ylabel="deflection [um]", title="(e) X beam, 11.4 Hz")
    ax["dy"].set(xlabel="time [s]", ylabel="deflection [um]", title="(f) Y beam, 6.8 Hz")
    for key in ("path", "feed", "ax", "ay", "dx", "dy"):
        ax[key].legend(loc="best", fontsize=7)
    fig.suptitle("FIR T1/T2 = 148/89 ms vs geometric smoothing and OCP held to the FIR's own axis peaks; "
                 "Table 6.1 P-PI drive with the 11.4 Hz (X) and 6.8 Hz (Y) beams", fontsize=8)
    out = Path(out_dir) / f"{NAME}.png"
    save(fig, out)
    return [out]


def _hold_until(traj: Trajectory, horizon: float) -> Trajectory:
    """The same motion, held at rest at its end point until ``horizon`` [s]."""
    n = int(np.ceil(horizon / traj.sample_period)) + 1
    k = traj.n_samples
    if n <= k:
        return traj
    t = np.arange(n) * traj.sample_period
    rest = np.zeros((n - k, traj.n_axes))
    q = np.vstack([np.asarray(traj.q), np.repeat(np.asarray(traj.q[-1:]), n - k, axis=0)])
    v, a, j = (np.vstack([np.asarray(x), rest]) for x in (traj.v, traj.a, traj.j))
    return Trajectory(t, q, v, a, j, traj.duration, traj.exact, traj.axes, traj.sample_period)
