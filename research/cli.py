"""Command line: ``python -m research run CONFIG``, ``python -m research sweep CONFIG``,
``python -m research figures`` and ``python -m research store verify|gc``.

Errors of the input or the file system (:class:`~research.errors.ResearchError`, any ``OSError``) print
one line ``error: ...`` and exit with status 2; ``--debug`` prints the traceback as well."""

from __future__ import annotations

import argparse
import json
import sys
import time
import traceback
from pathlib import Path

from research.errors import ResearchError


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m research", description=__doc__)
    parser.add_argument("--debug", action="store_true", help="print the traceback of an error")
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

    st = sub.add_parser("store", help="check or clean the results store")
    st_sub = st.add_subparsers(dest="action", required=True)
    for name, text in (("verify", "check every entry against its manifest of SHA-256 checksums (exit 1 if any is bad)"),
                       ("gc", "remove damaged entries and leftovers of interrupted writes")):
        a = st_sub.add_parser(name, help=text)
        a.add_argument("--cache", type=Path, default=Path(".cache/results"), help="results root (default .cache/results)")
        if name == "gc":
            a.add_argument("--stale-code", action="store_true", help="also remove entries of other code versions")
            a.add_argument("--dry-run", action="store_true", help="list what would be removed, remove nothing")

    args = parser.parse_args(argv)
    try:
        return {"run": _run, "sweep": _sweep, "figures": _figures, "store": _store}[args.command](args)
    except (ResearchError, OSError) as e:
        if args.debug:
            traceback.print_exc()
        print(f"error: {_one_line(e)}", file=sys.stderr)
        return 2


def _one_line(e: BaseException) -> str:
    """The message of ``e``; a plain ``OSError`` as ``<file>: <reason>`` (no traceback)."""
    if isinstance(e, OSError) and not isinstance(e, ResearchError):
        where = " -> ".join(str(f) for f in (e.filename, e.filename2) if f)
        text = f"{where}: {e.strerror or e}" if where else str(e) or type(e).__name__
        return f"{text} ({type(e).__name__}; --debug for the traceback)"
    return str(e)


def _store(args) -> int:
    from research.experiments.store import gc_store, verify_store

    root = args.cache / "store"
    if args.action == "verify":
        good, problems = verify_store(root)
        for p in problems:
            print(f"BAD {p.folder}: {p.reason}")
        print(f"{root}: {good} valid entries, {len(problems)} problems")
        return 1 if problems else 0
    problems, stale = gc_store(root, dry_run=args.dry_run, stale_code=args.stale_code)
    verb = "would remove" if args.dry_run else "removed"
    for p in problems:
        print(f"{verb} {p.folder}: {p.reason}")
    for f in stale:
        print(f"{verb} {f}: written by another code version")
    print(f"{root}: {verb} {len(problems)} damaged entries or leftovers, {len(stale)} stale entries")
    return 0


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
