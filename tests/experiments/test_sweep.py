"""Sweeps: expansion, the vmap fast path against the general path, resume, failing points, Dask."""

import json

import numpy as np
import pytest

from research.errors import ConfigError
from research.experiments import sweep_general
from research.experiments.config import load_config
from research.experiments.sweep import format_sweep, run_sweep
from research.experiments.sweep_points import expand, set_field

BASE = """
name = "sw"
reproduces = "test"
[path]
name = "diamond"
[interpolator]
feed_mm_per_s = 250.0
delays_ms = [148.0, 89.0]
tolerance_um = 500.0
[drive]
modes = [{axis = "x", frequency_hz = 11.4}, {axis = "y", frequency_hz = 6.8}]
[output]
figure = false
"""


def write(tmp_path, sweep, base=BASE, name="sw.toml"):
    f = tmp_path / name
    f.write_text(base + sweep)
    return f


def quiet(f, tmp_path, **kw):
    return run_sweep(f, cache_dir=tmp_path / "cache", figures_dir=tmp_path / "figs", log=lambda s: None,
                     show_progress=False, **kw)


def test_expand_grid_and_list(tmp_path):
    grid = write(tmp_path, '[sweep]\n[sweep.parameters]\n"interpolator.delays_ms[0]" = [100.0, 148.0]\n'
                           '"drive.modes[1].frequency_hz" = {start = 6.0, stop = 8.0, num = 3}\n')
    cfg, _ = load_config(grid)
    pts = expand(cfg, grid)
    assert len(pts) == 6 and pts[-1].values == {"interpolator.delays_ms[0]": 148.0, "drive.modes[1].frequency_hz": 8.0}
    assert pts[-1].config.drive.modes[1].frequency_hz == 8.0 and pts[-1].config.interpolators[0].delays_ms == [148.0, 89.0]
    lst = write(tmp_path, '[sweep]\nmode = "list"\n[sweep.parameters]\n"interpolator.tolerance_um" = [1.0, 2.0]\n'
                          '"interpolator.feed_mm_per_s" = [100.0, 200.0]\n', name="l.toml")
    cfg, _ = load_config(lst)
    assert [p.values["interpolator.feed_mm_per_s"] for p in expand(cfg, lst)] == [100.0, 200.0]
    assert set_field({"a": [{"b": 1}]}, "a.b", 2) == {"a": [{"b": 2}]}


@pytest.mark.parametrize("sweep, match", [
    ('"interpolator.delay_ms[0]" = [1.0]',
     r"sweep.parameters.*no field 'interpolator.delay_ms\[0\]'.*did you mean 'interpolator.delays_ms\[0\]'\?"),
    ('"drive.modes[1].frequncy_hz" = [1.0]', r"did you mean 'drive.modes\[1\].frequency_hz'\?"),
    ('"interpolator.delays_ms[5]" = [1.0]', r"no field.*index \[5\] out of range"),
    ('"interpolator.tolerance_um" = [1.0, 2.0]\n"interpolator.feed_mm_per_s" = [1.0]', r"equal lengths"),
])
def test_bad_sweep_fields_name_file_and_key(tmp_path, sweep, match):
    mode = 'mode = "list"\n' if "equal" in match else ""
    f = write(tmp_path, f"[sweep]\n{mode}[sweep.parameters]\n{sweep}\n")
    with pytest.raises(ConfigError, match=match) as e:
        quiet(f, tmp_path)
    assert str(f) in str(e.value)


