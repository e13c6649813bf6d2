"""What a run sweeps, checks and writes besides the study itself: the ``[sweep]`` table (:class:`SweepConfig`,
values as lists or :class:`Range`), the ``[[paper]]`` numbers a config reproduces (:class:`PaperNumber`)
and the ``[output]`` table (:class:`OutputConfig`).
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from pydantic import Field, StrictFloat, StrictInt, model_validator

from research.experiments.config_stages import _Strict


class Range(_Strict):
    """``num`` evenly spaced values from ``start`` to ``stop`` (both included)."""

    start: StrictInt | StrictFloat
    stop: StrictInt | StrictFloat
    num: int = Field(..., ge=1)

    def values(self) -> list[float] | list[int]:
        """The values; ints when ``start`` and ``stop`` are ints and every value is whole (a sweep of an
        int field such as ``identification.n_moves`` stays an int sweep)."""
        v = np.linspace(self.start, self.stop, self.num)
        if isinstance(self.start, int) and isinstance(self.stop, int) and np.all(v == np.round(v)):
            return [int(x) for x in np.round(v)]
        return v.tolist()


class SweepConfig(_Strict):
    """Sweep over any config fields, addressed as ``"section.key"`` or ``"section.key[i]"``."""

    mode: Literal["grid", "list"] = Field("grid", description="grid: every combination; list: values zipped")
    parameters: dict[str, list[float | int | str | bool] | Range] = Field(..., min_length=1, description="field -> values")
    engine: Literal["auto", "vmap", "dask", "serial"] = Field(
        "auto", description="auto: vmap when every swept field is an FIR/mode parameter, else dask")
    sensitivities: bool = Field(True, description="autodiff d(metric)/d(T_i, eps, F) on the vmap path")
    chunk: int = Field(2048, ge=1, description="points per compiled vmap call (one store entry each)")
    tolerance_envelope: bool = Field(True, description="a swept interpolator.tolerance_um keeps at each point the "
                                                       "fastest verified plan of a tolerance <= its own "
                                                       "(research.experiments.sweep_envelope; false: each point's own plan)")

    def values(self) -> dict[str, list]:
        return {k: v.values() if isinstance(v, Range) else list(v) for k, v in self.parameters.items()}


class PaperNumber(_Strict):
    """A number the paper prints that this config reproduces (issue 16 item 3): checked against the stored
    result by the figure's test and shown in the run summary."""

    key: str = Field(..., description="a result scalar (e.g. \"half.cycle_time\") or a path into the record's details "
                                      "(\"details.<label>.<field>[i]...\")")
    value: float = Field(..., description="the paper's value, in the unit of the result (mm, s, mm/s^n, -)")
    tolerance: float = Field(..., ge=0, description="accepted |result - value| (same unit): the paper's rounding, or a "
                                                    "stated model difference")
    source: str = Field(..., min_length=1, description="where the paper prints it (section, figure or eq, and the line)")
    reproduced: bool = Field(True, description="false: the paper's number is reported, not reproduced (stated with its "
                                               "reason; the summary shows the difference, the tests assert it is a miss)")
    reason: str | None = Field(None, description="why a number is not reproduced (required with reproduced = false)")

    @model_validator(mode="after")
    def _reason(self):
        if self.reproduced == (self.reason is not None and self.reason.strip() != ""):
            raise ValueError("reproduced = false needs a reason = \"...\" (why the paper's number is not reproduced), "
                             "and only then")
        return self


class OutputConfig(_Strict):
    """What a run writes besides ``results.json`` (none of it changes the results key)."""

    figure: bool = Field(True, description="write a figure to paper_figures/")
    export: list[Literal["csv", "gcode"]] = Field(
        [], description="trajectories to export per interpolator into results/<name>/: <label>.csv (t, q, v, a, j per "
                        "axis, units in the header) and <label>.ngc (a G-code stream, one G1 per sample)")
    gcode_tolerance_um: float = Field(0.0, ge=0, description="G64 P tolerance of the G-code stream [um] (0: G61, "
                                                             "exact path)")
