"""Experiment configs: schema errors name the file and the key; the runner writes its outputs."""

import json
from pathlib import Path

import numpy as np
import pytest

from research.errors import ConfigError
from research.experiments import load_config, run_experiment
from research.trajectory import Trajectory

REPO = Path(__file__).resolve().parents[2]
GOOD = """
name = "t"
reproduces = "test"
[path]
name = "corner90"
[interpolator]
feed_mm_per_s = 200.0
delays_ms = [50.0, 30.0]
tolerance_um = 100.0
"""


def write(tmp_path, text, name="exp.toml"):
    f = tmp_path / name
    f.write_text(text)
    return f


@pytest.mark.parametrize(
    "edit, match",
    [
        (("tolerance_um = 100.0", "tolerence_um = 100.0"), r"key 'interpolator.tolerence_um': unknown key \(typo\? did you mean 'tolerance_um'\?\)"),
        (("feed_mm_per_s = 200.0", 'feed_mm_per_s = "fast"'), r"key 'interpolator.feed_mm_per_s': .*number.*'fast'"),
        (("feed_mm_per_s = 200.0", "feed_mm_per_s = -1.0"), r"key 'interpolator.feed_mm_per_s': .*greater than 0"),
        (("delays_ms = [50.0, 30.0]", "delays_ms = [50.0, 0.0]"), r"delays_ms\[1\] must be > 0 ms"),
        (('name = "corner90"', 'name = "circle"'), r"key 'path': unknown path name 'circle'"),
        (('name = "corner90"', 'name = "corner90"\ngcode = "x.nc"'), r"exactly one of name, gcode, points_mm"),
        (('reproduces = "test"', 'reproduces = 3'), r"key 'reproduces': Input should be a valid string"),
        (("[interpolator]", "[interpolator"), r"TOML syntax error"),
        # unit plausibility (issue 16: `delays_ms = [0.06, 0.03]` passed and printed a jerk of inf)
        (("delays_ms = [50.0, 30.0]", "delays_ms = [0.06, 0.03]"),
         r"key 'interpolator.delays_ms\[0\]': .*0.06 ms is below the sample period.*seconds \(0.06 s = 60 ms\)"),
        (("delays_ms = [50.0, 30.0]", "delays_ms = [50.0, 30.0]\nsample_period_ms = 40.0"),
         r"key 'interpolator.delays_ms\[1\]': .*30 ms is below the sample period sample_period_ms = 40 ms"),
        (("feed_mm_per_s = 200.0", "feed_mm_per_s = 0.25"), r"key 'interpolator.feed_mm_per_s': .*below 1 mm/s.*m/s"),
        (("feed_mm_per_s = 200.0", "feed_mm_per_s = 15000.0"),
         r"key 'interpolator.feed_mm_per_s': .*above 10000 mm/s.*mm/min \(15000 mm/min = 250 mm/s\)"),
        (('[interpolator]\nfeed_mm_per_s = 200.0\ndelays_ms = [50.0, 30.0]',
          '[interpolator]\nkind = "time_optimal"\nfeed_mm_per_s = 200.0\nenvelope_delays_ms = [0.05, 30.0]'),
         r"key 'interpolator.envelope_delays_ms\[0\]': .*below the sample period"),
    ],
)
def test_config_errors_name_file_and_key(tmp_path, edit, match):
    f = write(tmp_path, GOOD.replace(*edit))
    with pytest.raises(ConfigError, match=match) as e:
        load_config(f)
    assert str(f) in str(e.value)


def test_shipped_configs_validate():
    files = sorted((REPO / "experiments").glob("*.toml"))
    assert files
    for f in files:
        cfg, _ = load_config(f)
        assert cfg.reproduces