def test_vmap_sweep_records_failures_resumes_and_matches_general_path(tmp_path):
    f = write(tmp_path, '[sweep]\n[sweep.parameters]\n"interpolator.delays_ms[0]" = [120.0, 148.0, -5.0]\n'
                        '"interpolator.tolerance_um" = [100.0, 500.0]\n')
    res = quiet(f, tmp_path)
    assert res.stats["points"] == 6 and res.stats["ok"] == 4 and res.stats["fast"] == 4
    bad = [r for r in res.rows if r["status"] != "ok"]
    assert len(bad) == 2 and all("delays_ms[0] must be > 0 ms" in r["error"] for r in bad)
    ok = [r for r in res.rows if r["status"] == "ok"]
    assert all(r["source"] == "vmap" and r["max_corner_error"] == pytest.approx(r["interpolator.tolerance_um"] * 1e-3) for r in ok)
    assert all(np.isfinite(r["d_cycle_time/d_T1"]) and np.isfinite(r["d_residual_vibration/d_T2"]) for r in ok)
    assert res.base_sensitivities["d_max_corner_error/d_eps"] == pytest.approx(1.0)
    table = json.loads(res.table_file.read_text())
    assert len(table["rows"]) == 6
    with np.load(res.table_file.with_name("table.npz")) as npz:
        assert npz["ok"].sum() == 4 and npz["cycle_time"].shape == (6,)
    again = quiet(f, tmp_path)  # everything from the store
    assert again.stats["computed"] == 0 and again.stats["cached"] == 4
    assert [r.get("cycle_time") for r in again.rows] == [r.get("cycle_time") for r in res.rows]
    # the general path (exact planner, sampled residual vibration) agrees with the closed forms
    general = quiet(f, tmp_path, engine="serial")
    for a, b in zip(res.rows, general.rows):
        if a["status"] == "ok":
            assert b["source"] == "general"
            assert b["cycle_time"] == pytest.approx(a["cycle_time"], abs=1e-12)
            assert b["max_corner_error"] == pytest.approx(a["max_corner_error"], rel=1e-6)
            assert b["residual_vibration"] == pytest.approx(a["residual_vibration"], rel=2e-3)  # Ts = 1 ms trapezoid
    assert "from the store" in format_sweep(general)


def test_interrupted_general_sweep_resumes_and_failing_point_goes_on(tmp_path, monkeypatch):
    base = BASE.replace('[path]\nname = "diamond"', '[path]\npoints_mm = [[0.0, 0.0], [30.0, 0.0], [30.0, 30.0]]')
    # points_mm[1][0] = 0 repeats points_mm[0]: the strict config refuses that point when the sweep
    # expands it (it is stored as a failed row and never reaches point_task); the others run
    f = write(tmp_path, '[sweep]\n[sweep.parameters]\n"path.points_mm[1][0]" = [0.0, 10.0, 20.0, 40.0]\n', base=base)
    real, calls = sweep_general.point_task, []

    def interrupted(cfg, base_dir):
        calls.append(cfg)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return real(cfg, base_dir)

    monkeypatch.setattr(sweep_general, "point_task", interrupted)
    with pytest.raises(KeyboardInterrupt):
        quiet(f, tmp_path, engine="serial")
    monkeypatch.setattr(sweep_general, "point_task", real)
    res = quiet(f, tmp_path, engine="serial")
    assert res.stats["cached"] == 2 and res.stats["computed"] == 1  # the two finished points were kept
    first = res.rows[0]
    assert first["status"] == "error" and "ConfigError" in first["error"] and "repeats" in first["error"]
    assert [r["status"] for r in res.rows[1:]] == ["ok"] * 3
    # a retry re-validates the refused point (still refused) and recomputes nothing else
    retry = quiet(f, tmp_path, engine="serial", retry_failed=True)
    assert retry.stats["computed"] == 0 and retry.rows[0]["status"] == "error"


def test_dask_local_cluster(tmp_path):
    """A LocalCluster sweep, closed without its nanny killing a worker (issue 16: every Dask sweep ended
    with ``distributed.nanny - WARNING ... killing``)."""
    import logging

    f = write(tmp_path, '[sweep]\nengine = "dask"\n[sweep.parameters]\n"interpolator.tolerance_um" = [100.0, 300.0]\n')
    seen = []
    handler = logging.Handler(logging.WARNING)
    handler.emit = lambda record: seen.append(record.getMessage())
    logging.getLogger("distributed.nanny").addHandler(handler)
    try:
        res = quiet(f, tmp_path, workers=1)  # one worker process: the LocalCluster path at the least start-up cost
    finally:
        logging.getLogger("distributed.nanny").removeHandler(handler)
    assert not [m for m in seen if "killing" in m], seen
    assert res.stats["ok"] == 2 and all(r["source"] == "general" for r in res.rows)
    assert res.rows[1]["max_corner_error"] == pytest.approx(0.3, rel=1e-6)


def test_vmap_engine_refuses_general_fields(tmp_path):
    f = write(tmp_path, '[sweep]\nengine = "vmap"\n[sweep.parameters]\n"interpolator.sample_period_ms" = [1.0, 2.0]\n')
    with pytest.raises(ConfigError, match="sweep.engine"):
        quiet(f, tmp_path)


