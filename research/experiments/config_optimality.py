"""Schema of the ``[optimality]`` stage: FIR overlap (Sencer 2015, plain and holding the limits) against the
time-optimal OCP in the same tolerance tube on the optimality study's paths (:mod:`research.experiments.optimality`,
whose full study, with the S-curve, the geometric blend and the vibration-aware OCP, stays the command
``python -m research.experiments.optimality``). Units are in the key names; every default is in its ``Field``."""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from research.experiments.config_stages import _Strict

#: the study's paths (research.experiments.optimality.STUDY_PATHS; cam30 is its seeded 30-segment CAM-like path)
OPTIMALITY_PATHS = ("corner90", "diamond", "zigzag", "cam30")

#: metrics of the stage, per ``<path>.<convention>.`` (units of :data:`~research.experiments.config.METRIC_UNITS`)
OPTIMALITY_METRIC_UNITS = {
    "fir_cycle_time": "s",  # plain FIR overlap (the paper's planner)
    "fir_held_cycle_time": "s",  # FIR overlap holding the convention's limits
    "ocp_cycle_time": "s",  # converged time-optimal OCP
    "fir_ocp_ratio": "-",
    "fir_held_ocp_ratio": "-",
    "fir_closed_form_gap": "s",  # plain FIR: |T_FIR - (sum L_k / F_k + T_d + sum (T_d - T_k))|, Sencer 2015 eq 5/11
    "ocp_bound_ratio": "-",  # T_OCP / T_lower (the corner-cut length over F)
    "ocp_converged": "-",  # 1 when the grid refinement met rel_change
}


class OptimalityConfig(_Strict):
    """FIR (plain, limits held) against the converged time-optimal OCP at the study's setting (Sencer 2015 §4:
    F = 250 mm/s, eps = 500 um, T = 148 / 89 ms), under each limit convention of
    :func:`research.experiments.optimality.study_limits` (``a``: the FIR's own per-axis peaks; ``b``: its
    nominal envelope ``v = F, a = F / T1, j = F / (T1 T2)``)."""

    paths: list[Literal[OPTIMALITY_PATHS]] = Field(["corner90", "diamond"], min_length=1,
                                                   description=f"study paths, of {OPTIMALITY_PATHS}")
    conventions: list[Literal["a", "b"]] = Field(["a", "b"], min_length=1, description="limit conventions")
    feed_mm_per_s: float = Field(250.0, gt=0, description="commanded feed F and OCP path-speed bound [mm/s]")
    delays_ms: list[float] = Field([148.0, 89.0], min_length=1, description="FIR delays T_i [ms]")
    tolerance_um: float = Field(500.0, gt=0, description="cornering tolerance / OCP tube radius epsilon [um]")
    start_intervals: int = Field(16, ge=3, description="OCP jerk intervals per segment of the first solve")
    rel_change_percent: float = Field(0.1, gt=0, description="OCP grid refined x1.5 until T changes by less [%]")
    max_intervals: int = Field(128, ge=3, description="largest OCP intervals per segment")
    sample_period_ms: float = Field(1.0, gt=0, description="sample period of the stored trajectories [ms]")

    @model_validator(mode="after")
    def _unique(self):
        for key in ("paths", "conventions"):
            v = getattr(self, key)
            if len(set(v)) != len(v):
                raise ValueError(f"{key} = {v} repeats an entry")
        bad = [d for d in self.delays_ms if not d >= self.sample_period_ms]
        if bad:
            raise ValueError(f"delays_ms = {self.delays_ms}: {bad[0]:g} ms is below sample_period_ms = "
                             f"{self.sample_period_ms:g} ms (a delay in seconds?)")
        return self
