"""The ``[identified_contour]`` stage: thesis §6.5.3 / Table 6.3 / Fig 6.13 from an
:class:`~research.experiments.config_identified_contour.IdentifiedContourConfig` (:func:`research.contour.fig6_13`)."""

from __future__ import annotations

import numpy as np

from research.experiments.config_identified_contour import IdentifiedContourConfig

AXES = ("x", "y", "z", "a", "c")
METHODS = ("ls", "pso")


def identified_contour_stage(ic: IdentifiedContourConfig) -> tuple[dict[str, float], dict, dict[str, np.ndarray]]:
    """Identify the Table 6.3 machine and predict the eq 4.36 contour error with it.

    Returns:
        ``(scalars, details, arrays)``. Scalars: ``true_contour_error_max`` [mm]; per method ``ls`` / ``pso``
        ``<m>.predicted_contour_discrepancy_max`` [mm] (a method whose fits cannot be simulated is left out and named
        in ``details.excluded``), ``<m>.identified_stable`` (all axes, 0 / 1) and per axis ``<m>.identified_wn_hz.<a>``,
        ``.identified_zeta.<a>``, ``.identified_p_hz.<a>``, ``.identified_wn_error.<a>``, ``.identified_p_error.<a>``,
        ``.identified_stable.<a>``. Details: ``columns`` (Table 6.3 layout per axis: ``(wn [Hz], zeta, p [Hz], dc,
        stable)`` for actual / ls / pso / thesis_pso; dc in the eq 6.3 units of the axis, mm/s^2 or rad/s^2),
        ``excluded``. Arrays: ``identified_contour.t`` [s], ``.true`` and ``.<m>`` tip contour error [mm].
    """
    from research.contour import fig6_13
    from research.identification import PSOSettings

    ident, pred = fig6_13(seed=ic.seed, pso_settings=PSOSettings(particles=ic.pso_particles, iterations=ic.pso_iterations),
                          feed=ic.feed_mm_per_s, acceleration=ic.acceleration_mm_per_s2,
                          sample_period=ic.sample_period_ms * 1e-3)
    columns = {a: ident[a].columns() for a in AXES}
    scalars = {"true_contour_error_max": float(np.max(pred.true))}
    for m in METHODS:
        if m in pred.predicted:
            scalars[f"{m}.predicted_contour_discrepancy_max"] = float(pred.discrepancy(m).max())
        for a in AXES:
            wn, zeta, p, _, stable = columns[a][m]
            wn0, _, p0, _, _ = columns[a]["actual"]
            scalars |= {f"{m}.identified_wn_hz.{a}": float(wn), f"{m}.identified_zeta.{a}": float(zeta),
                        f"{m}.identified_p_hz.{a}": float(p), f"{m}.identified_wn_error.{a}": abs(wn / wn0 - 1),
                        f"{m}.identified_p_error.{a}": abs(p / p0 - 1), f"{m}.identified_stable.{a}": float(stable)}
        scalars[f"{m}.identified_stable"] = float(all(columns[a][m][4] for a in AXES))
    details = {"columns": {a: {k: [None if v is None else (bool(v) if isinstance(v, (bool, np.bool_)) else float(v))
                                   for v in col] for k, col in cols.items()} for a, cols in columns.items()},
               "excluded": dict(pred.excluded or {})}
    arrays = {"identified_contour.t": np.asarray(pred.t), "identified_contour.true": np.asarray(pred.true)}
    arrays |= {f"identified_contour.{m}": np.asarray(v) for m, v in pred.predicted.items()}
    return scalars, details, arrays