def test_run_writes_results_and_figure(tmp_path):
    result = run_experiment(write(tmp_path, GOOD), cache_dir=tmp_path / "cache", figures_dir=tmp_path / "figs", log=lambda s: None)
    record = json.loads(result.results_file.read_text())
    assert record["metrics"]["max_corner_error"] == pytest.approx(0.1, rel=1e-6)
    assert record["config"]["interpolator"][0]["delays_ms"] == [50.0, 30.0]
    traj = Trajectory.load(tmp_path / "cache" / "t" / "trajectory.npz")
    assert np.max(np.abs(traj.q[-1] - np.array([0.0, 50.0]))) < 1e-9
    assert result.figure_file.exists() and result.figure_file.stat().st_size > 10_000


def test_gcode_path_uses_program_feeds(tmp_path):
    (tmp_path / "part.nc").write_text("G21 G90\nG1 X10 F1200\nG1 Y10 F600\n")
    text = GOOD.replace('name = "corner90"', 'gcode = "part.nc"').replace("feed_mm_per_s = 200.0\n", "")
    result = run_experiment(write(tmp_path, text), cache_dir=tmp_path / "c", figures_dir=tmp_path / "f", log=lambda s: None)
    np.testing.assert_allclose(result.record["details"]["fir"]["feeds"], [20.0, 10.0])  # mm/min -> mm/s


def test_config_of_ones_own_program_needs_no_paper(tmp_path):
    """A study of one's own program or machine names no paper result: ``reproduces`` may be left out
    (empty), and the report then has no "Reproduces" line."""
    cfg = load_config(write(tmp_path, GOOD.replace('reproduces = "test"\n', "")))[0]
    assert cfg.reproduces == ""


def test_gcode_path_without_f_words_runs_from_initial_feed(tmp_path):
    """A program with no F word reads with ``[path] initial_feed_mm_per_s`` (a controller's default
    feed: 25 mm/s here, the feed of every block); without it the run stops at the first move's line."""
    (tmp_path / "part.nc").write_text("G21 G90\nG1 X10\nG1 Y10\n")
    text = GOOD.replace('name = "corner90"', 'gcode = "part.nc"\ninitial_feed_mm_per_s = 25.0')
    text = text.replace("feed_mm_per_s = 200.0\n", "")
    result = run_experiment(write(tmp_path, text), cache_dir=tmp_path / "c", figures_dir=tmp_path / "f", log=lambda s: None)
    np.testing.assert_allclose(result.record["details"]["fir"]["feeds"], [25.0, 25.0])
    with pytest.raises(Exception, match=r"part.nc:2:1: G1 motion before any F word"):
        run_experiment(write(tmp_path, text.replace("initial_feed_mm_per_s = 25.0\n", ""), "b.toml"),
                       cache_dir=tmp_path / "c2", figures_dir=tmp_path / "f", log=lambda s: None)
    with pytest.raises(ConfigError, match=r"initial_feed_mm_per_s"):
        load_config(write(tmp_path, GOOD.replace('name = "corner90"', 'name = "corner90"\ninitial_feed_mm_per_s = 5'),
                          "c.toml"))


def test_gcode_path_block_delete_switch(tmp_path):
    """``[path] block_delete``: a '/' line of the program is read without its '/' by default (two
    blocks of 10 mm: feeds of both) and skipped with ``block_delete = true`` (one block); the switch
    without a G-code path is a config error naming it."""
    (tmp_path / "part.nc").write_text("G21 G90 F600\nG1 X10\n/G1 Y10\n")
    text = GOOD.replace('name = "corner90"', 'gcode = "part.nc"')

    def run(t, name):  # the feed of each planned block
        result = run_experiment(write(tmp_path, t, name), cache_dir=tmp_path / f"cache-{name}",
                                figures_dir=tmp_path / "f", log=lambda s: None)
        return result.record["details"]["fir"]["feeds"]

    assert len(run(text, "a.toml")) == 2
    assert len(run(text.replace('gcode = "part.nc"', 'gcode = "part.nc"\nblock_delete = true'), "b.toml")) == 1
    with pytest.raises(ConfigError, match=r"block_delete"):
        load_config(write(tmp_path, GOOD.replace('name = "corner90"', 'name = "corner90"\nblock_delete = true'),
                          "c.toml"))


