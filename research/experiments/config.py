"""Experiment configs: TOML files validated by a schema (pydantic).

Units are in the key names (``feed_mm_per_s``, ``delays_ms``, ``tolerance_um``) and converted to
the package's mm / s on entry. Unknown keys (typos), wrong types and out-of-range values raise
:class:`~research.errors.ConfigError` naming the file and the key.

Example (``experiments/sencer2015_diamond.toml``)::

    name = "sencer2015_diamond"
    reproduces = "Sencer 2015 §4 / Fig 6: diamond path, F = 250 mm/s, eps = 500 um"

    [path]
    name = "diamond"

    [interpolator]
    kind = "fir"
    feed_mm_per_s = 250.0
    delays_ms = [148.0, 89.0]
    tolerance_um = 500.0
"""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Literal

import numpy as np

from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from research.errors import ConfigError
from research.paths import PATHS, Polyline, named_path


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class PathConfig(_Strict):
    """The tool path: exactly one of a named benchmark path, a G-code file or explicit points."""

    name: str | None = Field(None, description=f"named path, one of {sorted(PATHS)}")
    gcode: str | None = Field(None, description="G-code file, relative to the config file")
    points_mm: list[list[float]] | None = Field(None, description="polyline vertices [mm]")
    chord_tolerance_um: float = Field(1.0, gt=0, description="arc-to-chord tolerance for G2/G3 [um]")

    @model_validator(mode="after")
    def _exactly_one(self):
        given = [k for k in ("name", "gcode", "points_mm") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError(f"give exactly one of name, gcode, points_mm (got {given or 'none'})")
        if self.name is not None and self.name not in PATHS:
            raise ValueError(f"unknown path name {self.name!r}; expected one of {sorted(PATHS)}")
        return self


class FIRConfig(_Strict):
    """Sencer 2015 FIR-overlap interpolator settings (defaults: the paper's §4 experiment)."""

    kind: Literal["fir"] = "fir"
    feed_mm_per_s: float = Field(250.0, gt=0, description="commanded feed F [mm/s]")
    delays_ms: list[float] = Field([148.0, 89.0], min_length=1, description="FIR delays T_i [ms]")
    tolerance_um: float = Field(500.0, ge=0, description="cornering tolerance epsilon [um]")
    sample_period_ms: float = Field(1.0, gt=0, description="interpolation period Ts [ms]")
    refine: bool = Field(True, description="short-segment rule (verified overlap)")

    @model_validator(mode="after")
    def _positive_delays(self):
        bad = [i for i, d in enumerate(self.delays_ms) if not d > 0]
        if bad:
            raise ValueError(f"delays_ms[{bad[0]}] must be > 0 ms, got {self.delays_ms[bad[0]]}")
        return self


class OutputConfig(_Strict):
    figure: bool = Field(True, description="write a figure to paper_figures/")


class ExperimentConfig(_Strict):
    """One study: a path, an interpolator, what it reproduces, and what to write."""

    name: str = Field(..., pattern=r"^[A-Za-z0-9_.-]+$", description="results and figure file stem")
    reproduces: str = Field(..., description="the paper result this experiment reproduces")
    description: str = ""
    path: PathConfig
    interpolator: FIRConfig = FIRConfig()
    output: OutputConfig = OutputConfig()


def load_config(file: str | Path) -> tuple[ExperimentConfig, Path]:
    """Read and validate a TOML experiment file.

    Returns:
        ``(config, directory of the file)`` (relative paths in the config are resolved from it).

    Raises:
        ConfigError: missing file, TOML syntax error, unknown key, wrong type or value.
    """
    file = Path(file)
    try:
        text = file.read_text()
    except OSError as e:
        raise ConfigError(f"{file}: cannot read config ({e.strerror or e})") from None
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise ConfigError(f"{file}: TOML syntax error: {e}") from None
    try:
        return ExperimentConfig.model_validate(raw), file.parent
    except ValidationError as e:
        lines = []
        for err in e.errors():
            key = ".".join(str(p) for p in err["loc"]) or "(top level)"
            msg = err["msg"].removeprefix("Value error, ")
            if err["type"] == "extra_forbidden":
                msg = "unknown key (typo?)"
            got = f" (got {err['input']!r})" if err["type"] not in ("missing", "extra_forbidden") and not isinstance(err["input"], dict) else ""
            lines.append(f"{file}: key '{key}': {msg}{got}")
        raise ConfigError("\n".join(lines)) from None


def build_path(cfg: PathConfig, base: Path) -> tuple[Polyline, np.ndarray | None]:
    """The :class:`Polyline` a path config describes, and the per-segment feeds [mm/s] of its
    G-code program (``None`` for named paths and point lists). G-code is read relative to ``base``."""
    if cfg.name is not None:
        return named_path(cfg.name), None
    if cfg.points_mm is not None:
        return Polyline(cfg.points_mm), None
    from research.paths.gcode import read_gcode

    program = read_gcode(base / cfg.gcode, chord_tolerance=cfg.chord_tolerance_um * 1e-3)
    return program.polyline, program.feeds
