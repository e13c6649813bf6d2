"""Stored Coulomb friction of the thesis ch 5 drives for :mod:`research.figures.sencer2009_fig3_13` (not itself
a figure; the last user of this module: the ch 5 figures are made from configs, ``[control]`` with
``[[control.cases]]``, and Fig 3.13's conversion removes it). The entry is a results-store entry
(``.cache/results/store``, keyed by its parameters and the code version,
:func:`research.experiments.store.result_key`); a missing entry is computed once and stored.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from research.control import FIG5_7_AXIS_PEAKS, identify_coulomb, step_disturbance_peak, table_5_2, thesis_plant
from research.experiments.runner import DEFAULT_CACHE
from research.experiments.store import ResultStore, result_key

#: control period of the Fig 3.13 fast variant [s]: the largest of 1, 0.5, 0.25 ms at which Table 5.2 is stable
FAST_PERIOD = 2.5e-4


def coulomb(T: float, fast: bool = False) -> np.ndarray:
    """Identified Coulomb friction [V] for period ``T`` (stored). ``fast``: the isolated-reversal estimate
    ``peak / (2 g)`` that starts :func:`research.control.identify_coulomb`'s fixed point (no path runs;
    A, C within 5 %, Y half, since Y never reverses on this path)."""
    config = dict(study="sencer2009_ch5_coulomb", T=T, fast=bool(fast))
    store, key = ResultStore(Path(DEFAULT_CACHE) / "store"), result_key(config, kind="sencer2009_ch5")
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
