"""The command line: the README's main job, sweeps, and figure regeneration.

The manifest smoke test runs two light figures through the CLI; every registered figure's numbers are
checked from its stored result in tests/figures/test_paper_numbers.py.
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from research.figures import registry

REPO = Path(__file__).resolve().parents[1]
LIGHT = ["sencer2015_fig3_fir_spectrum", "dimarco2015_fig3_sigmoid_startup"]


def test_run_default_experiment(tmp_path):
    """README command 1 (without the install): runs, prints the summary table, writes outputs."""
    out = subprocess.run(
        [sys.executable, "-m", "research", "run", str(REPO / "experiments" / "sencer2015_diamond.toml"),
         "--cache", str(tmp_path / "cache"), "--figures", str(tmp_path / "figs")],
        capture_output=True, text=True, check=True, cwd=tmp_path,
    ).stdout
    assert "max corner error [um]          500.000" in out
    # the visible results folder (issue 16 item 4), named in the summary line, in the working folder
    folder = tmp_path / "results" / "sencer2015_diamond"
    assert "results: results/sencer2015_diamond/" in out and "[3/3] results in results/sencer2015_diamond/" in out
    record = json.loads((folder / "results.json").read_text())
    assert record["scalars"]["max_corner_error"] == pytest.approx(0.5, rel=1e-9)  # eq 14: corner error = eps
    assert (folder / "config.toml").read_bytes() == (REPO / "experiments" / "sencer2015_diamond.toml").read_bytes()
    assert (folder / "figure.png").read_bytes() == (tmp_path / "figs" / "sencer2015_diamond.png").read_bytes()
    assert "trajectory.npz" in {f.name for f in folder.iterdir()}
    report = (folder / "report.md").read_text()
    assert "![figure](figure.png)" in report and "max corner error [um]          500.000" in report
    assert not (tmp_path / "cache" / "sencer2015_diamond").exists()  # the cache holds only the store


def test_run_on_a_gcode_program_says_what_to_write(tmp_path, capsys):
    """``run part.nc`` (a program where a config is expected) is one error line naming the file and
    the config keys to write, exit status 2."""
    from research.cli import main

    (tmp_path / "part.nc").write_text("G1 X10 F600\n")
    assert main(["run", str(tmp_path / "part.nc")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "part.nc: a G-code program, not an experiment config" in err
    assert 'gcode = "part.nc"' in err and "experiments/cam_part_arc.toml" in err


def test_run_twice_is_served_from_the_store(tmp_path, capsys):
    from research.cli import main

    cfg = tmp_path / "c.toml"
    cfg.write_text('name = "c"\nreproduces = "-"\n[path]\nname = "corner90"\n[output]\nfigure = false\n')
    args = ["run", str(cfg), "--cache", str(tmp_path / "cache"), "--results", str(tmp_path / "results")]
    assert main(args) == 0 and "computing" in capsys.readouterr().out
    assert main(args) == 0 and "(cached)" in capsys.readouterr().out


def test_summary_counts_the_programs_blocks_not_its_chords(tmp_path, capsys):
    """The summary of a G-code run counts the program's blocks and arcs, computed and from the store:
    by hand, the program below has 5 blocks (G0 Z1, G1 Z0, G1 X10, the G2 half circle of R 5 about
    (15, 0), G1 X30) of which 1 arc; its polyline view has 4 + 79 chords (the arc cut at 1 um:
    ceil(pi / (4 asin(sqrt(0.001 / 10)))) = 79), which the row must not show. A named polyline keeps
    "segments / corners" (corner90: 2 segments, 1 corner)."""
    import math
    import re

    from research.cli import main

    assert math.ceil(math.pi / (4 * math.asin(math.sqrt(0.001 / 10)))) == 79
    (tmp_path / "part.nc").write_text("G21 G90 G17\nG0 Z1\nG1 Z0 F600\nG1 X10\nG2 X20 Y0 I5 J0\nG1 X30\nM30\n")
    cfg = tmp_path / "c.toml"
    cfg.write_text('name = "c"\nreproduces = "-"\n[path]\ngcode = "part.nc"\n[output]\nfigure = false\n')
    args = ["run", str(cfg), "--cache", str(tmp_path / "cache"), "--results", str(tmp_path / "results")]
    for served in ("computing", "(cached)"):
        assert main(args) == 0
        out = capsys.readouterr().out
        assert served in out
        summary = out[out.index("\nexperiment "):]
        assert re.search(r"^blocks / arcs +5 / 1$", summary, re.M), out
        assert "segments / corners" not in summary and "83 / 82" not in summary  # the chords, as before
        assert ("interpolator fir: 5 blocks, 1 arc(s), 83 chords" in out) == (served == "computing")
    record = json.loads((tmp_path / "results" / "c" / "results.json").read_text())
    assert len(record["details"]["fir"]["turning_angle_deg"]) == 82  # the chords are still what the metrics use
    cfg.write_text('name = "d"\nreproduces = "-"\n[path]\nname = "corner90"\n[output]\nfigure = false\n')
    assert main(args) == 0
    assert re.search(r"^segments / corners +2 / 1$", capsys.readouterr().out, re.M)


def test_sweep_command(tmp_path, capsys):
    from research.cli import main

    cfg = tmp_path / "s.toml"
    cfg.write_text('name = "s"\nreproduces = "-"\n[path]\nname = "diamond"\n[sweep]\n[sweep.parameters]\n'
                   '"interpolator.tolerance_um" = [100.0, 200.0, 400.0]\n')
    assert main(["sweep", str(cfg), "--cache", str(tmp_path / "c"), "--figures", str(tmp_path / "f"), "--no-progress",
                 "--results", str(tmp_path / "r")]) == 0
    out = capsys.readouterr().out
    assert "3 points, 3 ok, 0 failed" in out and "d_cycle_time/d_T1" in out
    assert (tmp_path / "f" / "s.png").stat().st_size > 10_000
    folder = tmp_path / "r" / "s"  # the visible results folder, named in the last line
    assert f"results: {folder}/" in out
    assert (folder / "figure.png").read_bytes() == (tmp_path / "f" / "s.png").read_bytes()
    assert (folder / "config.toml").read_bytes() == cfg.read_bytes() and (folder / "table.npz").exists()
    table = json.loads((folder / "table.json").read_text())
    assert [r["max_corner_error"] for r in table["rows"]] == pytest.approx([0.1, 0.2, 0.4], rel=1e-6)  # eq 14: = eps
    assert "![figure](figure.png)" in (folder / "report.md").read_text()


def test_figures_list_is_fast_and_imports_no_figure_module():
    """Issue 16: ``figures --list`` took 2 min (it imported every figure module); target < 2 s. It reads the
    registry from the modules' source: no figure module and no jax is imported, and it lists exactly the
    names and descriptions the modules themselves carry."""
    code = ("import sys, time; t = time.perf_counter(); from research.cli import main; main(['figures', '--list']); "
            "print('SECONDS', time.perf_counter() - t); "
            "print('HEAVY', sorted(m for m in sys.modules if m == 'jax' or m.startswith(('research.figures.', 'matplotlib'))))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=REPO).stdout
    seconds = float(out.split("SECONDS ")[1].split()[0])
    assert seconds < 2.0, out
    assert "HEAVY []" in out, out
    listed = [line.split(": ", 1) for line in out.splitlines() if not line.startswith(("SECONDS", "HEAVY"))]
    modules = registry()
    assert [n for n, _ in listed] == list(modules)
    for name, text in listed:
        assert text.startswith(modules[name].REPRODUCES)


def test_figures_writes_manifest(tmp_path, capsys):
    from research.cli import main

    store = ["--cache", str(tmp_path / "c"), "--results", str(tmp_path / "r")]  # config figures: stores in tmp_path
    assert main(["figures", "--out", str(tmp_path)] + store + [a for n in LIGHT for a in ("--only", n)]) == 0
    out = capsys.readouterr().out.splitlines()
    lines = [ln for ln in out if ln.startswith("[")]  # a line as each figure starts, then one as it finishes
    paper = [ln for ln in out if ln.strip().startswith("paper: ")]  # the config figure's checks (fig 3: eq 8-10)
    assert paper and all(ln.endswith("PASS") for ln in paper)
    assert [ln.split(": ")[1].split(" ")[0] for ln in lines] == ["started", "done"] * len(LIGHT)
    assert lines[0].startswith(f"[1/2] {LIGHT[0]}: started") and lines[3].startswith(f"[2/2] {LIGHT[1]}: done in")
    manifest = json.loads((tmp_path / "manifest.json").read_text())
    assert [m["name"] for m in manifest] == LIGHT
    for m in manifest:
        assert m["reproduces"] and m["config"]
        for f in m["files"]:
            assert (tmp_path / f).stat().st_size > 10_000


def test_errors_exit_2_with_message(tmp_path, capsys):
    from research.cli import main

    bad = tmp_path / "bad.toml"
    bad.write_text('name = "x"\nreproduces = "y"\n[path]\nname = "diamond"\n[interpolator]\nfeed = 3\n')
    assert main(["run", str(bad)]) == 2
    assert "key 'interpolator.feed': unknown key" in capsys.readouterr().err
    assert main(["figures", "--only", "nope"]) == 2
    assert main(["sweep", str(bad)]) == 2


def test_os_error_is_one_line_and_debug_shows_the_traceback(tmp_path, capsys):
    """An OSError (here: the output folder is a file) prints one line naming the path, exit 2; --debug adds
    the traceback."""
    from research.cli import main

    blocker = tmp_path / "not_a_folder"
    blocker.write_text("x")
    store = ["--cache", str(tmp_path / "c"), "--results", str(tmp_path / "r")]
    assert main(["figures", "--out", str(blocker), "--only", LIGHT[0]] + store) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("error: ") and str(blocker) in err and "Traceback" not in err
    assert main(["--debug", "figures", "--out", str(blocker), "--only", LIGHT[0]] + store) == 2
    err = capsys.readouterr().err
    assert "Traceback" in err and err.strip().splitlines()[-1].startswith("error: ")


def test_unwritable_cache_is_a_clear_store_error(tmp_path, capsys):
    from research.cli import main

    cfg = tmp_path / "c.toml"
    cfg.write_text('name = "c"\nreproduces = "-"\n[path]\nname = "corner90"\n[output]\nfigure = false\n')
    (tmp_path / "cache").write_text("a file where the results root should be")
    assert main(["run", str(cfg), "--cache", str(tmp_path / "cache"), "--results", str(tmp_path / "results")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "cannot write" in err and str(tmp_path / "cache") in err


def test_store_verify_and_gc_commands(tmp_path, capsys):
    from research.cli import main
    from research.experiments import ResultStore, result_key

    store = ResultStore(tmp_path / "cache" / "store")
    good, bad = result_key({"k": 1}), result_key({"k": 2})
    store.put(good, {"v": 1})
    store.put(bad, {"v": 2}, {"a": [1.0, 2.0]})
    (store.folder(bad) / "arrays.npz").write_bytes(b"PK")
    args = ["--cache", str(tmp_path / "cache")]
    assert main(["store", "verify", *args]) == 1
    out = capsys.readouterr().out
    assert f"BAD {store.folder(bad)}: arrays.npz has 2 bytes" in out and "1 valid entries, 1 problems" in out
    assert main(["store", "gc", "--dry-run", *args]) == 0 and store.folder(bad).exists()
    assert "would remove" in capsys.readouterr().out
    assert main(["store", "gc", *args]) == 0 and not store.folder(bad).exists()
    assert main(["store", "verify", *args]) == 0 and "1 valid entries, 0 problems" in capsys.readouterr().out


def test_cached_run_does_not_import_jax(tmp_path):
    """A ``run`` served from the store reads its record and writes the views: it imports neither the
    evaluation nor JAX (issue 16: the cached re-run the README calls instant took 10 s importing them)."""
    config = tmp_path / "e.toml"
    config.write_text('name = "e"\nreproduces = "-"\n[path]\nname = "corner90"\n[output]\nfigure = false\n')
    args = ["run", str(config), "--cache", str(tmp_path / "c"), "--results", str(tmp_path / "r")]
    code = ("import sys; from research.cli import main; main(%r); "
            "print('loaded:', sorted(m for m in ('jax', 'research.experiments.evaluate') if m in sys.modules))")
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    from research.experiments.runner import run_experiment

    first = run_experiment(config, cache_dir=tmp_path / "c", results_dir=tmp_path / "r", log=lambda s: None)
    assert not first.cached
    again = subprocess.run([sys.executable, "-c", code % args], capture_output=True, text=True, check=True, cwd=tmp_path, env=env).stdout
    assert "found in the store" in again and "(cached)" in again and "loaded: []" in again


def test_every_option_states_its_default_and_unit():
    """``--help`` of every subcommand (issue: units and defaults): an option with a default says which, and a
    float option names its unit in brackets (every float option is a physical quantity)."""
    import argparse

    from research.cli import build_parser

    def parsers(p, name="python -m research"):
        yield name, p
        for action in p._actions:
            if isinstance(action, argparse._SubParsersAction):
                for sub_name, sub in action.choices.items():
                    yield from parsers(sub, f"{name} {sub_name}")

    missing = []
    for name, p in parsers(build_parser()):
        for action in p._actions:
            if not action.option_strings or isinstance(action, (argparse._HelpAction, argparse._StoreTrueAction)):
                continue
            text = action.help or ""
            if action.default is not None and "default" not in text:
                missing.append(f"{name} {action.option_strings[0]}: default {action.default!r} not stated")
            if action.type is float and "[" not in text:
                missing.append(f"{name} {action.option_strings[0]}: no [unit]")
    assert not missing, missing
