"""Schema of the ``[feedrate]`` stage (issue 16 item 1): thesis ch 3 feed-rate optimisation along a 5-axis
``[path]`` (``kind = "five_axis"``), the constant-feed comparison, and optionally the Fig 3.13 drive run.

- optimisation: a cubic B-spline feed in arc length (eq 3.31-3.38) with ``control_points`` coefficients, minimum
  time (eq 3.30) under every axis' velocity, acceleration and jerk limit (eq 3.39-3.56) of thesis Table 3.1 and
  the programmed feed cap (eq 3.57), :func:`research.optimal.optimize_feedrate`;
- comparison: each constant feed of ``constant_feeds_mm_per_s`` with S-curve start and stop
  (:func:`research.optimal.constant_feed`), its limits checked, not enforced;
- ``[feedrate.drive]`` (Fig 3.13): every schedule through the SISO sliding-mode drives of Table 5.2 with the
  amplifier limit ``u_max = m A + c V + d_c`` read from Table 3.1 (:func:`research.control.feed_tracking`).

Example::

    [feedrate]
    feed_mm_per_s = 150.0
    constant_feeds_mm_per_s = [15.0]
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from research.experiments.config_stages import _Strict

#: scalar metrics of the stage and their units (merged into ``config.METRIC_UNITS``); per schedule label
#: (``optimized``, ``constant_<F>``), per axis suffixed ``.x`` ... ``.c``
FEEDRATE_METRIC_UNITS = {
    "feedrate_cycle_time": "s",
    "feedrate_path_length": "mm",
    "feedrate_time_ratio": "-",  # constant-feed cycle time / optimized cycle time
    "feedrate_limit_ratio": "-",  # largest |axis value| / limit over v, a, j and the axes (1: at the limit)
    "feedrate_limits_violated": "-",  # 1 if a limit is exceeded by more than the tolerance, else 0
    "drive_axis_error_max": "mm",  # X, Y, Z
    "drive_rotary_error_max": "rad",  # A, C
    "drive_saturated_fraction": "-",  # share of control periods at the amplifier limit
    "drive_saturated": "-",  # 1 if any axis reaches its amplifier limit, else 0
    "drive_diverged": "-",
    "amplifier_limit": "V",
}


class FeedrateDriveConfig(_Strict):
    """Thesis Fig 3.13: the schedules through the SISO SMC drives (Table 5.1 plant, Table 5.2 gains) with the
    amplifier saturating at ``u_max,i = m_i A_i + c_i V_i + d_c,i`` (Table 3.1 A, V; :mod:`research.control._feed_tracking`)."""

    control_period_ms: float = Field(0.1, gt=0, le=1.0, description="control period [ms] (0.1: the printed Table 5.2 "
                                                                     "gains are unstable at the thesis' 1 ms)")
    friction: Literal["identified", "isolated_reversal"] = Field(
        "identified", description="Coulomb friction per axis: \"identified\" from the thesis' Fig 5.7 SISO peaks "
                                  "(research.control.identify_coulomb, a fixed point over path runs), or "
                                  "\"isolated_reversal\": its start, peak / (2 g) of one isolated reversal (no path run)")
    coulomb_V: list[float] | None = Field(None, min_length=5, max_length=5,
                                          description="Coulomb friction X Y Z A C [V] (overrides friction)")
    divergence_limit: float = Field(10.0, gt=0, description="axis error beyond which a run is flagged diverged "
                                                            "[mm or rad]")

    @model_validator(mode="after")
    def _friction(self):
        if self.coulomb_V is not None and any(v < 0 for v in self.coulomb_V):
            raise ValueError(f"coulomb_V = {self.coulomb_V} must be >= 0")
        return self


class FeedrateConfig(_Strict):
    """Thesis ch 3 (§3.3-3.6): optimized feed vs constant feeds along the ``[path]`` (5-axis kind)."""

    feed_mm_per_s: float = Field(150.0, ge=1.0, le=10_000.0, description="programmed feed cap F [mm/s] (eq 3.57; "
                                                                          "thesis §3.6: 150)")
    rotary_jerk_unit: Literal["rad", "deg"] = Field(
        "rad", description="unit of Table 3.1's A / C jerk 250 / 200 (printed deg/s^3, which needs 10 s to build up the "
                           "acceleration; read as rad/s^3 by default, research.optimal.table31_limits)")
    control_points: int = Field(276, ge=8, le=5000, description="feed B-spline control points n (thesis §3.6: 276 "
                                                                "on 300 mm)")
    checks_per_span: int = Field(4, ge=1, le=64, description="constraint points per knot span")
    refinements: int = Field(3, ge=0, le=10, description="passes doubling the check points where the dense check "
                                                         "finds a limit exceeded")
    tolerance: float = Field(2e-3, gt=0, lt=0.1, description="relative limit excess the dense check accepts [-]; "
                                                             "also the threshold of feedrate_limits_violated")
    constraint_form: Literal["per_axis", "combined"] = Field("per_axis", description="eq 3.41/3.46/3.53 (per axis) or "
                                                                                     "eq 3.43/3.49/3.56 (combined)")
    objective: Literal["time", "sum"] = Field("time", description="eq 3.30 (int ds / f) or eq 3.58 (max sum f_i)")
    sample_period_ms: float = Field(1.0, gt=0, le=10.0, description="sample period of the schedules' axis "
                                                                    "trajectories [ms]")
    constant_feeds_mm_per_s: list[float] = Field([15.0], max_length=8,
                                                 description="constant feeds to compare [mm/s] (thesis §3.6: 15; "
                                                             "Fig 3.13: 15 and 40)")
    envelope_points: int = Field(1500, ge=10, le=100_000, description="points in s of the Fig 3.10 axis-limit "
                                                                      "envelopes")
    drive: FeedrateDriveConfig | None = Field(None, description="Fig 3.13: the schedules through the SISO drives")

    @model_validator(mode="after")
    def _feeds(self):
        for i, f in enumerate(self.constant_feeds_mm_per_s):
            if not 1.0 <= f <= 10_000.0:
                raise ValueError(f"constant_feeds_mm_per_s[{i}] = {f:g} mm/s is outside 1 .. 10000 mm/s (the key is "
                                 "in mm/s: m/s or mm/min typed?)")
        labels = [constant_label(f) for f in self.constant_feeds_mm_per_s]
        if len(set(labels)) != len(labels):
            raise ValueError(f"constant_feeds_mm_per_s = {self.constant_feeds_mm_per_s} repeats a feed")
        return self


def constant_label(feed: float) -> str:
    """Results label of a constant-feed schedule: ``constant_15``, ``constant_12p5`` (no dot in a label)."""
    return "constant_" + f"{feed:g}".replace(".", "p")
