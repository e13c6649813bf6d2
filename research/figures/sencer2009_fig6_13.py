"""Sencer (2009) thesis §6.5.3, Table 6.3 and Fig 6.13: each axis of the Table 6.3 virtual 5-axis machine
identified with LS (eq 6.12) and PSO (§6.4) on the §6.5 program, the estimate columns beside the
thesis' "Actual" and "PSO Estimated" columns, and the tool-tip contour error of the Chapter 4 spiral
(eq 4.36) at 75 mm/s predicted with the identified models against the true machine (thesis: "The
discrepancy between the estimated and true contour errors is observed to be less than 10 [micron]").
Simulation; assumptions in :mod:`research.control._identified_machine`. The run is a results-store
entry (``.cache/results/store``); the figure only reads it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from research.figures._style import mosaic, save

NAME = "sencer2009_fig6_13_identified_5axis"
REPRODUCES = ("Sencer 2009 thesis Table 6.3 (LS / PSO estimates of the P-PI virtual 5-axis machine) and Fig 6.13 "
              "(identified models predict the 5-axis contour error at 75 mm/s within 10 um of the true machine)")
_COLUMNS = ("actual", "ls", "pso", "thesis_pso")


def stored(fast: bool = False) -> dict:
    """The stored run: ``{"t", "true", "ls", "pso"}`` arrays and ``"columns"`` (Table 6.3 layout per axis:
    ``(wn [Hz], zeta, p [Hz], dc, stable)`` for actual / ls / pso / thesis_pso) and ``"excluded"``.
    ``fast`` is accepted for the figures CLI; the run is the same (about a minute on 2 loaded cores)."""
    from research.control._identified_machine import AXES, fig6_13
    from research.experiments.runner import DEFAULT_CACHE
    from research.experiments.store import ResultStore, result_key

    config = dict(study="sencer2009_fig6_13", seed=0)
    store, key = ResultStore(Path(DEFAULT_CACHE) / "store"), result_key(config, kind="sencer2009_ch6")
    entry = store.get(key)
    if entry is None:
        ident, pred = fig6_13(seed=0)
        columns = {a: ident[a].columns() for a in AXES}
        arrays = dict(t=pred.t, true=pred.true, **pred.predicted)
        entry = store.put(key, dict(config, columns=columns, excluded=pred.excluded), arrays)
    out = dict(entry.arrays())
    out["columns"] = entry.record["columns"]
    out["excluded"] = entry.record["excluded"]
    return out


def _fmt(v) -> str:
    return "-" if v is None else (f"{v:.4g}" if isinstance(v, float) else str(v))


def make_figure(out_dir: Path, fast: bool = False) -> list[Path]:
    """Write the Fig 6.13 panels and the Table 6.3 columns to ``out_dir``; returns the files written."""
    out_dir = Path(out_dir)
    run = stored(fast)
    fig, ax = mosaic([["a", "a"], ["b", "t"]], figsize=(12, 8))
    ax["a"].plot(run["t"], run["true"] * 1e3, "k", lw=1.6, label="true Table 6.3 machine")
    for m, style in (("ls", "C0--"), ("pso", "C3:")):
        if m in run:
            d = np.abs(run[m] - run["true"]).max() * 1e3
            ax["a"].plot(run["t"], run[m] * 1e3, style, label=f"{m.upper()}-identified models (max discrepancy {d:.2f} um)")
            ax["b"].plot(run["t"], np.abs(run[m] - run["true"]) * 1e3, style, label=m.upper())
    ax["a"].set(xlabel="time [s]", ylabel="tool-tip contour error [um]",
                title="(a) eq 4.36 spiral at 75 mm/s, 1500 mm/s^2: true and predicted contour error (exact)")
    ax["a"].legend()
    ax["b"].axhline(10.0, color="C1", lw=1, label="thesis bound 10 um")
    ax["b"].set(xlabel="time [s]", ylabel="|predicted - true| [um]", title="(b) discrepancy")
    ax["b"].legend()
    rows = []
    for a, cols in run["columns"].items():
        for c in _COLUMNS:
            v = cols[c]
            rows.append([a.upper(), c, *(_fmt(x) for x in v[:4]), _fmt(v[4])])
    t = ax["t"]
    t.axis("off")
    tab = t.table(cellText=rows, colLabels=["axis", "column", "wn [Hz]", "zeta", "p [Hz]", "dc", "stable"], loc="center",
                  fontsize=7)
    tab.scale(1, 0.9)
    t.set_title("Table 6.3: actual, LS, PSO (this run), PSO (thesis, printed)", pad=28)
    out = out_dir / f"{NAME}.png"
    save(fig, out)
    return [out]