def test_run_after_sweep_runs_the_base_point_under_its_own_name(tmp_path):
    """Issue 16: ``run`` after ``sweep`` on the same config crashed (a sweep point's store entry served as a
    run's), and ``run`` on a sweep config ignored ``[sweep]`` silently and overwrote the sweep's figure."""
    from research.experiments import run_experiment

    base = BASE.replace('name = "diamond"', 'name = "corner90"').replace("figure = false", "figure = true")
    base = base.replace('modes = [{axis = "x", frequency_hz = 11.4}, {axis = "y", frequency_hz = 6.8}]', "")
    f = write(tmp_path, '[sweep]\nengine = "serial"\n[sweep.parameters]\n"interpolator.tolerance_um" = [100.0, 500.0]\n',
              base=base)
    sw = quiet(f, tmp_path)  # the 500 um point is the base config: stored under the base config's point key
    assert sw.stats["general"] == 2 and sw.figure_file == tmp_path / "figs" / "sw.png"
    sweep_png = sw.figure_file.read_bytes()
    lines = []
    res = run_experiment(f, cache_dir=tmp_path / "cache", figures_dir=tmp_path / "figs", log=lines.append)
    assert any("has a [sweep] table" in s and "only the" in s and "base point" in s for s in lines)
    assert res.figure_file == tmp_path / "figs" / "sw_base.png" and res.figure_file.stat().st_size > 10_000
    assert sw.figure_file.read_bytes() == sweep_png  # the sweep's figure is not overwritten
    assert res.record["experiment"] == "sw" and "metrics" in res.record  # a run record, not a sweep point's
    assert res.record["scalars"]["max_corner_error"] == pytest.approx(0.5, rel=1e-9)  # eq 14: error = eps
    assert res.results_file.parent.name == "sw_base"
    again = run_experiment(f, cache_dir=tmp_path / "cache", figures_dir=tmp_path / "figs", log=lambda s: None)
    assert again.cached and again.figure_file == res.figure_file


class _Bar:
    """Stands in for tqdm: records every update."""
    updates: list = []

    def __init__(self, total, **kw):
        self.total = total

    def update(self, n=1):
        _Bar.updates.append(n)

    def close(self):
        pass


def test_engine_lines_progress_and_sensitivities_are_honest(tmp_path, monkeypatch):
    """A sweep whose fast-path candidates partly fall outside the closed forms' domain: the engine lines
    count what actually ran where, the bar only goes forward and ends at the total, the general-path
    points are said to have no sensitivities, and rows carry units."""
    from research.experiments import sweep as sweep_mod

    # 5 mm legs: at 250 mm/s a leg takes 20 ms, shorter than T1 + T2 = 237 ms (closed forms not exact);
    # at 20 mm/s it takes 250 ms (exact)
    base = BASE.replace('[path]\nname = "diamond"', '[path]\npoints_mm = [[0.0, 0.0], [5.0, 0.0], [5.0, 5.0]]')
    f = write(tmp_path, '[sweep]\n[sweep.parameters]\n"interpolator.feed_mm_per_s" = [20.0, 250.0]\n', base=base)
    _Bar.updates = []
    monkeypatch.setattr(sweep_mod, "tqdm", _Bar)
    lines = []
    res = run_sweep(f, cache_dir=tmp_path / "cache", figures_dir=tmp_path / "figs", log=lines.append)
    assert [r["source"] for r in res.rows] == ["vmap", "general"]
    assert all(n >= 0 for n in _Bar.updates) and sum(_Bar.updates) == 2
    assert "on the vmap fast path," not in lines[0] and "candidates for the vmap fast path" in lines[0]
    assert "vmap fast path: 1 points; 1 outside the closed forms' domain" in "\n".join(lines)
    assert "engines: 1 points on the vmap fast path, 1 on the general path" in lines
    text = format_sweep(res)
    assert "unavailable for the 1 general-path points" in text
    assert "cycle_time [s]" in text and "max_corner_error [mm]" in text
    table = json.loads(res.table_file.read_text())
    assert table["units"]["cycle_time"] == "s" and table["units"]["d_cycle_time/d_T1"] == "s/(s)"
    assert table["units"]["residual_vibration.x"] == "mm"


def test_sensitivities_unavailable_off_the_fast_path(tmp_path):
    f = write(tmp_path, '[sweep]\nengine = "serial"\n[sweep.parameters]\n"interpolator.tolerance_um" = [100.0]\n')
    res = quiet(f, tmp_path)
    assert res.base_sensitivities is None
    assert "sensitivities: unavailable" in format_sweep(res)


