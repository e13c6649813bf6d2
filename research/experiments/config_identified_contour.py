"""Schema of the ``[identified_contour]`` stage: thesis §6.5.3 / Table 6.3 / Fig 6.13 from a config.

Every axis of the Table 6.3 virtual 5-axis machine (P-PI, eq 6.3 "Actual" models) is identified by LS (eq 6.12)
and PSO (§6.4) on the §6.5 program, and the identified machines predict the exact tool-tip contour error of the
eq 4.36 spiral against the true machine (:func:`research.contour.fig6_13`; choices in
:mod:`research.contour._identified_machine`).

Example::

    [identified_contour]
    feed_mm_per_s = 75.0
"""

from __future__ import annotations

from pydantic import Field

from research.experiments.config_stages import _Strict

#: scalar metrics of the stage and their units (merged into ``config.METRIC_UNITS``); per method (``ls``, ``pso``)
#: and, for the estimates, per axis ``.x`` ... ``.c``
IDENTIFIED_CONTOUR_METRIC_UNITS = {
    "true_contour_error_max": "mm",
    "predicted_contour_discrepancy_max": "mm",  # max |predicted - true| tip contour error
    "identified_wn_hz": "Hz",
    "identified_zeta": "-",
    "identified_p_hz": "Hz",
    "identified_wn_error": "-",  # |estimate - actual| / actual
    "identified_p_error": "-",
    "identified_stable": "-",  # 1 if every axis' fit is stable (a single axis: that axis)
}


class IdentifiedContourConfig(_Strict):
    """Thesis §6.5.3: identify the Table 6.3 machine axis by axis, predict the Fig 6.13 contour error."""

    seed: int = Field(0, ge=0, description="seed of the §6.5 program and of the swarm")
    feed_mm_per_s: float = Field(75.0, ge=1.0, le=10_000.0, description="tip feed of the eq 4.36 run [mm/s] "
                                                                          "(§6.5.3: 75)")
    acceleration_mm_per_s2: float = Field(1500.0, gt=0, description="tip acceleration [mm/s^2] (§6.5.3: 1500)")
    sample_period_ms: float = Field(1.0, gt=0, le=10.0, description="sample period of the prediction [ms]")
    pso_particles: int = Field(200, ge=2, le=10_000, description="PSO swarm size (§6.5: 200)")
    pso_iterations: int = Field(100, ge=1, le=10_000, description="PSO iterations (§6.5: 100)")
