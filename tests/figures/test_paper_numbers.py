"""Issue 16 item 3: every figure made from a config declares the paper numbers it reproduces ([[paper]]:
value, tolerance, source line); one test per figure runs its config through the results store and checks
them from the stored result (the second run is served from the store, and that record is what is checked)."""

from pathlib import Path

import pytest

from research.experiments import load_config, run_experiment
from research.figures import ROOT, catalog

CONFIG_FIGURES = {name: e.config for name, e in catalog().items() if e.config}


def test_config_figures_declare_paper_numbers():
    assert CONFIG_FIGURES, "no registered figure is made from a config"
    for name, config in CONFIG_FIGURES.items():
        cfg, _ = load_config(ROOT / config)
        assert cfg.name == name and cfg.paper, f"{config}: needs name = {name!r} and [[paper]] numbers"
        assert all(p.source.strip() for p in cfg.paper)


@pytest.mark.parametrize("name", sorted(CONFIG_FIGURES))
def test_paper_numbers_from_the_stored_result(tmp_path, name):
    kwargs = dict(cache_dir=tmp_path / "cache", results_dir=tmp_path / "results", figures_dir=tmp_path / "figs",
                  log=lambda s: None)
    first = run_experiment(ROOT / CONFIG_FIGURES[name], **kwargs)
    stored = run_experiment(ROOT / CONFIG_FIGURES[name], **kwargs)
    assert not first.cached and stored.cached
    checks = stored.paper_checks()
    assert checks and [c.key for c in checks] == [p.key for p in stored.config.paper]
    bad = [c.line() for c in checks if not c.ok]
    assert not bad, "\n".join(bad)
    assert Path(stored.results_file).parent == tmp_path / "results" / name
