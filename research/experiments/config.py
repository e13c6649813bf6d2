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

import difflib
import re
import tomllib
from pathlib import Path
from typing import Annotated, Literal, Union, get_args

import numpy as np
from pydantic import BaseModel, StrictFloat, StrictInt, Discriminator, Field, Tag, ValidationError, field_validator, model_validator

from research.errors import ConfigError, PathError
from research.experiments.config_control import CONTROL_METRIC_UNITS, ControlConfig
from research.experiments.config_feedrate import FEEDRATE_METRIC_UNITS, FeedrateConfig
from research.experiments.config_five_axis_path import FiveAxisPathConfig
from research.experiments.config_identified_contour import IDENTIFIED_CONTOUR_METRIC_UNITS, IdentifiedContourConfig
from research.experiments.config_identification_ch6 import IDENTIFICATION_CH6_METRIC_UNITS, IdentificationCh6Config
from research.experiments.config_optimality import OPTIMALITY_METRIC_UNITS, OptimalityConfig
from research.experiments.config_path_bspline import BSplinePathConfig
from research.experiments.stage_execution_errors import EXECUTION_ERROR_METRIC_UNITS
from research.experiments.config_stages import (
    _Strict,
    BlendConfig,
    ClosedLoopConfig,
    CompensationConfig,
    FrequencyResponseConfig,
    ContourConfig,
    LimitsConfig,
    SCurveConfig,
    SigmoidConfig,
    FiveAxisContourConfig,
    SpectrumConfig,
    MTPConfig,
    StartupConfig,
    VibrationConfig,
)
from research.paths import PATHS, Polyline, named_path

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
#: largest |coordinate| of ``points_mm`` [mm] (1 km: beyond any machine, and far from float overflow)
MAX_COORDINATE_MM = 1e6
#: plausible feed range [mm/s] (issue 16): below 1 mm/s is a unit slip (m/s typed in a mm/s key), above
#: 10 m/s beyond any machine tool (mm/min typed in a mm/s key); outside it a config is refused
FEED_RANGE_MM_PER_S = (1.0, 10_000.0)
DRIVE_MODELS = ("ideal", "sencer2009_table6_1", "sencer2009_table6_1_ppi", "sencer2009_table6_2", "sencer2009_table6_2_pid",
                "sencer2009_table6_3", "sencer2009_table6_3_ppi", "parameters", "identified")
#: catalog drives with one model per axis (thesis Table 6.3: axes x, y, z, a, c)
PER_AXIS_DRIVES = {"sencer2009_table6_3": "table_6_3_closed_loop", "sencer2009_table6_3_ppi": "table_6_3_ppi"}


