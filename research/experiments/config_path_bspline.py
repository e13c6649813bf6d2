"""Schema of the B-spline path kind of ``[path]`` (``[path.bspline]``): a B-spline tool path given by its
control points, knot vector and degree (:class:`research.paths.bspline.BSplinePath`), e.g. the planar cubic
B-spline of Prévost, Lavernhe, Lartigue (HSM 2012) Application 1, Fig 4. The G01 interpolators run on a dense
polyline through the curve (chord error ``chord_error_um``); the contour-error and CEC stages measure against
the curve itself (:meth:`BSplinePathConfig.curve`).

Example (``experiments/figures/prevost2012_fig5_cec_bspline.toml``)::

    [path.bspline]
    control_points_mm = [[-100, 0], [-50, 0], [-50, 50], [0, 50], [50, 0], [50, -50], [-100, -50]]
    knots = [0, 0, 0, 0, 0.3333333333333333, 0.5, 0.6666666666666666, 1, 1, 1, 1]
    degree = 3
"""

from __future__ import annotations

from pydantic import Field, StrictFloat, StrictInt, model_validator

from research.experiments.config_stages import _Strict


class BSplinePathConfig(_Strict):
    """A B-spline ``C(u) = sum_i N_{i,p}(u) P_i`` on ``[U_p, U_n]`` (Piegl-Tiller notation, as the paper's Fig 4)."""

    control_points_mm: list[list[StrictFloat | StrictInt]] = Field(
        ..., min_length=2, description="control points P_i [mm], 1 to 3 coordinates each, at least degree + 1 of them")
    knots: list[StrictFloat | StrictInt] = Field(..., description="knot vector U [-], n + p + 1 non-decreasing values")
    degree: int = Field(3, ge=1, description="degree p [-] (3: cubic)")
    chord_error_um: float = Field(0.1, gt=0, description="chord error of the polyline the interpolators run on [um] "
                                                         "(sagitta bound h^2 kappa_max / 8)")

    @model_validator(mode="after")
    def _a_curve(self):
        """The curve is built once at load, so a wrong shape or knot vector fails with the spline's own reason."""
        self.curve()
        return self

    def curve(self):
        """The :class:`~research.paths.bspline.BSplinePath` [mm].

        Raises:
            ValueError: the control points, knots or degree do not make a B-spline (the reason of
                :class:`~research.paths.bspline.BSplinePath`; pydantic names the key).
        """
        import numpy as np

        from research.errors import PathError
        from research.paths.bspline import BSplinePath

        dims = {len(p) for p in self.control_points_mm}
        if len(dims) != 1:
            raise ValueError(f"control_points_mm: every point needs the same number of coordinates, got {sorted(dims)}")
        try:
            return BSplinePath(np.asarray(self.control_points_mm, dtype=np.float64),
                               np.asarray(self.knots, dtype=np.float64), self.degree)
        except PathError as e:
            raise ValueError(str(e)) from None

    def polyline(self):
        """The :class:`~research.paths.Polyline` through the curve, equally spaced in arc length, within
        ``chord_error_um`` of it (:meth:`~research.paths.bspline.BSplinePath.to_polyline`)."""
        return self.curve().to_polyline(self.chord_error_um * 1e-3)
