"""Command line: ``python -m research run CONFIG`` and ``python -m research figures``."""

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

    figs = sub.add_parser("figures", help="regenerate the registered paper figures")
    figs.add_argument("--only", action="append", metavar="NAME", help="only this figure (repeatable)")
    figs.add_argument("--fast", action="store_true", help="coarser grids, for smoke tests")
    figs.add_argument("--out", type=Path, default=Path("paper_figures"), help="output folder (default paper_figures)")
    figs.add_argument("--list", action="store_true", help="list the registered figures and exit")

    args = parser.parse_args(argv)
    try:
        if args.command == "run":
            return _run(args)
        return _figures(args)
    except ResearchError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2


def _run(args) -> int:
    from research.experiments import format_summary, run_experiment

    result = run_experiment(args.config, cache_dir=args.cache, figures_dir=args.figures)
    print()
    print(format_summary(result))
    return 0


def _figures(args) -> int:
    from research.figures import registry

    figures = registry()
    if args.list:
        for name, module in figures.items():
            print(f"{name}: {module.REPRODUCES}")
        return 0
    names = args.only or list(figures)
    unknown = [n for n in names if n not in figures]
    if unknown:
        raise ResearchError(f"unknown figure(s) {unknown}; registered: {sorted(figures)}")
    args.out.mkdir(parents=True, exist_ok=True)
    manifest = []
    for i, name in enumerate(names, 1):
        start = time.perf_counter()
        files = figures[name].make_figure(args.out, fast=args.fast)
        print(f"[{i}/{len(names)}] {name} ({time.perf_counter() - start:.1f} s): " + ", ".join(str(f) for f in files))
        manifest.append({"name": name, "reproduces": figures[name].REPRODUCES, "files": [Path(f).name for f in files]})
    (args.out / "manifest.json").write_text(json.dumps(manifest, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
