"""Stored results of the thesis ch 5 closed-loop runs that the Fig 5.7-5.10 modules plot (not itself a
figure). Each run is a results-store entry (``.cache/results/store``, keyed by its parameters and the
code version, :func:`research.experiments.store.result_key`): the figure modules only read the entry's
arrays; a missing entry is computed once by :func:`research.control.run_case` and stored.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from research.control import (
    CONTROL_PERIOD,
    FIG5_7_AXIS_PEAKS,
    feedback_vs_feedforward,
    identify_coulomb,
    run_case,
    step_disturbance_peak,
    table_5_2,
    table_5_3,
    thesis_plant,
)
from research.experiments.runner import DEFAULT_CACHE
from research.experiments.store import ResultStore, result_key

#: control period of the figures' fast variant [s]: the largest of 1, 0.5, 0.25 ms at which Table 5.2 is stable
FAST_PERIOD = 2.5e-4


def _store() -> ResultStore:
    return ResultStore(Path(DEFAULT_CACHE) / "store")


def coulomb(T: float, fast: bool = False) -> np.ndarray:
    """Identified Coulomb friction [V] for period ``T`` (stored). ``fast``: the isolated-reversal estimate
    ``peak / (2 g)`` that starts :func:`research.control.identify_coulomb`'s fixed point (no path runs;
    A, C within 5 %, Y half, since Y never reverses on this path)."""
    config = dict(study="sencer2009_ch5_coulomb", T=T, fast=bool(fast))
    store, key = _store(), result_key(config, kind="sencer2009_ch5")
    entry = store.get(key)
    if entry is None:
        if fast:
            p, g = thesis_plant(), table_5_2()
            dc = np.asarray(FIG5_7_AXIS_PEAKS) / (2 * np.array(
                [step_disturbance_peak(float(p.m[i]), float(p.c[i]), g, i, T) for i in range(5)]))
        else:
            dc = identify_coulomb(T=T)
        entry = store.put(key, config, {"coulomb": dc})
    return entry.arrays()["coulomb"]


def case(controller: str, *, feed: float = 50.0, W: float = 0.0, wn=(100.0, 230.0, 230.0), fast: bool = False) -> dict:
    """Arrays and summary of one run: ``controller`` is ``"siso"`` (Table 5.2) or ``"contour"`` (Table 5.3
    with ``W = diag(W, W)`` and tip bandwidths ``wn``).

    Returns:
        ``{"t", "axis_error", "contour", "contour_estimate", "orientation", "orientation_estimate", "u"}`` arrays and ``"summary"``.
    """
    T = FAST_PERIOD if fast else CONTROL_PERIOD
    config = dict(study="sencer2009_ch5_case", controller=controller, feed=float(feed), T=T)
    if controller == "contour":
        config.update(W=float(W), wn=[float(w) for w in wn])
    store, key = _store(), result_key(config, kind="sencer2009_ch5")
    entry = store.get(key)
    if entry is None:
        gains = table_5_2() if controller == "siso" else table_5_3().with_weights(W, W).with_bandwidths(wn)
        r = run_case(gains, feed=feed, coulomb=coulomb(T, fast), T=T)
        arrays = dict(t=r.t, axis_error=r.axis_error, contour=r.contour, contour_estimate=r.contour_estimate,
                      orientation=r.orientation, orientation_estimate=r.orientation_estimate, u=r.u)
        entry = store.put(key, dict(config, summary=r.summary()), arrays)
    out = dict(entry.arrays())
    out["summary"] = entry.record["summary"]
    return out


def feedforward_comparison(*, feed: float = 50.0, passes: int = 3, fast: bool = False) -> dict:
    """Stored :func:`research.control.feedback_vs_feedforward` rows: ``{"names", "summaries"}`` and per row
    ``contour_<i>``, ``orientation_<i>`` arrays with the shared ``t``."""
    T = FAST_PERIOD if fast else CONTROL_PERIOD
    config = dict(study="sencer2009_ch5_feedforward", feed=float(feed), passes=int(passes), T=T)
    store, key = _store(), result_key(config, kind="sencer2009_ch5")
    entry = store.get(key)
    if entry is None:
        rows = feedback_vs_feedforward(feed=feed, passes=passes, coulomb=coulomb(T, fast), T=T)
        arrays = {"t": rows[0].case.t}
        for i, r in enumerate(rows):
            arrays[f"contour_{i}"], arrays[f"orientation_{i}"] = r.case.contour, r.case.orientation
        entry = store.put(key, dict(config, names=[r.name for r in rows], summaries=[r.case.summary() for r in rows]), arrays)
    out = dict(entry.arrays())
    out["names"], out["summaries"] = entry.record["names"], entry.record["summaries"]
    return out
