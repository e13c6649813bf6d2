"""The command line: the README's main job and figure regeneration (fast mode)."""

import json
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


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


def test_figures_fast_writes_manifest(tmp_path):
    from research.cli import main

    assert main(["figures", "--fast", "--out", str(tmp_path)]) == 0
    manifest = json.loads((tmp_path / "manifest.json").read_text())
    assert {m["name"] for m in manifest} >= {"sencer2015_fig3_fir_spectrum", "sencer2015_fig4_fir_cornering"}
    for m in manifest:
        for f in m["files"]:
            assert (tmp_path / f).stat().st_size > 10_000


def test_errors_exit_2_with_message(tmp_path, capsys):
    from research.cli import main

    bad = tmp_path / "bad.toml"
    bad.write_text('name = "x"\nreproduces = "y"\n[path]\nname = "diamond"\n[interpolator]\nfeed = 3\n')
    assert main(["run", str(bad)]) == 2
    assert "key 'interpolator.feed': unknown key" in capsys.readouterr().err
    assert main(["figures", "--only", "nope"]) == 2
