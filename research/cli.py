"""Command line: ``python -m research run CONFIG``, ``python -m research sweep CONFIG`` and
``python -m research figures``."""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from research.errors import ResearchError


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m research", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)

    run = sub.add_parser("run", help="run one experiment config (TOML) and save results + figure")
    run.add_argument("config", type=Path, help="experiment file, e.g. experiments/sencer2015_diamond.toml")
    run.add_argument("--cache", type=Path, default=Path(".cache/results"), help="results root (default .cache/results)")
    run.add_argument("--figures", type=Path, default=Path("paper_figures"), help="figure folder (default paper_figures)")
    run.add_argument("--force", action="store_true", help="recompute even when the store has the result")

    sw = sub.add_parser("sweep", help="run (or resume) the [sweep] of an experiment config")
    sw.add_argument("config", type=Path, help="experiment file with a [sweep] table, e.g. experiments/sensitivity_delays.toml")
    sw.add_argument("--cache", type=Path, default=Path(".cache/results"), help="results root (default .cache/results)")
    sw.add_argument("--figures", type=Path, default=Path("paper_figures"), help="figure folder (default paper_figures)")
    sw.add_argument("--engine", choices=("auto", "vmap", "dask", "serial"), help="override sweep.engine")
    sw.add_argument("--scheduler", metavar="ADDRESS", help="Dask scheduler (default: a LocalCluster)")
    sw.add_argument("--workers", type=int, help="LocalCluster worker processes (default: CPU count)")
    sw.add_argument("--retry-failed", action="store_true", help="recompute points stored as failures")
    sw.add_argument("--no-progress", action="store_true", help="no progress bar")

    figs = sub.add_parser("figures", help="regenerate the registered paper figures")
    figs.add_argument("--only", action="append", metavar="NAME", help="only this figure (repeatable)")
    figs.add_argument("--fast", action="store_true", help="coarser grids, for smoke tests")
    figs.add_argument("--out", type=Path, default=Path("paper_figures"), help="output folder (default paper_figures)")
    figs.add_argument("--list", action="store_true", help="list the registered figures and exit")

    args = parser.parse_args(argv)
    try:
        return {"run": _run, "sweep": _sweep, "figures": _figures}[args.command](args)
    except ResearchError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2


def _run(args) -> int:
    from research.experiments import format_summary, run_experiment

    result = run_experiment(args.config, cache_dir=args.cache, figures_dir=args.figures, force=args.force)
    print()
    print(format_summary(result))
    return 0


def _sweep(args) -> int:
    from research.experiments.sweep import format_sweep, run_sweep

    result = run_sweep(args.config, cache_dir=args.cache, figures_dir=args.figures, engine=args.engine,
                       scheduler=args.scheduler, workers=args.workers, retry_failed=args.retry_failed,
                       show_progress=not args.no_progress)
    print()
    print(format_sweep(result))
    return 0


def _figures(args) -> int:
    from research.figures import registry

    figures = registry()
    if args.list:
        for name, module in figures.items():
            print(f"{name}: {module.REPRODUCES}" + (f" [{module.CONFIG}]" if getattr(module, "CONFIG", None) else ""))
        return 0
    names = args.only or list(figures)
    unknown = [n for n in names if n not in figures]
    if unknown:
        raise ResearchError(f"unknown figure(s) {unknown}; registered: {sorted(figures)}")
    args.out.mkdir(parents=True, exist_ok=True)
    manifest = []
    for i, name in enumerate(names, 1):
        start = time.perf_counter()
        module = figures[name]
        files = module.make_figure(args.out, fast=args.fast)
        seconds = time.perf_counter() - start
        print(f"[{i}/{len(names)}] {name} ({seconds:.1f} s): " + ", ".join(str(f) for f in files))
        manifest.append({
            "name": name,
            "reproduces": module.REPRODUCES,
            # the experiment config the figure is made from (a module CONFIG), else its parameters' module
            "config": getattr(module, "CONFIG", None) or f"{module.__name__} (module constants)",
            "module": module.__name__,
            "files": [Path(f).name for f in files],
            "fast": bool(args.fast),
            "seconds": round(seconds, 2),
        })
    (args.out / "manifest.json").write_text(json.dumps(manifest, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
