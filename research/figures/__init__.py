"""Regenerated paper figures: one module per figure, each with ``NAME``, ``REPRODUCES``, ``CONFIG`` (an
experiment config under ``experiments/figures/``, with the paper numbers it reproduces) and
``plot(record, arrays) -> Figure``: :func:`render` runs the config through the results store (an unchanged
config and code is not recomputed) and draws the stored result; the module computes nothing itself.

``python -m research figures`` renders them all.

:func:`catalog` reads ``NAME``, ``REPRODUCES`` and ``CONFIG`` from the modules' source (literal
assignments, no import), so listing the figures costs milliseconds; :func:`registry` and
:func:`figure_module` import them."""

from __future__ import annotations

import ast
import importlib
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

#: registered figure modules, in the order they are regenerated
FIGURE_MODULES = (
    "research.figures.fir_spectrum",
    "research.figures.fir_cornering",
    "research.figures.sencer2015_fig6",
    "research.figures.drive_bode",
    "research.figures.dimarco2015_fig3",
    "research.figures.dimarco2015_mtp",
    "research.figures.prevost2012_fig5",
    "research.figures.prevost2012_fig6",
    "research.figures.contour_sencer2009_fig4_6",
    "research.figures.identification_ch6",
    "research.figures.sencer2009_fig3_11",
    "research.figures.vibration_calibration",
    "research.figures.sencer2009_fig5_7",
    "research.figures.sencer2009_fig5_9",
    "research.figures.sencer2009_fig5_10",
    "research.figures.sencer2009_fig5_feedforward",
    "research.figures.sencer2009_fig6_13",
    "research.figures.sencer2009_fig3_13",
    "research.figures.optimality",
)


def registry() -> dict[str, ModuleType]:
    """``{NAME: module}`` of every registered figure."""
    modules = [importlib.import_module(m) for m in FIGURE_MODULES]
    return {m.NAME: m for m in modules}


@dataclass(frozen=True)
class FigureEntry:
    """A registered figure as its module's source states it (nothing imported).

    Attributes:
        name: ``NAME``; module: the dotted module name; reproduces: ``REPRODUCES``;
        config: ``CONFIG``, the experiment config it is made from (relative to :data:`ROOT`).
    """

    name: str
    module: str
    reproduces: str
    config: str


def catalog() -> dict[str, FigureEntry]:
    """``{NAME: FigureEntry}`` of every registered figure, in order, read from the module files' literal
    ``NAME`` / ``REPRODUCES`` / ``CONFIG`` assignments (no module, and so no jax, is imported).

    Raises:
        ResearchError: a registered module is missing, or does not assign ``NAME``, ``REPRODUCES`` and
            ``CONFIG`` as literal strings (the registry could not list it without importing it).
    """
    from research.errors import ResearchError

    here = Path(__file__).resolve().parent
    out = {}
    for dotted in FIGURE_MODULES:
        file = here / (dotted.rsplit(".", 1)[1] + ".py")
        try:
            tree = ast.parse(file.read_text(encoding="utf-8"), filename=str(file))
        except (OSError, SyntaxError) as e:
            raise ResearchError(f"{file}: registered figure module {dotted!r} cannot be read ({e})") from None
        found = {}
        for node in tree.body:
            if (isinstance(node, ast.Assign) and len(node.targets) == 1 and isinstance(node.targets[0], ast.Name)
                    and node.targets[0].id in ("NAME", "REPRODUCES", "CONFIG")):
                try:
                    found[node.targets[0].id] = ast.literal_eval(node.value)
                except ValueError:
                    raise ResearchError(f"{file}: line {node.lineno}: {node.targets[0].id} must be a literal string "
                                        "(the figure registry reads it without importing the module)") from None
        if not all(isinstance(found.get(k), str) for k in ("NAME", "REPRODUCES", "CONFIG")):
            raise ResearchError(f"{file}: a registered figure module needs literal NAME, REPRODUCES and CONFIG "
                                f"strings, found {sorted(found)}")
        out[found["NAME"]] = FigureEntry(found["NAME"], dotted, found["REPRODUCES"], found["CONFIG"])
    return out


#: the repository root: ``CONFIG`` paths are relative to it
ROOT = Path(__file__).resolve().parents[2]


@dataclass(frozen=True)
class Rendered:
    """What :func:`render` produced: the files written and the config's run result."""

    files: list[Path]
    run: object


def render(name: str, out_dir: Path, *, cache_dir: Path | None = None,
           results_dir: Path | None = None, log=None) -> Rendered:
    """Write the registered figure ``name`` to ``out_dir/<name>.png``.

    A config figure runs its ``CONFIG`` through :func:`research.experiments.run_experiment` (store under
    ``cache_dir``, readable results under ``results_dir``) and plots the stored record and arrays.

    Raises:
        ResearchError: unknown name; ConfigError from the config.
    """
    from research.experiments.plot_style import save
    from research.experiments.runner import DEFAULT_CACHE, DEFAULT_RESULTS, run_experiment

    module = figure_module(name)
    run = run_experiment(ROOT / module.CONFIG, cache_dir=DEFAULT_CACHE if cache_dir is None else cache_dir,
                         results_dir=DEFAULT_RESULTS if results_dir is None else results_dir,
                         log=log or (lambda s: None))
    out = Path(out_dir) / f"{name}.png"
    save(module.plot(run.record, run.arrays()), out)
    return Rendered([out], run)


def figure_module(name: str) -> ModuleType:
    """Import the module of the registered figure ``name`` (a key of :func:`catalog`).

    Raises:
        ResearchError: no figure of that name is registered.
    """
    from research.errors import ResearchError

    entries = catalog()
    if name not in entries:
        raise ResearchError(f"unknown figure {name!r}; registered: {sorted(entries)}")
    return importlib.import_module(entries[name].module)
