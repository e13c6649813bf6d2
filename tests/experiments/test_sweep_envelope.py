"""The tolerance envelope of a sweep (``research.experiments.sweep_envelope``): a looser tolerance never
runs slower than a tighter one of the same sweep (issue "FIR cornering on real CAM programs": "a looser
tolerance can make the part 17 % slower, which ruins any tolerance sensitivity study").

Expected values come from a brute-force computation over the rows (every row of the same group with a
tolerance at most its own), never from the envelope's own earlier output."""

import json

import numpy as np
import pytest

from research.experiments.config import load_config
from research.experiments.sweep import run_sweep
from research.experiments.sweep_envelope import OWN_CYCLE_TIME, PLANNED_AT, envelope_field, tolerance_envelope

TOL = "interpolator.tolerance_um"
FEED = "interpolator.feed_mm_per_s"


def _random_rows(rng):
    """A grid of tolerances x feeds with random cycle times (some failed points, repeated tolerances)."""
    tols = rng.choice([10.0, 20.0, 30.0, 50.0, 75.0], size=rng.integers(2, 9))
    rows = []
    for feed in (100.0, 200.0):
        for t in tols:
            i = len(rows)
            if rng.random() < 0.15:
                rows.append({"index": i, TOL: float(t), FEED: feed, "status": "error", "error": "E", "source": "general"})
                continue
            ct = float(rng.uniform(1.0, 2.0))
            rows.append({"index": i, TOL: float(t), FEED: feed, "status": "ok", "error": None, "source": "general",
                         "cycle_time": ct, "max_corner_error": float(rng.uniform(0, t * 1e-3)),
                         "d_cycle_time/d_eps": float(rng.normal()), "d_cycle_time/d_F": float(rng.normal())})
    return rows


@pytest.mark.parametrize("seed", range(40))
def test_envelope_keeps_the_fastest_plan_of_a_tighter_tolerance(seed):
    """Property over random sweep tables: each ok row runs the fastest ok plan of its group (same feed)
    whose tolerance is at most its own (brute force), its own plan where that one is as fast; its
    scalars are then all the kept row's (d cycle time / d eps 0 where kept elsewhere), its own time
    is kept in ``own_cycle_time``; failed rows are unchanged; the input rows are not modified."""
    rng = np.random.default_rng(seed)
    rows = _random_rows(rng)
    before = json.dumps(rows)
    out, moved = tolerance_envelope(rows, TOL, [TOL, FEED])
    assert json.dumps(rows) == before
    n_moved = 0
    for r, o in zip(rows, out):
        if r["status"] != "ok":
            assert o == r
            continue
        pool = [q for q in rows if q["status"] == "ok" and q[FEED] == r[FEED] and q[TOL] <= r[TOL]]
        fastest = min(q["cycle_time"] for q in pool)
        assert o["cycle_time"] == fastest and o[OWN_CYCLE_TIME] == r["cycle_time"]
        if r["cycle_time"] == fastest:
            assert o[PLANNED_AT] == r[TOL] and o == r | {OWN_CYCLE_TIME: r["cycle_time"], PLANNED_AT: r[TOL]}
            continue
        n_moved += 1
        src = [q for q in pool if q["cycle_time"] == fastest and q[TOL] == o[PLANNED_AT]]
        assert src and o[PLANNED_AT] <= r[TOL]
        assert o["max_corner_error"] == src[0]["max_corner_error"] and o["d_cycle_time/d_F"] == src[0]["d_cycle_time/d_F"]
        assert o["d_cycle_time/d_eps"] == 0.0
        assert {k: o[k] for k in ("index", TOL, FEED, "source")} == {k: r[k] for k in ("index", TOL, FEED, "source")}
    assert moved == n_moved
    for feed in (100.0, 200.0):  # non-increasing along the tolerance, per group
        ok = sorted((o[TOL], o["cycle_time"]) for o in out if o["status"] == "ok" and o[FEED] == feed)
        assert all(b[1] <= a[1] for a, b in zip(ok, ok[1:]) if b[0] > a[0])