def test_summary_names_the_programs_g64_tolerances_and_the_planner(tmp_path):
    """A program whose ``G64 P`` (10 and 200 um) governs its blocks: the summary's tolerance row gives
    those, not the config's 50 um beside a 200 um corner error, and a mirror plan is named as one."""
    from research.experiments.runner import format_summary

    (tmp_path / "part.nc").write_text("G21 G90 F6000\nG64 P0.01\nG1 X10\nG1 Y10\nG64 P0.2\nG1 X0\nG1 Y0\nM2\n")
    text = GOOD.replace('name = "corner90"', 'gcode = "part.nc"').replace("feed_mm_per_s = 200.0\n", "")
    text = text.replace("tolerance_um = ", "mirror = true\ntolerance_um = ")
    result = run_experiment(write(tmp_path, text), cache_dir=tmp_path / "c", figures_dir=tmp_path / "f", log=lambda s: None)
    summary = format_summary(result)
    assert "10 .. 200 (the program's G64 P;" in summary
    assert "fir (plan_fir_mirror)" in summary


def test_gcode_path_after_m30_is_not_run_and_is_reported(tmp_path, caplog):
    """Text after M30 (here a second, malformed program) is not read, as LinuxCNC does; the run plans
    the two moves before it and logs a warning naming the file, the end line and the unread lines."""
    (tmp_path / "part.nc").write_text("G21 G90\nG1 X10 F1200\nG1 Y10 F600\nM30\n\nO0002\nG1 X#1\n")
    text = GOOD.replace('name = "corner90"', 'gcode = "part.nc"').replace("feed_mm_per_s = 200.0\n", "")
    with caplog.at_level("WARNING"):
        result = run_experiment(write(tmp_path, text), cache_dir=tmp_path / "c", figures_dir=tmp_path / "f",
                                log=lambda s: None)
    np.testing.assert_allclose(result.record["details"]["fir"]["feeds"], [20.0, 10.0])
    assert any("part.nc: the program ends on line 4" in r.getMessage() and "2 non-blank line(s)" in r.getMessage()
               and "first: line 6" in r.getMessage() for r in caplog.records), caplog.text


def test_gcode_path_with_g28_reads_home_mm(tmp_path):
    """A post-processor's G28 G91 Z0 retract: with ``home_mm`` the program reads and runs (the retract
    from z = 5 to the home z = 20 is a rapid block of 15 mm, X then home from (10, 0)); without it
    LinuxCNC's default home, the machine origin, (0, 0, 0) here. ``home_mm`` with a named
    path is a config error."""
    (tmp_path / "part.nc").write_text("G21 G90\nG0 Z5\nG1 X10 F1200\nG28 G91 Z0\nG90\nG28 X10\nM30\n")
    text = GOOD.replace('name = "corner90"', 'gcode = "part.nc"\nhome_mm = [0.0, 0.0, 20.0]')
    text = text.replace("feed_mm_per_s = 200.0\n", "")
    result = run_experiment(write(tmp_path, text), cache_dir=tmp_path / "c", figures_dir=tmp_path / "f", log=lambda s: None)
    traj = Trajectory.load(tmp_path / "c" / "t" / "trajectory.npz")
    np.testing.assert_allclose(traj.q[-1], [0.0, 0.0, 20.0], atol=1e-9)
    assert result.record["details"]["fir"]["feeds"][0] == pytest.approx(15000.0 / 60.0)  # G0 at the rapid feed
    # without it LinuxCNC's default home, the machine origin (0, 0, 0) here: the run ends there
    run_experiment(write(tmp_path, text.replace("home_mm = [0.0, 0.0, 20.0]\n", ""), "b.toml"),
                   cache_dir=tmp_path / "c2", figures_dir=tmp_path / "f", log=lambda s: None)
    np.testing.assert_allclose(Trajectory.load(tmp_path / "c2" / "t" / "trajectory.npz").q[-1], [0, 0, 0], atol=1e-9)
    with pytest.raises(ConfigError, match=r"home_mm"):
        load_config(write(tmp_path, GOOD.replace('name = "corner90"', 'name = "corner90"\nhome_mm = [0, 0, 1]'), "c.toml"))


