"""The command line: the README's main job, sweeps, and figure regeneration (fast mode).

The manifest smoke test runs two light figures through the CLI; every registered figure's fast mode
is covered by its own test (so pytest-xdist spreads them), each under its module's ``fast`` path.
"""

import json
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
    assert (tmp_path / "cache" / "sencer2015_diamond" / "results.json").exists()
    assert (tmp_path / "figs" / "sencer2015_diamond.png").exists()


def test_run_twice_is_served_from_the_store(tmp_path, capsys):
    from research.cli import main

    cfg = tmp_path / "c.toml"
    cfg.write_text('name = "c"\nreproduces = "-"\n[path]\nname = "corner90"\n[output]\nfigure = false\n')
    args = ["run", str(cfg), "--cache", str(tmp_path / "cache")]
    assert main(args) == 0 and "computing" in capsys.readouterr().out
    assert main(args) == 0 and "(cached)" in capsys.readouterr().out


def test_sweep_command(tmp_path, capsys):
    from research.cli import main

    cfg = tmp_path / "s.toml"
    cfg.write_text('name = "s"\nreproduces = "-"\n[path]\nname = "diamond"\n[sweep]\n[sweep.parameters]\n'
                   '"interpolator.tolerance_um" = [100.0, 200.0, 400.0]\n')
    assert main(["sweep", str(cfg), "--cache", str(tmp_path / "c"), "--figures", str(tmp_path / "f"), "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert "3 points, 3 ok, 0 failed" in out and "d_cycle_time/d_T1" in out
    assert (tmp_path / "f" / "s.png").stat().st_size > 10_000
    assert (tmp_path / "c" / "sweeps" / "s" / "table.npz").exists()


def test_figures_fast_writes_manifest(tmp_path):
    from research.cli import main

    assert main(["figures", "--fast", "--out", str(tmp_path)] + [a for n in LIGHT for a in ("--only", n)]) == 0
    manifest = json.loads((tmp_path / "manifest.json").read_text())
    assert [m["name"] for m in manifest] == LIGHT
    for m in manifest:
        assert m["reproduces"] and m["config"] and m["fast"]
        for f in m["files"]:
            assert (tmp_path / f).stat().st_size > 10_000


@pytest.mark.parametrize("name", [n for n in registry() if n not in LIGHT])
def test_each_figure_fast(tmp_path, name):
    module = registry()[name]
    assert module.REPRODUCES
    files = module.make_figure(tmp_path, fast=True)
    assert files and all(Path(f).stat().st_size > 10_000 for f in files)


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
    assert main(["figures", "--fast", "--out", str(blocker), "--only", LIGHT[0]]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("error: ") and str(blocker) in err and "Traceback" not in err
    assert main(["--debug", "figures", "--fast", "--out", str(blocker), "--only", LIGHT[0]]) == 2
    err = capsys.readouterr().err
    assert "Traceback" in err and err.strip().splitlines()[-1].startswith("error: ")


def test_unwritable_cache_is_a_clear_store_error(tmp_path, capsys):
    from research.cli import main

    cfg = tmp_path / "c.toml"
    cfg.write_text('name = "c"\nreproduces = "-"\n[path]\nname = "corner90"\n[output]\nfigure = false\n')
    (tmp_path / "cache").write_text("a file where the results root should be")
    assert main(["run", str(cfg), "--cache", str(tmp_path / "cache")]) == 2
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