# seed 187 of tests/interpolators/test_fir_monotone.py (research.paths.library.random_program, lines):
# seven G01 blocks, F = 281.77 mm/s, T = 60/30 ms, on whose eps ladder plan_fir alone rises (measured:
# benchmarks/README.md, "The eps ladder on test_fir_monotone's line programs")
PROGRAM = """
name = "rising"
reproduces = "test"
[path]
points_mm = [[0.0, 0.0], [7.999075984330815, 0.0], [8.498831952940673, 0.015619597908469209],
             [8.50545998138787, -0.0032501990937019998], [35.069149816765815, 13.93842768880194],
             [35.8796839437275, 15.766824371425946], [35.8996724499162, 15.766146418371434],
             [35.419469858282966, 15.626842897279088]]
[interpolator]
feed_mm_per_s = 281.7653895858543
delays_ms = [60.0, 30.0]
tolerance_um = 47.8476023794991
[output]
figure = false
[sweep]
engine = "serial"
{extra}
[sweep.parameters]
"interpolator.tolerance_um" = [47.8476023794991, 52.63236261744901, 59.80950297437388, 71.77140356924865,
                               95.6952047589982, 143.5428071384973]
"""


def test_tolerance_sweep_of_a_rising_program_is_monotone(tmp_path):
    """A whole ``sweep`` run over eps x 1, 1.1, 1.25, 1.5, 2, 3 of a program on which the planner's own
    choice rises: with the envelope (default) the cycle time is non-increasing along eps, every point
    runs a plan of a tolerance at most its own whose own time it reports (the envelope off gives each
    point's own plan, the same times as ``own_cycle_time``), and each corner error stays within
    the point's tolerance."""
    f = tmp_path / "rising.toml"
    f.write_text(PROGRAM.format(extra=""))
    res = run_sweep(f, cache_dir=tmp_path / "c", figures_dir=tmp_path / "f", log=lambda s: None, show_progress=False)
    eps = res.column(TOL)
    ct, own, at = res.column("cycle_time"), res.column(OWN_CYCLE_TIME), res.column(PLANNED_AT)
    assert np.all(np.diff(ct) <= 0.0), ct
    assert np.all(at <= eps) and np.all(ct <= own)
    assert np.all(res.column("max_corner_error") <= eps * 1e-3 * (1 + 1e-9))
    for i in range(eps.size):  # the kept plan is the planned-at point's own plan
        j = int(np.flatnonzero(eps == at[i])[0])
        assert ct[i] == own[j] == np.min(own[: i + 1])
    assert res.stats["tolerance_envelope"] == {"field": TOL, "moved": int(np.sum(at < eps))}
    raw = tmp_path / "raw.toml"
    raw.write_text(PROGRAM.format(extra="tolerance_envelope = false").replace('"rising"', '"raw"'))
    plain = run_sweep(raw, cache_dir=tmp_path / "c", figures_dir=tmp_path / "f", log=lambda s: None, show_progress=False)
    assert "tolerance_envelope" not in plain.stats and OWN_CYCLE_TIME not in plain.rows[0]
    np.testing.assert_array_equal(plain.column("cycle_time"), own)  # the store's own plans, the same points


def test_envelope_applies_only_where_a_tighter_plan_is_valid(tmp_path):
    """``envelope_field``: a single FIR with verified plans (refine or optimized) or the time-optimal
    reference, the tolerance swept, the option on; not with two interpolators (a row's scalars are no
    longer one plan's), not with ``refine = false`` (eq 13/14 alone is not verified on short blocks),
    not where the tolerance is not swept."""
    def cfg(interp, params, extra=""):
        f = tmp_path / "e.toml"
        f.write_text(f'name = "e"\nreproduces = "t"\n[path]\nname = "diamond"\n{interp}\n[sweep]\n{extra}\n'
                     f'[sweep.parameters]\n{params}\n')
        return load_config(f)[0]

    fir = "[interpolator]\ntolerance_um = 100.0"
    tol = '"interpolator.tolerance_um" = [100.0, 200.0]'
    assert envelope_field(cfg(fir, tol)) == TOL
    assert envelope_field(cfg(fir, '"interpolator[0].tolerance_um" = [100.0, 200.0]')) == "interpolator[0].tolerance_um"
    assert envelope_field(cfg(fir, tol, "tolerance_envelope = false")) is None
    assert envelope_field(cfg(fir + "\nrefine = false", tol)) is None
    assert envelope_field(cfg(fir, '"interpolator.feed_mm_per_s" = [100.0, 200.0]')) is None
    assert envelope_field(cfg('[interpolator]\nkind = "time_optimal"\ntolerance_um = 100.0', tol)) == TOL
    two = '[[interpolator]]\ntolerance_um = 100.0\n[[interpolator]]\nkind = "scurve"\nlabel = "s"'
    assert envelope_field(cfg(two, '"interpolator[0].tolerance_um" = [100.0, 200.0]')) is None
