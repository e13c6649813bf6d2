"""The ``[identification]`` table: identify a drive (thesis ch 6) from a synthetic log of a catalog
drive or from a logged file, with the log's column names and units by role.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from research.experiments.config_stages import _Strict


class LogColumns(_Strict):
    """Names of a drive log's columns (or halscope channels) by role."""

    t: str = Field("t", min_length=1, description="time column (none in a halscope export: t = k Ts)")
    x_ref: str = Field("x_ref", min_length=1, description="commanded position column")
    x_act: str = Field("x_act", min_length=1, description="measured (encoder) position column")


class LogUnits(_Strict):
    """Units of a drive log's columns by role; converted to s and mm (rad for a rotary axis) on reading."""

    t: str = Field("s", description="time unit (s, ms, us)")
    x_ref: str = Field("mm", description="commanded position unit (mm, m, um, in; deg, rad; counts)")
    x_act: str = Field("mm", description="measured position unit (mm, m, um, in; deg, rad; counts)")


class IdentificationConfig(_Strict):
    """Identify a drive from a log: a synthetic one (the thesis §6.5 program run through a catalog drive
    and a noisy encoder, so errors against the truth are known) or a logged file."""

    method: Literal["ls", "pso", "optimistix", "simulation_error"] = Field(
        "ls", description="least squares (eq 6.12), PSO (§6.4), optimistix bounded fit, or the noise-robust "
                          "simulation-error fit (research.identification.simulation_error_fit)")
    structure: Literal["eq6.3", "pp2", "pp4", "pi5"] = Field(
        "eq6.3", description="model structure of the simulation-error fit (the other methods fit eq 6.3)")
    truth: Literal["sencer2009_table6_1", "sencer2009_table6_2"] = Field(
        "sencer2009_table6_1", description="catalog closed-loop drive that generates the synthetic log")
    n_moves: int = Field(70, ge=1, description="excitation length: moves of the §6.5 program (thesis: 70)")
    noise_um: float = Field(0.0, ge=0, description="encoder noise standard deviation [um]")
    resolution_um: float = Field(0.05, ge=0, description="encoder resolution [um] (0: none)")
    seed: int = Field(0, ge=0, description="seed of the program and the noise")
    log_file: str | None = Field(None, description="logged drive data (csv/mat/npz or a halscope text export; "
                                                    "relative to the config file) instead of a synthetic log")
    columns: LogColumns = Field(LogColumns(), description="column names of log_file by role, e.g. "
                                                          "{t = \"time_s\", x_ref = \"X_cmd\", x_act = \"X_enc\"}")
    units: LogUnits = Field(LogUnits(), description="units of log_file's columns, e.g. {x_ref = \"m\", x_act = \"counts\"}")
    counts_per_mm: float | None = Field(None, gt=0, description="encoder resolution of columns in counts [1/mm]")
    counts_per_rev: float | None = Field(None, gt=0, description="encoder resolution of rotary columns in counts [1/rev]")

    @model_validator(mode="after")
    def _log_options(self):
        defaults = {"columns": LogColumns(), "units": LogUnits(), "counts_per_mm": None, "counts_per_rev": None}
        given = [k for k, v in defaults.items() if getattr(self, k) != v]  # a dumped config repeats the defaults
        if self.log_file is None and given:
            raise ValueError(f"{', '.join(given)} describe log_file, which is not given (the synthetic log needs none)")
        if self.counts_per_mm is not None and self.counts_per_rev is not None:
            raise ValueError("give counts_per_mm (linear axis) or counts_per_rev (rotary axis), not both")
        return self
