"""Schema of the 5-axis kind of the ``[path]`` table (issue 16 item 1): a tool path in tool tip and tool axis,
as a quintic pose B-spline (:class:`~research.paths.pose_spline.PoseSpline`) mapped to the axes ``x, y, z, a, c``
of the A/C table-tilting machine by the inverse kinematics (:mod:`research.paths.kinematics5`, eq 3.21, 4.6).

- ``name = "eq436"``: the thesis' eq 4.36 test path (tip length 273.87 mm, §4.5 / Fig 4.5);
- ``name = "blade_flank"``: the public 300 mm blade-flank stand-in for the thesis' impeller path (Fig 3.8; its
  CL data are not public), :func:`research.paths.five_axis_library.blade_flank_path`.

Example::

    [path]
    kind = "five_axis"
    name = "blade_flank"
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from research.experiments.config_stages import _Strict

#: the named 5-axis paths of the ``[path]`` table's five-axis kind
FIVE_AXIS_PATHS = ("blade_flank", "eq436")


class FiveAxisPathConfig(_Strict):
    """A named 5-axis tool path (tool tip [mm] and tool axis), for the ``[feedrate]`` stage."""

    kind: Literal["five_axis"] = Field(..., description="the 5-axis path kind (tip + orientation pose B-spline)")
    name: Literal[FIVE_AXIS_PATHS] = Field("blade_flank", description=f"one of {FIVE_AXIS_PATHS}")
    n_samples: int | None = Field(None, ge=50, le=100_000,
                                  description="poses the quintic B-spline interpolates (none: 601 for blade_flank, "
                                              "801 for eq436, where the eq 4.36 tip length is within 1e-9 mm)")
    length_mm: float | None = Field(None, gt=0, le=10_000,
                                    description="tip path length [mm], blade_flank only (none: 300, the thesis' "
                                                "impeller path, §3.6)")

    @model_validator(mode="after")
    def _length_only_for_the_blade(self):
        if self.length_mm is not None and self.name != "blade_flank":
            raise ValueError(f"length_mm = {self.length_mm:g} applies to name = \"blade_flank\" only (the eq 4.36 "
                             "path's length is fixed by its equation, 273.87 mm)")
        return self

    def build(self):
        """The :class:`~research.paths.pose_spline.PoseSpline` the table describes."""
        from research.paths.five_axis_library import BLADE_LENGTH, blade_flank_path, eq436_spline

        if self.name == "eq436":
            return eq436_spline() if self.n_samples is None else eq436_spline(self.n_samples)
        return blade_flank_path(601 if self.n_samples is None else self.n_samples,
                                BLADE_LENGTH if self.length_mm is None else self.length_mm)
