"""The ``[path]`` table: a named benchmark path, a G-code file, explicit points or a B-spline
(:class:`PathConfig`), or a named 5-axis pose path (``kind = "five_axis"``,
:class:`~research.experiments.config_five_axis_path.FiveAxisPathConfig`); and the :class:`Polyline`
a path config describes (:func:`build_path`). Coordinates in mm.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Annotated, Union

import numpy as np
from pydantic import Discriminator, Field, Tag, field_validator, model_validator

from research.errors import PathError
from research.experiments.config_five_axis_path import FiveAxisPathConfig
from research.experiments.config_path_bspline import BSplinePathConfig
from research.experiments.config_stages import _Strict
from research.paths import PATHS, Polyline, named_path

#: largest |coordinate| of ``points_mm`` [mm] (1 km: beyond any machine, and far from float overflow)
MAX_COORDINATE_MM = 1e6


class PathConfig(_Strict):
    """The tool path: exactly one of a named benchmark path, a G-code file, explicit points or a B-spline."""

    name: str | None = Field(None, description=f"named path, one of {sorted(PATHS)}")
    gcode: str | None = Field(None, description="G-code file, relative to the config file")
    points_mm: list[list[float]] | None = Field(None, description="polyline vertices [mm]")
    chord_tolerance_um: float = Field(1.0, gt=0, description="arc-to-chord tolerance for G2/G3 [um]")
    start_mm: list[float] = Field([0.0, 0.0, 0.0], description="position before the G-code program's first move "
                                  "(x, y, z) [mm]; with gcode only")
    home_mm: list[float] | None = Field(None, description="machine home (x, y, z) [mm, program frame], the target "
                                        "of G28; default LinuxCNC's, the machine origin (logged); with gcode only")
    machine_origin_mm: list[float] | None = Field(None, description="origin of the machine coordinates (x, y, z) [mm, "
                                                  "program frame: minus the work offset, one for G54-G59], the frame "
                                                  "of G53's X Y Z; default LinuxCNC's with a work offset of 0, "
                                                  "the program's origin (logged); with gcode only")
    initial_feed_mm_per_s: float | None = Field(None, gt=0, description="feed in effect before the program's first "
                                                "F word [mm/s] (a controller's default feed); without it a move "
                                                "before any F word is an error naming its line; with gcode only")
    block_delete: bool = Field(False, description="the block delete switch: lines starting with '/' are skipped "
                               "when true, read without the '/' when false (LinuxCNC's default); with gcode only")
    bspline: BSplinePathConfig | None = Field(None, description="B-spline path ([path.bspline]: control points, knots, degree)")

    @model_validator(mode="after")
    def _exactly_one(self):
        given = [k for k in ("name", "gcode", "points_mm", "bspline") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError(f"give exactly one of name, gcode, points_mm, bspline (got {given or 'none'})")
        if self.gcode is None:
            # by value, not by fields set: a dumped config (sweeps, the store) writes every field back
            extra = [k for k, v in (("home_mm", None), ("machine_origin_mm", None), ("start_mm", [0.0, 0.0, 0.0]),
                                    ("initial_feed_mm_per_s", None), ("block_delete", False)) if getattr(self, k) != v]
            if extra:
                raise ValueError(f"{', '.join(extra)} only apply to a G-code path (gcode = ...); remove them or give gcode")
        if self.name is not None and self.name not in PATHS:
            raise ValueError(f"unknown path name {self.name!r}; expected one of {sorted(PATHS)}")
        return self

    @field_validator("start_mm", "home_mm", "machine_origin_mm")
    @classmethod
    def _xyz(cls, v, info):
        if v is not None and (len(v) != 3 or any(abs(c) > MAX_COORDINATE_MM for c in v)):
            raise ValueError(f"{info.field_name} = {v}: expected 3 coordinates (x, y, z) within "
                             f"+-{MAX_COORDINATE_MM:g} mm")
        return v

    @field_validator("points_mm")
    @classmethod
    def _points(cls, pts):
        """Shape, dimension and repeated points checked here, so a bad list fails at load with its index."""
        if pts is None:
            return pts
        if len(pts) < 2:
            raise ValueError(f"a polyline needs at least 2 points, got {len(pts)}")
        dim = len(pts[0])
        if not 1 <= dim <= 3:
            raise ValueError(f"points_mm[0] has {dim} coordinates; expected 1 to 3 (x, y, z) per point")
        for i, p in enumerate(pts):
            if len(p) != dim:
                raise ValueError(f"points_mm[{i}] has {len(p)} coordinates but points_mm[0] has {dim}; "
                                 "every point needs the same number")
            big = next((c for c in p if abs(c) > MAX_COORDINATE_MM), None)
            if big is not None:
                raise ValueError(f"points_mm[{i}] has a coordinate {big!r} beyond +-{MAX_COORDINATE_MM:g} mm "
                                 "(a unit mistake? coordinates are in mm)")
            if i and p == pts[i - 1]:
                raise ValueError(f"points_mm[{i}] repeats points_mm[{i - 1}] = {p} (a zero-length segment)")
        try:
            Polyline(pts)
        except PathError as e:
            raise ValueError(str(e)) from None
        return pts


def _path_kind(value) -> str:
    """The ``kind`` of a ``[path]`` table (none: the named / G-code / points kind)."""
    return (value.get("kind") if isinstance(value, dict) else getattr(value, "kind", None)) or "polyline"


#: the ``[path]`` kinds: a polyline (named, G-code, points) or a named 5-axis pose path (``kind = "five_axis"``)
PathTable = Annotated[Union[Annotated[PathConfig, Tag("polyline")], Annotated[FiveAxisPathConfig, Tag("five_axis")]],
                      Discriminator(_path_kind)]
PATH_KINDS = ("polyline", "five_axis")


def build_path(cfg: PathConfig, base: Path) -> tuple[Polyline, np.ndarray | None]:
    """The :class:`Polyline` a path config describes, and the per-segment feeds [mm/s] of its
    G-code program (``None`` for named paths and point lists). G-code is read relative to ``base``."""
    if cfg.name is not None:
        return named_path(cfg.name), None
    if cfg.points_mm is not None:
        return Polyline(cfg.points_mm), None
    if cfg.bspline is not None:
        return cfg.bspline.polyline(), None
    program = read_program(cfg, base)
    return program.polyline, program.feeds


def read_program(cfg: PathConfig, base: Path):
    """The :class:`~research.paths.gcode.GCodeProgram` of a G-code path config (read relative to
    ``base``; arcs as chords at ``chord_tolerance_um`` and as blocks; from ``start_mm``, ``G28`` to
    ``home_mm``, ``G53`` from ``machine_origin_mm``, ``F`` before the first F word from
    ``initial_feed_mm_per_s``, ``/`` lines skipped or read by ``block_delete``)."""
    from research.paths.gcode import read_gcode

    program = read_gcode(base / cfg.gcode, chord_tolerance=cfg.chord_tolerance_um * 1e-3, start=tuple(cfg.start_mm),
                         home=None if cfg.home_mm is None else tuple(cfg.home_mm),
                         machine_origin=None if cfg.machine_origin_mm is None else tuple(cfg.machine_origin_mm),
                         initial_feed=None if cfg.initial_feed_mm_per_s is None else 60.0 * cfg.initial_feed_mm_per_s,
                         block_delete=cfg.block_delete)
    if program.unread_lines:
        logging.getLogger(__name__).warning(
            "%s: the program ends on line %d (M2/M30 or the closing %%); %d non-blank line(s) after it are not "
            "read, as LinuxCNC does (first: line %d)", program.source, program.end_line, len(program.unread_lines),
            program.unread_lines[0])
    return program
