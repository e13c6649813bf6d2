"""Schema of the ``[control]`` stage (issue 17): the thesis' ch 5 closed loop from a config.

The Fig 5.5 path (eq 4.36) runs through the Table 5.1 rigid-body drives and the A/C table-tilting
kinematics under either the SISO sliding-mode axis controllers (Table 5.2) or the 5-axis contour
controller (tool-tip controller of §5.2 with Table 5.3, orientation controller of §5.3 with the
coupling weights ``W = diag(wa, wc)``), optionally with feed-forward mirror passes on the setpoint
(:func:`research.control.tracking_mirror_passes`). Every gain defaults to the thesis' table; units are
in the key names or, where they differ between linear and rotary axes, in the description.

Example:
    >>> ControlConfig(controller="siso", feed_mm_per_s=60.0).feed_mm_per_s
    60.0
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from research.experiments.config_stages import _Strict


#: scalar metrics of the stage and their units (merged into ``config.METRIC_UNITS``)
CONTROL_METRIC_UNITS = {
    "tip_contour_error_max": "mm",
    "tip_contour_error_mean": "mm",
    "tip_estimate_error_max": "mm",
    "orientation_error_max": "rad",
    "orientation_error_mean": "rad",
    "axis_error_max": "mm",  # X, Y, Z
    "rotary_axis_error_max": "rad",  # A, C
    "control_voltage_max": "V",
    "diverged": "-",
}


def _n(n: int, what: str):
    return Field(None, min_length=n, max_length=n, description=what)


class ControlConfig(_Strict):
    """Thesis ch 5 closed-loop simulation on the Fig 5.5 path (:func:`research.control.run_case`)."""

    controller: Literal["siso", "contour"] = Field("contour", description="SISO SMC (Table 5.2) or the 5-axis contour "
                                                                          "controller (Table 5.3, eq 5.1-5.39)")
    feed_mm_per_s: float = Field(50.0, gt=0, description="cruise tool-tip feed [mm/s] (Fig 5.7: 50; Table 5.4: 50/60/80)")
    acceleration_mm_per_s2: float = Field(1500.0, gt=0, description="tip acc/dec of the cubic profile [mm/s^2] (§5.4)")
    control_period_ms: float = Field(0.1, gt=0, description="control period [ms] (0.1: the printed gains are unstable "
                                                            "at the thesis' 1 ms, see research.control._study)")
    coulomb_V: list[float] | None = _n(5, "Coulomb friction voltage per axis X Y Z A C [V] (none: identified from "
                                          "the Fig 5.7 peak SISO errors, research.control.identify_coulomb)")
    siso_bandwidth_rad_per_s: list[float] | None = _n(5, "SISO surface bandwidth lambda per axis X Y Z A C [rad/s] "
                                                         "(none: Table 5.2, 200 200 180 150 200)")
    siso_Ks: list[float] | None = _n(5, "SISO feedback gain Ks per axis [V s/mm, V s/rad] (none: Table 5.2, 7 5 5 0.5 1)")
    siso_Gamma: list[float] | None = _n(5, "SISO adaptation gain per axis [V/mm, V/rad] (none: Table 5.2, 25 30 15 3 3)")
    tip_bandwidth_rad_per_s: list[float] | None = _n(3, "tool-tip wn tangent / normal / binormal [rad/s] "
                                                        "(none: Table 5.3, 100 230 230; Table 5.5 varies it)")
    tip_Ks: list[float] | None = _n(3, "tool-tip Ks per Frenet direction [V s/mm] (none: Table 5.3, 2 4 4)")
    tip_Gamma: list[float] | None = _n(3, "tool-tip Gamma per Frenet direction [V/mm] (none: Table 5.3, 10 20 20)")
    tip_damping: float = Field(1.0, gt=0, description="damping of the tip sliding surface (Table 5.3 prints none; "
                                                      "1: the double root at wn)")
    orientation_weights_per_s: list[float] = Field([0.0, 0.0], min_length=2, max_length=2,
                                                   description="orientation coupling W = diag(wa, wc) [1/s] "
                                                               "(Fig 5.10: 0, 3, 4, 5)")
    amplifier_limit_V: float | list[float] | None = Field(None, description="amplifier saturation |u| per axis [V] "
                                                                            "(none: unlimited)")
    mirror_passes: int = Field(0, ge=0, le=20, description="feed-forward mirror passes on the setpoint "
                                                          "(0: feedback only)")

    @model_validator(mode="after")
    def _consistent(self):
        if self.controller == "siso" and any(getattr(self, k) is not None for k in ("tip_bandwidth_rad_per_s", "tip_Ks", "tip_Gamma")):
            raise ValueError("tip_* gains belong to controller = \"contour\"; the SISO controller takes siso_*")
        if self.controller == "siso" and any(self.orientation_weights_per_s):
            raise ValueError("orientation_weights_per_s belongs to controller = \"contour\" (the SISO loops are uncoupled)")
        if any(w < 0 for w in self.orientation_weights_per_s):
            raise ValueError(f"orientation_weights_per_s = {self.orientation_weights_per_s}: W must be >= 0 (eq 5.22)")
        if self.amplifier_limit_V is not None and self.mirror_passes > 0:
            raise ValueError("amplifier_limit_V with mirror_passes > 0: the mirror passes run without saturation; "
                             "use one or the other")
        limit = self.amplifier_limit_V
        if limit is not None:
            values = limit if isinstance(limit, list) else [limit]
            if len(values) not in (1, 5) or not all(v > 0 for v in values):
                raise ValueError(f"amplifier_limit_V = {limit}: one positive value, or five (X Y Z A C)")
        for key in ("coulomb_V",):
            v = getattr(self, key)
            if v is not None and any(x < 0 for x in v):
                raise ValueError(f"{key} = {v} must be >= 0")
        return self