def test_gcode_path_with_g53_reads_machine_origin_mm(tmp_path):
    """A post's ``G53 G0 Z0.`` / ``G53 G0 X0. Y0.`` end-of-program retract, read with ``machine_origin_mm =
    [-5, 2, 20]``: from (10, 0, 5) a rapid to z = 20 + 0, then to x = -5 + 0, y = 2 + 0 (z kept), so the
    run ends at (-5, 2, 20) and its block feeds are rapid, F1200 = 20 mm/s, rapid, rapid (the rapid feed
    15000 mm/min = 250 mm/s). Without the key LinuxCNC's default (a work offset of 0) puts the end at
    the program's origin; a misspelt key is the usual "did you mean"; the key with a named
    path, or with two coordinates, is a config error."""
    (tmp_path / "part.nc").write_text("G21 G90\nG0 Z5\nG1 X10 F1200\nG53 G0 Z0.\nG53 X0. Y0.\nM30\n")
    text = GOOD.replace('name = "corner90"', 'gcode = "part.nc"\nmachine_origin_mm = [-5.0, 2.0, 20.0]')
    text = text.replace("feed_mm_per_s = 200.0\n", "")
    result = run_experiment(write(tmp_path, text), cache_dir=tmp_path / "c", figures_dir=tmp_path / "f", log=lambda s: None)
    traj = Trajectory.load(tmp_path / "c" / "t" / "trajectory.npz")
    np.testing.assert_allclose(traj.q[-1], [-5.0, 2.0, 20.0], atol=1e-9)
    np.testing.assert_allclose(result.record["details"]["fir"]["feeds"], [250.0, 20.0, 250.0, 250.0], rtol=1e-12)
    # without it LinuxCNC's default work offset of 0: the program's origin, where the run ends
    run_experiment(write(tmp_path, text.replace("machine_origin_mm = [-5.0, 2.0, 20.0]\n", ""), "b.toml"),
                   cache_dir=tmp_path / "c2", figures_dir=tmp_path / "f", log=lambda s: None)
    np.testing.assert_allclose(Trajectory.load(tmp_path / "c2" / "t" / "trajectory.npz").q[-1], [0, 0, 0], atol=1e-9)
    typo = write(tmp_path, text.replace("machine_origin_mm", "machine_orign_mm"), "typo.toml")
    with pytest.raises(ConfigError, match=r"key 'path.machine_orign_mm': unknown key \(typo\? did you mean "
                                          r"'machine_origin_mm'\?\)") as e:
        load_config(typo)
    assert str(typo) in str(e.value)
    with pytest.raises(ConfigError, match=r"machine_origin_mm only apply to a G-code path"):
        load_config(write(tmp_path, GOOD.replace('name = "corner90"', 'name = "corner90"\nmachine_origin_mm = [0, 0, 1]'),
                          "c.toml"))
    with pytest.raises(ConfigError, match=r"machine_origin_mm = \[0.0, 1.0\]: expected 3 coordinates"):
        load_config(write(tmp_path, text.replace("[-5.0, 2.0, 20.0]", "[0, 1]"), "d.toml"))


