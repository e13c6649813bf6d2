"""Export (issue 16 item 7): CSV with units in the header, a G-code stream that the package's own G-code
reader reads back as the sampled path with the sampled feeds, from a config and from the command line; and
a program's ``G64 P<tol>`` used as the cornering tolerance of its blocks."""

import numpy as np
import pytest

from research.errors import ParameterError
from research.experiments import run_experiment
from research.experiments.export import trajectory_csv, trajectory_gcode
from research.interpolators import fir_interpolate
from research.paths import named_path
from research.paths.gcode import parse_gcode


@pytest.fixture(scope="module")
def traj():
    return fir_interpolate(named_path("corner90"), 100.0, [0.02, 0.01], 0.05, 1e-3)


def test_csv_has_units_and_reads_back_exactly(traj, tmp_path):
    text = trajectory_csv(traj)
    header = text.splitlines()[0].split(",")
    assert header == ["t [s]", "q_x [mm]", "q_y [mm]", "v_x [mm/s]", "v_y [mm/s]", "a_x [mm/s^2]", "a_y [mm/s^2]",
                      "j_x [mm/s^3]", "j_y [mm/s^3]"]
    (tmp_path / "t.csv").write_text(text)
    table = np.loadtxt(tmp_path / "t.csv", delimiter=",", skiprows=1)
    assert np.array_equal(table[:, 0], np.asarray(traj.t)) and np.array_equal(table[:, 1:3], np.asarray(traj.q))
    assert np.array_equal(table[:, 7:9], np.asarray(traj.j))


def test_gcode_stream_reads_back_as_the_samples(traj):
    """Every moving sample is a vertex read back exactly; each G1's feed is its step over the time it covers
    (the sum of the block times is the trajectory's motion time); G64 P is read back as the tolerance."""
    text = trajectory_gcode(traj, tolerance_mm=0.002)
    q = np.asarray(traj.q)
    prog = parse_gcode(text, start=tuple(q[0]) + (0.0,))
    moving = np.flatnonzero(np.linalg.norm(np.diff(q, axis=0), axis=1) >= 1e-6) + 1
    assert np.array_equal(prog.polyline.points[1:, :2], q[moving])
    block_time = np.sum(prog.polyline.lengths / prog.feeds)
    t = np.asarray(traj.t)
    assert block_time == pytest.approx(t[moving[-1]] - t[moving[0] - 1], rel=1e-6)  # F rounded to 1e-4 mm/min
    assert np.all(prog.block_tolerance[~prog.block_rapid] == 0.002)
    assert "G61" in trajectory_gcode(traj) and "G64" not in trajectory_gcode(traj)


def test_gcode_refuses_rotary_axes():
    from research.trajectory import Trajectory

    tr = Trajectory.from_positions(np.arange(3) * 1e-3, np.zeros((3, 1)) + [[0.0], [1.0], [2.0]], ("a",))
    with pytest.raises(ParameterError, match=r"axes \('x', 'y', 'z'\); the trajectory has \['a'\]"):
        trajectory_gcode(tr)


def test_export_from_config_and_cli(tmp_path, capsys):
    from research.cli import main

    cfg = tmp_path / "e.toml"
    cfg.write_text('name = "e"\nreproduces = "-"\n[path]\nname = "corner90"\n[interpolator]\nfeed_mm_per_s = 100.0\n'
                   'delays_ms = [20.0, 10.0]\ntolerance_um = 50.0\n[output]\nfigure = false\nexport = ["csv", "gcode"]\n')
    res = run_experiment(cfg, cache_dir=tmp_path / "c", results_dir=tmp_path / "r", log=lambda s: None)
    folder = tmp_path / "r" / "e"
    assert trajectory_csv(res.trajectory()) == (folder / "fir.csv").read_text()
    assert trajectory_gcode(res.trajectory()) == (folder / "fir.ngc").read_text()
    assert main(["export", str(folder / "trajectory.npz"), "--csv", str(tmp_path / "x.csv"), "--gcode",
                 str(tmp_path / "x.ngc"), "--tolerance-um", "5"]) == 0
    assert (tmp_path / "x.csv").read_text() == (folder / "fir.csv").read_text()
    assert "G64 P0.005" in (tmp_path / "x.ngc").read_text()
    assert main(["export", str(folder / "trajectory.npz")]) == 2
    assert "give --csv FILE and/or --gcode FILE" in capsys.readouterr().err


def test_g64_tolerance_of_a_program_is_the_cornering_tolerance(tmp_path):
    """The config's tolerance_um (500 um) applies where the program gives none; under G64 P0.1 the corner is
    held to 100 um (eq 14: the corner error equals the tolerance when full overlap would exceed it)."""
    (tmp_path / "p.ngc").write_text("G21 G90\nG1 X50 F6000\nY50\nG64 P0.1\nX0\nY0\n")
    cfg = tmp_path / "g.toml"
    cfg.write_text('name = "g"\nreproduces = "-"\n[path]\ngcode = "p.ngc"\n[interpolator]\ndelays_ms = [148.0, 89.0]\n'
                   'tolerance_um = 500.0\n[output]\nfigure = false\n')
    res = run_experiment(cfg, cache_dir=tmp_path / "c", results_dir=tmp_path / "r", log=lambda s: None)
    corners = res.record["details"]["fir"]["corner_errors"]
    assert corners == pytest.approx([0.5, 0.1, 0.1], abs=1e-9)
