"""Experiment configs: TOML files validated by a schema (pydantic).

An experiment is a path + one or more interpolators + an optional drive model (with structural
modes) + optional identification + the metrics to report + what to write; a ``[sweep]`` table
turns it into a sensitivity study (:mod:`research.experiments.sweep`). Units are in the key names
(``feed_mm_per_s``, ``delays_ms``, ``tolerance_um``, ``frequency_hz``) and converted to the
package's mm / s on entry. Unknown keys (typos, or a unit the key does not have, e.g.
``feed_mm_per_min``), wrong types, out-of-range values and missing input files raise
:class:`~research.errors.ConfigError` naming the file and the key.

Validation is strict (pydantic ``strict=True``, ``allow_inf_nan=False``): numbers are finite (TOML
``inf`` / ``nan`` are refused), nothing is coerced (a bool is not a number, ``"250"`` is not a number,
``10.0`` is not an int; a TOML integer is fine where a float is expected), ``points_mm`` is checked at
load (equal lengths, 1 to 3 coordinates, at least 2 points, no repeated consecutive point, coordinates
within :data:`MAX_COORDINATE_MM`), and
``name`` (a file stem) must match :data:`NAME_PATTERN`. Every default is in the
``Field(...)`` of its key, with its description (``ExperimentConfig.model_json_schema()`` lists them).

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

from pydantic import Field, ValidationError, model_validator

from research.errors import ConfigError
from research.experiments.config_control import CONTROL_METRIC_UNITS, ControlConfig
from research.experiments.config_drive import DRIVE_MODELS, PER_AXIS_DRIVES, DriveConfig, ModeConfig
from research.experiments.config_feedrate import FEEDRATE_METRIC_UNITS, FeedrateConfig
from research.experiments.config_five_axis_path import FiveAxisPathConfig
from research.experiments.config_identification import IdentificationConfig, LogColumns, LogUnits
from research.experiments.config_identification_ch6 import IDENTIFICATION_CH6_METRIC_UNITS, IdentificationCh6Config
from research.experiments.config_identified_contour import IDENTIFIED_CONTOUR_METRIC_UNITS, IdentifiedContourConfig
from research.experiments.config_interpolator import (
    FEED_RANGE_MM_PER_S, INTERPOLATOR_KINDS, FIRConfig, Interpolator, TimeOptimalConfig)
from research.experiments.config_messages import describe_error
from research.experiments.config_optimality import OPTIMALITY_METRIC_UNITS, OptimalityConfig
from research.experiments.config_output import OutputConfig, PaperNumber, Range, SweepConfig
from research.experiments.config_path import (
    MAX_COORDINATE_MM, PATH_KINDS, PathConfig, PathTable, build_path, read_program)
from research.experiments.config_stages import (
    _Strict,
    CompensationConfig,
    ContourConfig,
    FiveAxisContourConfig,
    MTPConfig,
    SpectrumConfig,
    StartupConfig,
    VibrationConfig,
)
from research.experiments.stage_execution_errors import EXECUTION_ERROR_METRIC_UNITS
from research.paths import named_path

#: the schema's tables live in ``config_<table>.py`` modules; these names stay importable from here
__all__ = [
    "DRIVE_MODELS", "FEED_RANGE_MM_PER_S", "INTERPOLATOR_KINDS", "MAX_COORDINATE_MM", "METRIC_UNITS", "NAME_PATTERN",
    "PATH_KINDS", "PER_AXIS_DRIVES", "DriveConfig", "ExperimentConfig", "FIRConfig", "IdentificationConfig",
    "Interpolator", "LogColumns", "LogUnits", "ModeConfig", "OutputConfig", "PaperNumber", "PathConfig", "PathTable",
    "Range", "SweepConfig", "TimeOptimalConfig", "build_path", "input_files", "load_config", "named_axes",
    "read_program", "validate",
]

#: metric names a config may ask for (``metrics = [...]``); units in :data:`METRIC_UNITS`
METRIC_UNITS = {
    "cycle_time": "s",
    "max_corner_error": "mm",
    "max_contour_error": "mm",
    "peak_feed": "mm/s",
    "residual_vibration": "mm",
    "max_tracking_error": "mm",
    "wn_error": "-",
    "zeta_error": "-",
    "p_error": "-",
    "dc_error": "-",
    # contour stage (drive's actual motion): exact error against the CAM path, and each estimator's
    # largest estimate and largest difference to the exact error against the reference curve
    "max_actual_contour_error": "mm",
    "rms_actual_contour_error": "mm",
    "max_estimate": "mm",
    "max_estimator_error": "mm",
    # compensation stage (CEC): max |e_T| before and after, and the drive simulations it took
    "cec_error_before": "mm",
    "cec_error_after": "mm",
    "cec_error_ratio": "-",
    "cec_simulations": "-",
    # drive frequency response: poles of eq 6.13 and the -3 dB tracking bandwidth
    "drive_wn_hz": "Hz",
    "drive_zeta": "-",
    "drive_p_hz": "Hz",
    "drive_bandwidth_hz": "Hz",
    # vibration stage: estimated modes and their eq 10 delays
    "mode_frequency_hz": "Hz",
    "mode_damping": "-",
    "tuned_delay": "s",
    # spectrum stage: FIR chain gain |M| (eq 9) at a mode, and its largest value at the zeros k / T_i
    "spectrum_gain": "-",
    "spectrum_null_gain": "-",
    # startup stage: the peak of a sigmoid-blended move's feed and when it occurs
    "startup_peak_feed": "mm/s",
    "startup_peak_time": "s",
    "startup_initial_acceleration": "mm/s^2",
    # mtp stage (DiMarco 2015 MTP through a drive): per reference, cycle, errors against the nominal move, peaks
    "mtp_cycle_time": "s",
    "mtp_rms_tracking_error": "mm",
    "mtp_max_tracking_error": "mm",
    "mtp_max_reference_error": "mm",
    "mtp_peak_acceleration": "mm/s^2",
    "mtp_peak_jerk": "mm/s^3",
    # five-axis contour stage: mean |estimate - exact| while moving
    "mean_estimator_error": "mm",
}
METRIC_UNITS |= CONTROL_METRIC_UNITS  # [control] stage (thesis ch 5)
METRIC_UNITS |= FEEDRATE_METRIC_UNITS  # [feedrate] stage (thesis ch 3)
METRIC_UNITS |= IDENTIFIED_CONTOUR_METRIC_UNITS  # [identified_contour] stage (thesis §6.5.3)
METRIC_UNITS |= IDENTIFICATION_CH6_METRIC_UNITS  # [identification_ch6] stage (thesis ch 6)
METRIC_UNITS |= OPTIMALITY_METRIC_UNITS  # [optimality] stage (FIR against the time-optimal OCP)
METRIC_UNITS |= EXECUTION_ERROR_METRIC_UNITS  # Prévost's e1 / e2 / eT in the [compensation] stage
#: what ``name`` (the results folder and figure file stem) may be: starts with a letter or digit, at most 64
#: characters of letters, digits, ``_``, ``-`` and ``.`` (so never ``..`` or a path)
NAME_PATTERN = r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,63}$"


class ExperimentConfig(_Strict):
    """One study: a path, interpolator(s), a drive, identification, metrics, what it reproduces."""

    name: str = Field(..., pattern=NAME_PATTERN, description="results and figure file stem (letters, digits, _ - .)")
    reproduces: str = Field("", description="the paper result this experiment reproduces (empty for a study "
                            "of one's own program or machine)")
    description: str = ""
    path: PathTable | None = Field(None, description="tool path (required unless the study is identification only); "
                                                    "kind = \"five_axis\": a 5-axis pose path for [feedrate]")
    interpolator: list[Interpolator] = Field([FIRConfig()], min_length=1,
                                             description="one table, or an array of tables [[interpolator]]; kind defaults to fir")
    drive: DriveConfig | None = None
    identification: IdentificationConfig | None = None
    vibration: VibrationConfig | None = Field(None, description="resonance test -> modes -> eq 10 delays")
    spectrum: SpectrumConfig | None = Field(None, description="FIR chain frequency response (eq 8-10)")
    startup: StartupConfig | None = Field(None, description="sigmoid start of a linear move (DiMarco 2015 eq 3-5)")
    mtp: MTPConfig | None = Field(None, description="modulated tool path: sigmoid vs linear interpolators through "
                                                    "the [drive] (DiMarco 2015)")
    five_axis_contour: FiveAxisContourConfig | None = Field(
        None, description="thesis §4.5: eq 4.36 5-axis path, exact tip contour error vs Frenet estimates")
    contour: ContourConfig | None = Field(None, description="contour-error stage (needs a drive other than ideal)")
    compensation: CompensationConfig | None = Field(None, description="CEC stage (needs a drive other than ideal)")
    control: ControlConfig | None = Field(None, description="thesis ch 5 closed loop on the Fig 5.5 path (SISO SMC or "
                                                            "5-axis contour controller)")
    feedrate: FeedrateConfig | None = Field(None, description="thesis ch 3: optimized vs constant feed along a 5-axis "
                                                              "[path] (kind = \"five_axis\"), Fig 3.13 drive run")
    identified_contour: IdentifiedContourConfig | None = Field(
        None, description="thesis §6.5.3 / Fig 6.13: Table 6.3 machine identified by LS and PSO, predicting the eq 4.36 "
                          "tip contour error")
    identification_ch6: IdentificationCh6Config | None = Field(None, description="thesis ch 6: methods compared on the "
                                                                                 "Table 6.1 virtual drive, and the EMPS axis")
    optimality: OptimalityConfig | None = Field(None, description="FIR (plain, limits held) against the time-optimal OCP "
                                                                  "on the optimality study's paths")
    metrics: list[Literal[tuple(METRIC_UNITS)]] | None = Field(None, description="metrics to report (default: all)")
    output: OutputConfig = OutputConfig()
    sweep: SweepConfig | None = None
    paper: list[PaperNumber] = Field([], description="paper numbers this config reproduces ([[paper]] tables)")

    @model_validator(mode="before")
    @classmethod
    def _interpolator_list(cls, data):
        if isinstance(data, dict) and "interpolator" in data:
            items = data["interpolator"]
            items = [items] if isinstance(items, dict) else items
            if isinstance(items, list):
                items = [({"kind": "fir"} | i) if isinstance(i, dict) else i for i in items]
            data = data | {"interpolator": items}
        return data

    @model_validator(mode="after")
    def _limits_from_earlier(self):
        labels = []
        for ic in self.interpolators:
            source = getattr(ic, "limits_from", None)
            if source is not None and (ic.limits is not None or source not in labels):
                raise ValueError(f"interpolator {ic.label or ic.kind!r}: limits_from = {source!r} names no earlier "
                                 f"interpolator (earlier: {labels}) or comes with limits; give one of them")
            labels.append(ic.label or ic.kind)
        return self

    @model_validator(mode="after")
    def _something_to_do(self):
        drive_study = self.drive is not None and self.drive.frequency_response is not None
        if (self.path is None and self.identification is None and self.vibration is None and self.spectrum is None
                and self.startup is None and self.five_axis_contour is None and self.control is None and not drive_study
                and self.identified_contour is None
                and self.mtp is None and self.identification_ch6 is None
                and self.optimality is None):
            raise ValueError("give a [path] (motion study), an [identification] table, a [vibration] table, a "
                             "[spectrum] table, a [startup] table, an [mtp] table, a [five_axis_contour] table, a [control] table, an "
                             "[identified_contour] table, an [identification_ch6] table, an [optimality] table or a "
                             "[drive.frequency_response] table")
        five_axis = isinstance(self.path, FiveAxisPathConfig)
        if five_axis != (self.feedrate is not None):
            raise ValueError("a [path] with kind = \"five_axis\" and a [feedrate] table go together (the feed-rate "
                             "optimisation runs along a 5-axis path; the interpolators along a polyline)")
        if five_axis and ({"interpolator", "drive", "contour", "compensation", "sweep"} & self.model_fields_set):
            raise ValueError("a 5-axis [path] is scheduled by [feedrate] only; [interpolator], [drive], [contour], "
                             "[compensation] and [sweep] take a polyline path (the Fig 3.13 drives are [feedrate.drive])")
        if self.mtp is not None and (self.drive is None or self.drive.model == "ideal" or self.drive.model in PER_AXIS_DRIVES):
            raise ValueError("[mtp] runs its references through a [drive] of one model (not \"ideal\", not per axis)")
        if drive_study and self.drive.model == "ideal":
            raise ValueError("[drive.frequency_response] needs a drive model, not \"ideal\"")
        if self.drive is not None and self.drive.model == "identified":
            if self.drive.identified_file is not None:
                if self.identification is not None:
                    raise ValueError("drive.model = \"identified\" has two sources: drive.identified_file and this "
                                     "config's [identification]; keep one")
            elif (self.identification is None or self.identification.method != "simulation_error"
                  or self.identification.structure != "eq6.3"):
                raise ValueError("drive.model = \"identified\" runs the path through an identified drive: give "
                                 "drive.identified_file (a model file written by save_identified), or an "
                                 "[identification] table with method = \"simulation_error\" and structure = \"eq6.3\" "
                                 "(the structure the drive simulator takes)")
        for stage in ("contour", "compensation"):
            if getattr(self, stage) is not None and (self.path is None or self.drive is None or self.drive.model == "ideal"):
                raise ValueError(f"the [{stage}] stage works on the drive's actual motion: it needs a [path] and a [drive] "
                                 "with a model other than \"ideal\"")
        labels = [i.label or i.kind for i in self.interpolators]
        if len(set(labels)) != len(labels):
            raise ValueError(f"interpolator labels must be unique, got {labels}; set label = \"...\"")
        if self.drive is not None and self.path is not None:
            axes = named_axes(self)
            bad = [m.axis for m in self.drive.modes if m.axis not in axes]
            if bad:
                raise ValueError(f"drive.modes: axis {bad[0]!r} is not an axis of the path {axes}")
        return self

    @property
    def interpolators(self) -> list:
        """The interpolator configs (always a list)."""
        return list(self.interpolator)


def named_axes(cfg: ExperimentConfig) -> tuple[str, ...]:
    """Axis letters of the path (from its dimension: x, y, z; a 5-axis path: x, y, z, a, c)."""
    p = cfg.path
    if isinstance(p, FiveAxisPathConfig):
        return ("x", "y", "z", "a", "c")
    dim = len(p.points_mm[0]) if p.points_mm else (named_path(p.name).dim if p.name else
                                                    len(p.bspline.control_points_mm[0]) if p.bspline else 3)
    return ("x", "y", "z")[:dim]


def load_config(file: str | Path) -> tuple[ExperimentConfig, Path]:
    """Read and validate a TOML experiment file.

    Returns:
        ``(config, directory of the file)`` (relative paths in the config are resolved from it).

    Raises:
        ConfigError: missing file, TOML syntax error, unknown key, wrong type or value, or an input
            file (G-code, drive log) that does not exist.
    """
    file = Path(file)
    try:
        data = file.read_bytes()
    except OSError as e:
        raise ConfigError(f"{file}: cannot read config ({e.strerror or e})") from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as e:
        line = data[: e.start].count(b"\n") + 1
        raise ConfigError(f"{file}: line {line}: not UTF-8 text (byte {data[e.start]:#04x}); save the config as UTF-8") from None
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise ConfigError(f"{file}: TOML syntax error: {e}") from None
    return validate(raw, file), file.parent


def validate(raw: dict, file: str | Path) -> ExperimentConfig:
    """Validate a config dictionary; errors name ``file`` and the dotted key. Also checks that the
    input files it names exist (relative to the file's folder)."""
    file = Path(file)
    try:
        cfg = ExperimentConfig.model_validate(raw)
    except ValidationError as e:
        single = isinstance(raw.get("interpolator"), dict)
        raise ConfigError("\n".join(describe_error(err, file, single, ExperimentConfig) for err in e.errors())) from None
    for key, name in input_files(cfg).items():
        try:
            found = (file.parent / name).is_file()
        except (OSError, ValueError) as e:  # e.g. a NUL byte or an over-long name
            raise ConfigError(f"{file}: key '{key}': not a usable file name {name!r} ({e})") from None
        if not found:
            raise ConfigError(f"{file}: key '{key}': file not found: {file.parent / name}")
    return cfg


def input_files(cfg: ExperimentConfig) -> dict[str, str]:
    """``{dotted key: file name}`` of every input file the config reads (part of the results key)."""
    files = {}
    if isinstance(cfg.path, PathConfig) and cfg.path.gcode is not None:
        files["path.gcode"] = cfg.path.gcode
    if cfg.identification is not None and cfg.identification.log_file is not None:
        files["identification.log_file"] = cfg.identification.log_file
    if cfg.vibration is not None and cfg.vibration.log_file is not None:
        files["vibration.log_file"] = cfg.vibration.log_file
    if cfg.identification_ch6 is not None and cfg.identification_ch6.emps_log_file is not None:
        files["identification_ch6.emps_log_file"] = cfg.identification_ch6.emps_log_file
    if cfg.drive is not None and cfg.drive.identified_file is not None:
        files["drive.identified_file"] = cfg.drive.identified_file
    return files