def test_gcode_pauses_are_planned_by_fir_and_refused_elsewhere(tmp_path):
    """A program with a spindle warm-up ``G4 P1.5`` and an ``M1`` between its two cuts: the FIR run's
    cycle time is the two cuts planned alone (here, from the same planner without pauses) plus 1.5 s;
    the S-curve's is the same program's without the pauses plus 1.5 s; a corner-blending interpolator,
    which has no pauses, is refused by name with the program's lines."""
    from research.interpolators import plan_fir
    from research.paths import Polyline

    (tmp_path / "part.nc").write_text("G21 G90\nM3 S1000\nG4 P1.5\nG1 X10 F1200\nG1 Y10\nM1\nG1 X0\nM30\n")
    text = GOOD.replace('name = "corner90"', 'gcode = "part.nc"').replace("feed_mm_per_s = 200.0\n", "")
    result = run_experiment(write(tmp_path, text), cache_dir=tmp_path / "c", figures_dir=tmp_path / "f", log=lambda s: None)
    d = (0.05, 0.03)
    first = plan_fir(Polyline([[0, 0, 0], [10, 0, 0], [10, 10, 0]]), 20.0, d, 0.1)  # tolerance_um = 100
    second = plan_fir(Polyline([[10, 10, 0], [0, 10, 0]]), 20.0, d, 0.1)
    expected = float(first.cycle_time) + float(second.cycle_time) + 1.5
    assert result.record["scalars"]["cycle_time"] == pytest.approx(expected, abs=1e-3)  # sampled at 1 ms
    # the S-curve stops at every vertex anyway: the pauses add their 1.5 s to the same moves
    scurve = text.replace("[interpolator]\n", '[interpolator]\nkind = "scurve"\n').replace("delays_ms = [50.0, 30.0]\n", "")
    scurve = scurve.replace("tolerance_um = 100.0\n", "")
    (tmp_path / "plain.nc").write_text("G21 G90\nM3 S1000\nG1 X10 F1200\nG1 Y10\nG1 X0\nM30\n")
    times = [run_experiment(write(tmp_path, scurve.replace("part.nc", name), f"{name}.toml"), cache_dir=tmp_path / f"c_{name}",
                            figures_dir=tmp_path / "f", log=lambda s: None).record["scalars"]["cycle_time"]
             for name in ("part.nc", "plain.nc")]
    assert times[0] - times[1] == pytest.approx(1.5, abs=1e-3)  # sampled at 1 ms
    blend = text.replace("[interpolator]\n", '[interpolator]\nkind = "blend"\n').replace("delays_ms = [50.0, 30.0]\n", "")
    with pytest.raises(ConfigError, match=r"part.nc pauses \(G4 / M0 / M1 / M60\) next to the moves of lines \[4, 5\].*kind 'blend' "
                                          r"does not plan pauses"):
        run_experiment(write(tmp_path, blend, "s.toml"), cache_dir=tmp_path / "c2", figures_dir=tmp_path / "f",
                       log=lambda s: None)


# -- strict configs (issue: nothing silently wrong) -------------------------------------------------------
BASE = 'name = "t"\nreproduces = "test"\n'
PATH = '[path]\nname = "corner90"\n'


@pytest.mark.parametrize("table, line, match", [
    # item 4: TOML inf / nan for constrained numbers
    ("[interpolator]", "feed_mm_per_s = inf", r"'interpolator.feed_mm_per_s': .*finite number"),
    ("[drive]", 'modes = [{axis = "x", frequency_hz = inf}]', r"'drive.modes\[0\].frequency_hz': .*finite number"),
    ("[drive]", "settle_time_s = inf", r"'drive.settle_time_s': .*finite number"),
    ("[interpolator]", "tolerance_um = nan", r"'interpolator.tolerance_um': .*finite number"),
    ("[interpolator]", "delays_ms = [148.0, -inf]", r"'interpolator.delays_ms\[1\]': .*finite number"),
    # item 5: no coercion
    ("[interpolator]", "feed_mm_per_s = true", r"'interpolator.feed_mm_per_s': .*a bool is not a number"),
    ("[identification]", "noise_um = false", r"'identification.noise_um': .*a bool is not a number"),
    ("[interpolator]", 'feed_mm_per_s = "250"', r"'interpolator.feed_mm_per_s': .*not a string"),
    ("[interpolator]", 'refine = "yes"', r"'interpolator.refine': .*valid boolean"),
    ("[identification]", "n_moves = 10.0", r"'identification.n_moves': .*valid integer"),
    ("[identification]", "seed = true", r"'identification.seed': .*valid integer"),
])
def test_non_finite_and_coerced_values_are_refused(tmp_path, table, line, match):
    f = write(tmp_path, BASE + PATH + f"{table}\n{line}\n")
    with pytest.raises(ConfigError, match=match) as e:
        load_config(f)
    assert str(f) in str(e.value)


