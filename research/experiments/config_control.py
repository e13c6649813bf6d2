"""Schema of the ``[control]`` stage (issue 17): the thesis' ch 5 closed loop from a config.

The Fig 5.5 path (eq 4.36) runs through the Table 5.1 rigid-body drives and the A/C table-tilting
kinematics under either the SISO sliding-mode axis controllers (Table 5.2) or the 5-axis contour
controller (tool-tip controller of §5.2 with Table 5.3, orientation controller of §5.3 with the
coupling weights ``W = diag(wa, wc)``), optionally with feed-forward mirror passes on the setpoint
(:func:`research.control.tracking_mirror_passes`). Every gain defaults to the thesis' table; units are
in the key names or, where they differ between linear and rotary axes, in the description. The SISO
controller takes ``siso_*`` (X Y Z A C); the contour controller ``tip_*`` (Frenet directions) and ``rotary_*``
(A, C), and refuses ``siso_*``, which it would not use.

Several runs in one config (the thesis compares runs: SISO against contour controller, feeds, bandwidths,
weights W, mirror passes): ``[[control.cases]]``, each a ``label``, the keys that differ from the table
(:data:`CASE_KEYS`) and optionally ``ratio_to`` (labels whose metrics this case's are divided by). Each
case is the table with its keys replaced, validated again as a whole; the friction is identified once.
This is the smallest shape that keeps a figure's runs and their comparisons in one stored result; a
``[sweep]`` maps a grid instead and has no per-run labels or ratios.

Example:
    >>> ControlConfig(controller="siso", feed_mm_per_s=60.0).feed_mm_per_s
    60.0
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, ValidationError, create_model, model_validator

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
    "orientation_estimate_error_max": "rad",
    "diverged": "-",
}
#: ``<label>.<metric>_ratio.<other>``: a case's metric over the same metric of case ``<other>`` (``ratio_to``)
CONTROL_METRIC_UNITS |= {f"{k}_ratio": "-" for k in tuple(CONTROL_METRIC_UNITS) if k != "diverged"}


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
    rotary_bandwidth_rad_per_s: list[float] | None = _n(2, "contour controller: A, C surface bandwidth [rad/s] "
                                                           "(none: Table 5.3, 150 200)")
    rotary_Ks: list[float] | None = _n(2, "contour controller: A, C feedback gain [V s/rad] (none: Table 5.3, 0.5 1)")
    rotary_Gamma: list[float] | None = _n(2, "contour controller: A, C adaptation gain [V/rad] (none: Table 5.3, 3 3)")
    orientation_weights_per_s: list[float] = Field([0.0, 0.0], min_length=2, max_length=2,
                                                   description="orientation coupling W = diag(wa, wc) [1/s] "
                                                               "(Fig 5.10: 0, 3, 4, 5)")
    amplifier_limit_V: float | list[float] | None = Field(None, description="amplifier saturation |u| per axis [V] "
                                                                            "(none: unlimited)")
    mirror_passes: int = Field(0, ge=0, le=20, description="feed-forward mirror passes on the setpoint "
                                                          "(0: feedback only)")
    cases: list["ControlCase"] | None = Field(None, description="several runs in one config ([[control.cases]]: a "
                                                                  "label and the keys that differ from this table; "
                                                                  "none: one run of this table)")

    @model_validator(mode="after")
    def _consistent(self):
        if self.controller == "siso":
            for k in ("tip_bandwidth_rad_per_s", "tip_Ks", "tip_Gamma"):
                if getattr(self, k) is not None:
                    raise ValueError(f"{k} = {getattr(self, k)}: tip_* gains belong to controller = \"contour\" (thesis "
                                     f"Table 5.3: tangential, normal, binormal); the SISO controller takes siso_* "
                                     f"(Table 5.2: X Y Z A C)")
            for k in ("rotary_bandwidth_rad_per_s", "rotary_Ks", "rotary_Gamma"):
                if getattr(self, k) is not None:
                    raise ValueError(f"{k} = {getattr(self, k)}: rotary_* gains belong to controller = \"contour\" "
                                     f"(thesis Table 5.3, A and C); the SISO controller takes siso_* (Table 5.2: five "
                                     f"axes X Y Z A C, A and C the last two)")
        else:
            for k in ("siso_bandwidth_rad_per_s", "siso_Ks", "siso_Gamma"):
                if getattr(self, k) is not None:
                    raise ValueError(f"{k} = {getattr(self, k)}: controller = \"contour\" does not use the SISO gains "
                                     f"(thesis Table 5.2, X Y Z A C): its gains are Table 5.3's, the tool-tip controller's "
                                     f"per Frenet direction as tip_* and A, C as rotary_{k.removeprefix('siso_')}; "
                                     f"set controller = \"siso\" or drop {k}")
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
        if self.cases is not None:
            self.case_configs()  # every case, merged with this table, is a valid run
        return self

    def case_configs(self) -> dict[str, "ControlConfig"]:
        """``{label: ControlConfig}`` of the runs: this table alone (label ``""``) without ``cases``, else each
        case's keys over this table's.

        Raises:
            ValueError: duplicate labels, ``ratio_to`` naming an unknown label or the case itself, or a case whose
                merged table is invalid (the case and the key are named).
        """
        if self.cases is None:
            return {"": self}
        base = self.model_dump(exclude={"cases"}, exclude_unset=True)
        out = {}
        labels = [c.label for c in self.cases]
        for i, case in enumerate(self.cases):
            if case.label in out:
                raise ValueError(f"cases[{i}] = {case.label!r}: duplicate label")
            for other in case.ratio_to:
                if other not in labels or other == case.label:
                    raise ValueError(f"cases[{i}] = {case.label!r}: ratio_to {other!r} is not another case's label "
                                     f"(labels: {labels})")
            merged = base | case.model_dump(exclude={"label", "ratio_to"}, exclude_none=True)
            try:
                out[case.label] = ControlConfig.model_validate(merged)
            except ValidationError as e:
                what = "; ".join(f"key '{'.'.join(str(p) for p in err['loc']) or '(table)'}': "
                                 f"{err['msg'].removeprefix('Value error, ')}" for err in e.errors())
                raise ValueError(f"cases[{i}] = {case.label!r}: {what}") from None
        return out


#: keys of [control] a case may change (friction, control period and surface damping stay the table's: the
#: friction is identified once per config, at its period)
CASE_KEYS = ("controller", "feed_mm_per_s", "acceleration_mm_per_s2", "siso_bandwidth_rad_per_s", "siso_Ks",
             "siso_Gamma", "tip_bandwidth_rad_per_s", "tip_Ks", "tip_Gamma", "rotary_bandwidth_rad_per_s", "rotary_Ks",
             "rotary_Gamma", "orientation_weights_per_s", "amplifier_limit_V", "mirror_passes")

ControlCase = create_model(
    "ControlCase",
    __base__=_Strict,
    __doc__="One run of a [control] table with cases (``[[control.cases]]``): a label, the ratios to report and "
            "the keys that differ from the table (each validated again on the merged table).",
    label=(str, Field(..., pattern=r"^[a-z][a-z0-9_]*$", max_length=40,
                      description="name of the run: its scalars are <label>.<metric>, its arrays control.<label>.<name>")),
    ratio_to=(list[str], Field([], description="labels of other cases: <label>.<metric>_ratio.<other> = this run's "
                                               "metric / the other's [-]")),
    **{k: (ControlConfig.model_fields[k].annotation | None,
           Field(None, description=f"{ControlConfig.model_fields[k].description}; none: the [control] table's"))
       for k in CASE_KEYS},
)
ControlConfig.model_rebuild()
