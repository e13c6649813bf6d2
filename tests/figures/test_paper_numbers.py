"""Issue 16 item 3: every figure made from a config declares the paper numbers it reproduces ([[paper]]:
value, tolerance, source line); one test per figure runs its config through the results store and checks
them from the stored result (the second run is served from the store, and that record is what is checked)."""

from pathlib import Path

import pytest

from research.experiments import load_config, run_experiment
from research.figures import ROOT, catalog

CONFIG_FIGURES = {name: e.config for name, e in catalog().items()}  # every registered figure has one


def _absent_shared_data(config: str) -> str | None:
    """Why ``config`` cannot run here, when it reads third-party data under ``../shared/data`` (beside the
    checkout, as in CI; /work/shared/data/README.md) that this checkout lacks; else None."""
    from research.errors import ConfigError

    try:
        load_config(ROOT / config)
    except ConfigError as e:
        if "file not found" in str(e) and "/shared/data/" in str(e):
            return f"third-party data beside the checkout is absent: {e}"
        raise
    return None


def test_config_figures_declare_paper_numbers():
    assert CONFIG_FIGURES, "no registered figure is made from a config"
    for name, config in CONFIG_FIGURES.items():
        if _absent_shared_data(config):
            continue
        cfg, _ = load_config(ROOT / config)
        assert cfg.name == name and cfg.paper, f"{config}: needs name = {name!r} and [[paper]] numbers"
        assert all(p.source.strip() for p in cfg.paper)
        assert any(p.reproduced for p in cfg.paper), f"{config}: no [[paper]] number is reproduced"


@pytest.mark.parametrize("name", sorted(CONFIG_FIGURES))
def test_paper_numbers_from_the_stored_result(tmp_path, name):
    if reason := _absent_shared_data(CONFIG_FIGURES[name]):
        pytest.skip(reason)
    kwargs = dict(cache_dir=tmp_path / "cache", results_dir=tmp_path / "results", figures_dir=tmp_path / "figs",
                  log=lambda s: None)
    first = run_experiment(ROOT / CONFIG_FIGURES[name], **kwargs)
    stored = run_experiment(ROOT / CONFIG_FIGURES[name], **kwargs)
    assert not first.cached and stored.cached
    checks = stored.paper_checks()
    assert checks and [c.key for c in checks] == [p.key for p in stored.config.paper]
    bad = [c.line() for c in checks if not c.holds]  # reproduced: agrees; declared not reproduced: still a miss
    assert not bad, "\n".join(bad)
    assert Path(stored.results_file).parent == tmp_path / "results" / name


def test_figures_command_runs_a_config_figure_through_the_store(tmp_path, capsys):
    """``figures`` on a config figure: computed once, then served from the store (unchanged config and code),
    the paper checks printed and written to the manifest, the readable results under --results."""
    import json

    from research.cli import main

    name = "sencer2009_fig6_7_drive_bode"
    args = ["figures", "--only", name, "--out", str(tmp_path / "f"), "--cache", str(tmp_path / "c"),
            "--results", str(tmp_path / "r")]
    assert main(args) == 0
    first = capsys.readouterr().out
    assert main(args) == 0
    again = capsys.readouterr().out
    assert "(from the store)" not in first and "(from the store)" in again
    assert again.count("paper: ") == 2 and "MISS" not in again
    manifest = json.loads((tmp_path / "f" / "manifest.json").read_text())
    assert manifest[0]["config"] == CONFIG_FIGURES[name] and all(c["ok"] for c in manifest[0]["paper"])
    assert (tmp_path / "f" / f"{name}.png").exists() and (tmp_path / "r" / name / "arrays.npz").exists()


def test_a_number_declared_not_reproduced_is_reported_with_its_reason():
    """``reproduced = false`` needs a reason; its check reports the difference and is asserted as a miss (a number
    that starts to agree is flagged, so the declaration cannot go stale); a reason without ``reproduced = false``
    is refused."""
    from research.errors import ConfigError
    from research.experiments.config import validate
    from research.experiments.paper_numbers import check_paper_numbers

    base = {"name": "t", "reproduces": "-", "path": {"name": "corner90"}}
    paper = {"key": "cycle_time", "value": 1.0, "tolerance": 0.1, "source": "p. 1", "reproduced": False}
    with pytest.raises(ConfigError, match=r"reproduced = false needs a reason"):
        validate(base | {"paper": [paper]}, "t.toml")
    with pytest.raises(ConfigError, match=r"reproduced = false needs a reason"):
        validate(base | {"paper": [paper | {"reproduced": True, "reason": "x"}]}, "t.toml")
    cfg = validate(base | {"paper": [paper | {"reason": "stand-in drive"}]}, "t.toml")
    miss, agrees = (check_paper_numbers(cfg, {"scalars": {"cycle_time": v}})[0] for v in (2.0, 1.05))
    assert miss.holds and miss.verdict == "NOT REPRODUCED (stand-in drive)"
    assert not agrees.holds and agrees.verdict.startswith("MISS")