class PathConfig(_Strict):
    """The tool path: exactly one of a named benchmark path, a G-code file, explicit points or a B-spline."""

    name: str | None = Field(None, description=f"named path, one of {sorted(PATHS)}")
    gcode: str | None = Field(None, description="G-code file, relative to the config file")
    points_mm: list[list[float]] | None = Field(None, description="polyline vertices [mm]")
    chord_tolerance_um: float = Field(1.0, gt=0, description="arc-to-chord tolerance for G2/G3 [um]")
    bspline: BSplinePathConfig | None = Field(None, description="B-spline path ([path.bspline]: control points, knots, degree)")

    @model_validator(mode="after")
    def _exactly_one(self):
        given = [k for k in ("name", "gcode", "points_mm", "bspline") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError(f"give exactly one of name, gcode, points_mm, bspline (got {given or 'none'})")
        if self.name is not None and self.name not in PATHS:
            raise ValueError(f"unknown path name {self.name!r}; expected one of {sorted(PATHS)}")
        return self

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


class FIRConfig(_Strict):
    """Sencer 2015 FIR-overlap interpolator settings (defaults: the paper's §4 experiment)."""

    kind: Literal["fir"] = "fir"
    label: str | None = Field(None, description="name in results (default: kind)")
    feed_mm_per_s: float = Field(250.0, gt=0, description="commanded feed F [mm/s]")
    delays_ms: list[float] = Field([148.0, 89.0], min_length=1, description="FIR delays T_i [ms]")
    tolerance_um: float = Field(500.0, ge=0, description="cornering tolerance epsilon [um]")
    sample_period_ms: float = Field(1.0, gt=0, description="interpolation period Ts [ms]")
    refine: bool = Field(True, description="short-segment rule (verified overlap)")
    limits: LimitsConfig | None = Field(None, description="axis limits the FIR also holds (plan_fir(limits=...), "
                                                          "beyond the paper; none: the paper's planner)")
    optimized: bool = Field(False, description="per-corner overlaps and per-block feeds chosen for the least cycle "
                                               "time (research.interpolators.optimize_fir, beyond the paper): G01 "
                                               "paths with one feed and tolerance, eps > 0")

    @model_validator(mode="after")
    def _positive_delays(self):
        bad = [i for i, d in enumerate(self.delays_ms) if not d > 0]
        if bad:
            raise ValueError(f"delays_ms[{bad[0]}] must be > 0 ms, got {self.delays_ms[bad[0]]}")
        _plausible_units(self.feed_mm_per_s, self.delays_ms, self.sample_period_ms, "delays_ms")
        if self.optimized and not self.tolerance_um > 0:
            raise ValueError("optimized = true needs a cornering tolerance tolerance_um > 0 um (optimize_fir)")
        return self


class TimeOptimalConfig(_Strict):
    """CasADi minimum-time reference (:func:`research.optimal.time_optimal`) in the tolerance tube,
    under the nominal envelope of an FIR with ``envelope_delays_ms`` (``v = F, a = F/T1, j = F/(T1 T2)``)."""

    kind: Literal["time_optimal"]
    label: str | None = Field(None, description="name in results (default: kind)")
    feed_mm_per_s: float = Field(250.0, gt=0, description="path speed bound F and envelope feed [mm/s]")
    tolerance_um: float = Field(500.0, gt=0, description="tube radius epsilon [um]")
    envelope_delays_ms: list[float] = Field([148.0, 89.0], min_length=1, description="FIR delays setting the limits [ms]")
    intervals_per_segment: int = Field(16, ge=3, description="jerk intervals per segment")
    window: int | None = Field(None, ge=1, description="segments per receding window (none: whole path)")
    sample_period_ms: float = Field(1.0, gt=0, description="sample period of the returned trajectory [ms]")

    @model_validator(mode="after")
    def _plausible(self):
        _plausible_units(self.feed_mm_per_s, self.envelope_delays_ms, self.sample_period_ms, "envelope_delays_ms")
        return self


def _plausible_units(feed: float, delays_ms: list[float], sample_period_ms: float, delays_key: str) -> None:
    """Refuse the unit slips the key names invite (issue 16): a feed outside :data:`FEED_RANGE_MM_PER_S`
    and a delay shorter than the sample period (an FIR shorter than Ts has no sample inside it; a value
    such as 0.06 in a ``_ms`` key is most likely seconds)."""
    lo, hi = FEED_RANGE_MM_PER_S
    if feed < lo:
        raise ValueError(f"feed_mm_per_s = {feed:g} mm/s is below {lo:g} mm/s; the key is in mm/s: was it m/s "
                         f"({feed:g} m/s = {feed * 1e3:g} mm/s)?")
    if feed > hi:
        raise ValueError(f"feed_mm_per_s = {feed:g} mm/s is above {hi:g} mm/s (10 m/s); the key is in mm/s: was it "
                         f"mm/min ({feed:g} mm/min = {feed / 60:g} mm/s)?")
    for i, d in enumerate(delays_ms):
        if d < sample_period_ms:
            hint = (f"; the key is in ms: was it seconds ({d:g} s = {d * 1e3:g} ms)?" if d < 1.0
                    else "; lengthen the delay or shorten sample_period_ms")
            raise ValueError(f"{delays_key}[{i}] = {d:g} ms is below the sample period sample_period_ms = "
                             f"{sample_period_ms:g} ms{hint}")


def _path_kind(value) -> str:
    """The ``kind`` of a ``[path]`` table (none: the named / G-code / points kind)."""
    return (value.get("kind") if isinstance(value, dict) else getattr(value, "kind", None)) or "polyline"


#: the ``[path]`` kinds: a polyline (named, G-code, points) or a named 5-axis pose path (``kind = "five_axis"``)
PathTable = Annotated[Union[Annotated[PathConfig, Tag("polyline")], Annotated[FiveAxisPathConfig, Tag("five_axis")]],
                      Discriminator(_path_kind)]
PATH_KINDS = ("polyline", "five_axis")


Interpolator = Annotated[Union[FIRConfig, TimeOptimalConfig, SCurveConfig, BlendConfig, SigmoidConfig],
                         Field(discriminator="kind")]
#: the interpolator kinds a config may name
INTERPOLATOR_KINDS = ("fir", "time_optimal", "scurve", "blend", "sigmoid")


class ModeConfig(_Strict):
    """A lightly damped structural mode excited by one axis' acceleration (the beams of Sencer 2015 §4)."""

    axis: str = Field(..., description="axis letter that excites it (x, y, z)")
    frequency_hz: float = Field(..., gt=0, description="natural frequency [Hz]")
    damping: float = Field(0.02, gt=0, lt=1, description="damping ratio [-] (2 %: the paper gives none)")


class DriveConfig(_Strict):
    """Drive model the references run through. ``ideal``: the axes follow the reference exactly and the
    modes see the reference acceleration; a thesis catalog drive (Table 6.1 / 6.2 on every axis, Table 6.3
    per axis); ``parameters``: the eq 6.3 model in ``[drive.parameters]``; ``identified``: the drive the
    config's ``[identification]`` fits, or the model file ``identified_file`` (written by
    :func:`research.identification.save_identified`, e.g. ``drive_model.json`` of an earlier run)."""

    model: Literal[DRIVE_MODELS] = Field("ideal", description=f"one of {DRIVE_MODELS}")
    parameters: ClosedLoopConfig | None = Field(None, description="eq 6.3 parameters (model = \"parameters\")")
    identified_file: str | None = Field(
        None, description="identified-model file written by save_identified (model = \"identified\"), relative to the "
                          "config file, e.g. \"../results/<name>/drive_model.json\" of an earlier run; its bytes are "
                          "part of the results key")
    modes: list[ModeConfig] = Field([], description="structural modes")
    settle_time_s: float = Field(1.5, gt=0, description="rest simulated after the motion [s] (catalog drives)")
    frequency_response: FrequencyResponseConfig | None = Field(
        None, description="tracking / disturbance responses, poles and bandwidth of the drive (a drive model, not ideal)")

    @model_validator(mode="after")
    def _parameters_with_model(self):
        if (self.model == "parameters") != (self.parameters is not None):
            raise ValueError("model = \"parameters\" and a [drive.parameters] table go together "
                             f"(got model = {self.model!r}, parameters {'given' if self.parameters else 'missing'})")
        if self.identified_file is not None and self.model != "identified":
            raise ValueError(f"identified_file goes with model = \"identified\" (got model = {self.model!r})")
        return self


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


class ExperimentConfig(_Strict):
    """One study: a path, interpolator(s), a drive, identification, metrics, what it reproduces."""

    name: str = Field(..., pattern=NAME_PATTERN, description="results and figure file stem (letters, digits, _ - .)")
    reproduces: str = Field(..., description="the paper result this experiment reproduces")
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
        raise ConfigError("\n".join(_describe(err, file, single) for err in e.errors())) from None
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


def _describe(err: dict, file: Path, single_interpolator: bool) -> str:
    loc = list(err["loc"])
    if loc[:1] == ["interpolator"]:  # drop the union tag, and the list index of a single [interpolator] table
        loc = ["interpolator"] + [p for p in loc[1 + single_interpolator:] if p not in INTERPOLATOR_KINDS]
    elif loc[:1] == ["path"]:  # drop the path kind tag
        loc = ["path"] + [p for p in loc[1:] if p not in PATH_KINDS]
    key = "".join(f"[{p}]" if isinstance(p, int) else f".{p}" for p in loc).lstrip(".") or "(top level)"
    msg = err["msg"].removeprefix("Value error, ")
    kind, value = err["type"], err.get("input")
    named = re.match(r"([A-Za-z_]+(?:\[\d+\])?) = ", msg) if kind == "value_error" else None
    if named and isinstance(value, dict) and named.group(1).split("[")[0] in value:  # a table check naming its key
        key = f"{key}.{named.group(1)}"
    if kind == "extra_forbidden":
        msg = "unknown key (typo?" + _suggest(err["loc"]) + ")"
    elif kind.startswith(("float", "int")) and isinstance(value, bool):
        msg += "; a bool is not a number"
    elif kind.startswith(("float", "int")) and isinstance(value, str):
        msg += ("; give a plain number, the unit is in the key name" if any(c.isalpha() for c in value)
                else "; give a number, not a string (no quotes)")
    elif kind == "int_type" and isinstance(value, float):
        msg += "; give a whole number without a decimal point"
    elif kind == "finite_number":
        msg += " (inf and nan are not allowed)"
    elif kind == "list_type" and isinstance(value, (str, int, float)):
        msg += f"; give an array, e.g. [{_toml(value)}]"
    elif kind == "bool_type":
        msg += "; give true or false (no quotes)"
    shown = repr(value)
    shown = shown if len(shown) <= 120 else shown[:100] + " ... " + shown[-15:]
    got = "" if kind in ("missing", "extra_forbidden") or isinstance(value, dict) else f" (got {shown})"
    return f"{file}: key '{key}': {msg}{got}"


def _toml(value) -> str:
    return f'"{value}"' if isinstance(value, str) else str(value).lower() if isinstance(value, bool) else repr(value)


def _suggest(loc: tuple) -> str:
    """`` did you mean 'x'?`` for an unknown key close to a known one of the same table."""
    models = [ExperimentConfig]
    for part in loc[:-1]:
        if not isinstance(part, str):
            continue
        tagged = [m for m in models if "kind" in m.model_fields and part in get_args(m.model_fields["kind"].annotation)]
        if tagged:  # a discriminated-union tag (interpolator kind)
            models = tagged
            continue
        field = next((m.model_fields[part] for m in models if part in m.model_fields), None)
        models = _models_in(field.annotation) if field is not None else models
    known = [k for m in models for k in m.model_fields]
    close = difflib.get_close_matches(str(loc[-1]), known, n=1, cutoff=0.6)
    return f" did you mean '{close[0]}'?" if close else ""


def _models_in(annotation) -> list[type[BaseModel]]:
    """Pydantic models inside an annotation (through Optional, list, Union, Annotated)."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation]
    return [m for a in get_args(annotation) for m in _models_in(a)]


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
    ``base``; arcs as chords at ``chord_tolerance_um`` and as blocks)."""
    from research.paths.gcode import read_gcode

    return read_gcode(base / cfg.gcode, chord_tolerance=cfg.chord_tolerance_um * 1e-3)