def test_sweep_axis_labels_come_from_the_schema(tmp_path):
    """Issue 16 item 6: sweep axes were labelled with raw keys (``interpolator.delays_ms[0]``); the label is
    the schema's description of the field, with the list index as the symbol's subscript and the unit."""
    from research.experiments.config import FIRConfig, ModeConfig
    from research.experiments.sweep_figure import field_label

    cfg, _ = load_config(write(tmp_path, ""))
    assert FIRConfig.model_fields["delays_ms"].description == "FIR delays T_i [ms]"
    assert field_label("interpolator.delays_ms[0]", cfg) == "FIR delays T_1 [ms]"
    assert field_label("interpolator.delays_ms[1]", cfg) == "FIR delays T_2 [ms]"
    assert field_label("interpolator.tolerance_um", cfg) == FIRConfig.model_fields["tolerance_um"].description
    assert field_label("drive.modes[1].frequency_hz", cfg) == (
        ModeConfig.model_fields["frequency_hz"].description + " (mode 2, y)")
    assert field_label("drive.modes[0].damping", cfg) == "damping ratio [-] (mode 1, x)"
    assert field_label("no.such_field", cfg) == "no.such_field"


def test_sweep_points_keep_the_program_feeds_and_the_fields_left_unwritten(tmp_path):
    """A sweep point is the config as written with the swept fields set: on a G-code path without
    ``feed_mm_per_s`` every point runs the program's F words (20 and 10 mm/s, from F1200 / F600
    mm/min), as ``run`` does -- not the field's default 250 mm/s -- and a swept field the config
    leaves at its default (``sample_period_ms``) is set on each point all the same. The points'
    peak feeds stay at the program's 20 mm/s."""
    (tmp_path / "part.nc").write_text("G21 G90\nG1 X10 F1200\nG1 X10 Y10 F600\n")
    base = ('name = "g"\nreproduces = "test"\n[path]\ngcode = "part.nc"\n[interpolator]\ndelays_ms = [50.0, 30.0]\n'
            'tolerance_um = 100.0\n[output]\nfigure = false\n')
    f = write(tmp_path, '[sweep]\n[sweep.parameters]\n"interpolator.tolerance_um" = [50.0, 200.0]\n'
                        '"interpolator.sample_period_ms" = [0.5]\n', base=base)
    cfg, _ = load_config(f)
    points = expand(cfg, f)
    assert all("feed_mm_per_s" not in p.config.interpolators[0].model_fields_set for p in points)
    assert [p.config.interpolators[0].sample_period_ms for p in points] == [0.5, 0.5]
    res = quiet(f, tmp_path)
    peaks = list(res.column("peak_feed"))
    assert len(peaks) == 2 and max(peaks) <= 20.0 * (1 + 1e-9), peaks


def test_store_key_tells_program_feeds_from_a_written_default(tmp_path):
    """On a G-code path a written ``feed_mm_per_s = 250`` (every block at 250 mm/s) and the field
    left out (the program's F words) are different runs: different store keys, and the second run is
    computed, not served the first one's feeds."""
    from research.experiments import run_experiment

    (tmp_path / "part.nc").write_text("G21 G90\nG1 X10 F1200\nG1 X10 Y10 F600\n")
    base = ('name = "g"\nreproduces = "test"\n[path]\ngcode = "part.nc"\n[interpolator]\ndelays_ms = [50.0, 30.0]\n'
            'tolerance_um = 100.0\n[output]\nfigure = false\n')
    own = run_experiment(write(tmp_path, "", base=base, name="a.toml"), cache_dir=tmp_path / "c",
                         figures_dir=tmp_path / "f", log=lambda s: None)
    written = run_experiment(write(tmp_path, "", base=base.replace("[interpolator]\n", "[interpolator]\nfeed_mm_per_s = 250.0\n"),
                                   name="b.toml"), cache_dir=tmp_path / "c", figures_dir=tmp_path / "f", log=lambda s: None)
    assert own.key != written.key and not written.cached
    np.testing.assert_allclose(own.record["details"]["fir"]["feeds"], [20.0, 10.0])
    np.testing.assert_allclose(written.record["details"]["fir"]["feeds"], [250.0, 250.0])