def test_toml_int_for_a_float_field_is_fine(tmp_path):
    cfg, _ = load_config(write(tmp_path, BASE + PATH + "[interpolator]\nfeed_mm_per_s = 250\ndelays_ms = [148, 89]\n"))
    assert cfg.interpolators[0].feed_mm_per_s == 250.0 and isinstance(cfg.interpolators[0].feed_mm_per_s, float)


@pytest.mark.parametrize("points, match", [  # item 6
    ("[[0, 0], [1, 0, 0]]", r"points_mm\[1\] has 3 coordinates but points_mm\[0\] has 2"),
    ("[[0, 0, 0, 0], [1, 0, 0, 0]]", r"4 coordinates; expected 1 to 3"),
    ("[[0, 0]]", r"at least 2 points, got 1"),
    ("[[0, 0], [5, 0], [5, 0], [5, 5]]", r"points_mm\[2\] repeats points_mm\[1\]"),
    ("[[0, 0], [nan, 0]]", r"'path.points_mm\[1\]\[0\]': .*finite number"),
    ("[[0, 0], [true, 1]]", r"'path.points_mm\[1\]\[0\]': .*bool is not a number"),
    ("[]", r"at least 2 points, got 0"),
    ("[[0, 0], [1e300, 0]]", r"points_mm\[1\] has a coordinate 1e\+300 beyond \+-1e\+06 mm"),
])
def test_points_are_validated_at_load(tmp_path, points, match):
    f = write(tmp_path, BASE + f"[path]\npoints_mm = {points}\n")
    with pytest.raises(ConfigError, match=match) as e:
        load_config(f)
    assert str(f) in str(e.value) and "path.points_mm" in str(e.value)


@pytest.mark.parametrize("name", ["..", ".", "../x", "a/b", ".hidden", "", "x" * 65, "a b"])
def test_unsafe_names_are_refused(tmp_path, name):  # item 7
    f = write(tmp_path, f'name = "{name}"\nreproduces = "-"\n' + PATH)
    with pytest.raises(ConfigError, match=r"key 'name': String should match pattern") as e:
        load_config(f)
    assert str(f) in str(e.value)


def test_dotdot_name_writes_nothing_outside_the_cache(tmp_path):  # item 7, what went wrong
    f = write(tmp_path, 'name = ".."\nreproduces = "-"\n' + PATH + "[output]\nfigure = false\n")
    with pytest.raises(ConfigError):
        run_experiment(f, cache_dir=tmp_path / "cache", log=lambda s: None)
    assert not (tmp_path / "results.json").exists() and not (tmp_path / "cache").exists()


def test_metrics_string_gets_an_array_hint_not_a_number_hint(tmp_path):  # item 17
    f = write(tmp_path, BASE + 'metrics = "cycle_time"\n' + PATH)
    with pytest.raises(ConfigError, match=r"key 'metrics': Input should be a valid list; give an array") as e:
        load_config(f)
    assert "plain number" not in str(e.value)


def test_non_utf8_config_and_bad_file_names(tmp_path):
    f = tmp_path / "e.toml"
    f.write_bytes(BASE.encode() + b'description = "caf\xe9"\n' + PATH.encode())
    with pytest.raises(ConfigError, match=r"line 3: not UTF-8"):
        load_config(f)
    f = write(tmp_path, BASE + '[path]\ngcode = "a\\u0000b.nc"\n')
    with pytest.raises(ConfigError, match=r"key 'path.gcode': "):
        load_config(f)


def test_int_range_sweep_of_an_int_field_stays_int(tmp_path):
    from research.experiments.sweep_points import expand

    f = write(tmp_path, BASE + '[identification]\n[sweep.parameters]\n"identification.n_moves" = {start = 10, stop = 30, num = 3}\n')
    cfg, _ = load_config(f)
    points = expand(cfg, f)
    assert [p.config.identification.n_moves for p in points] == [10, 20, 30]


def test_time_optimal_on_a_gcode_program_takes_its_feed(tmp_path, caplog):
    """The time-optimal reference on a G-code path without ``feed_mm_per_s`` is bounded by the
    program's F (1200 mm/min = 20 mm/s here: its peak path speed stays at 20 mm/s to the OCP's check
    tolerance, where the field's default would allow 250), as the FIR stage runs the program's
    feeds; with feeds that differ it takes the largest and says so in a warning; a written
    ``feed_mm_per_s`` still wins."""
    (tmp_path / "part.nc").write_text("G21 G90\nG1 X10 F1200\nG1 X10 Y10\n")
    text = ('name = "t"\nreproduces = "test"\n[path]\ngcode = "part.nc"\n[interpolator]\nkind = "time_optimal"\n'
            'tolerance_um = 100.0\nintervals_per_segment = 8\n[output]\nfigure = false\n')
    res = run_experiment(write(tmp_path, text), cache_dir=tmp_path / "c", figures_dir=tmp_path / "f", log=lambda s: None)
    assert res.record["details"]["time_optimal"]["feed_mm_per_s"] == 20.0
    assert res.record["scalars"]["peak_feed"] <= 20.0 * 1.01
    (tmp_path / "two.nc").write_text("G21 G90\nG1 X10 F1200\nG1 X10 Y10 F600\n")
    with caplog.at_level("WARNING"):
        res = run_experiment(write(tmp_path, text.replace("part.nc", "two.nc"), "b.toml"), cache_dir=tmp_path / "c",
                             figures_dir=tmp_path / "f", log=lambda s: None)
    assert res.record["details"]["time_optimal"]["feed_mm_per_s"] == 20.0
    assert any("from 10 to 20 mm/s" in r.getMessage() for r in caplog.records), caplog.text
    res = run_experiment(write(tmp_path, text.replace("[interpolator]\n", "[interpolator]\nfeed_mm_per_s = 40.0\n"),
                               "c.toml"), cache_dir=tmp_path / "c", figures_dir=tmp_path / "f", log=lambda s: None)
    assert res.record["details"]["time_optimal"]["feed_mm_per_s"] == 40.0
    assert res.record["scalars"]["peak_feed"] > 20.0 * 1.01


def test_whole_path_time_optimal_nlp_on_a_long_program_is_warned_of(monkeypatch, caplog):
    """A time-optimal reference without ``window`` on a program of ``_WHOLE_NLP_WARN`` segments or more
    logs a warning that names the NLP's size and the ``window`` key (here the threshold is lowered
    to the 2 segments of corner90 so that the solve stays small); below it, no warning."""
    from research.experiments import stages
    from research.experiments.config import validate
    from research.paths import named_path

    ic = validate({"name": "t", "reproduces": "-", "path": {"name": "corner90"},
                   "interpolator": {"kind": "time_optimal", "intervals_per_segment": 8}}, "t.toml").interpolators[0]
    path = named_path("corner90")
    with caplog.at_level("WARNING"):
        stages.interpolate(ic, path, None)
    assert not any("one NLP" in r.getMessage() for r in caplog.records)
    monkeypatch.setattr(stages, "_WHOLE_NLP_WARN", 2)
    with caplog.at_level("WARNING"):
        stages.interpolate(ic, path, None)
    assert any("over all 2 segments is one NLP of 16 intervals" in r.getMessage() and "window" in r.getMessage()
               for r in caplog.records), caplog.text
