"""The ``[identification_ch6]`` stage (thesis ch 6 §6.5): identification methods compared on the Table 6.1 virtual
drive (Fig 6.7 FRFs, Fig 6.8 PSO convergence) and, optionally, the real EMPS axis (fit on its first
``emps_split_s``, free-run validation on the rest). Calls :mod:`research.identification`; the schema is
:class:`~research.experiments.config_identification_ch6.IdentificationCh6Config`."""

from __future__ import annotations

from pathlib import Path

import numpy as np

HZ = 2 * np.pi  # rad/s per Hz
SETTLE_BAND = 0.01  # PSO convergence: within 1 % of the final value (pso_settle_iteration)


def _poles(model) -> dict[str, float]:
    wn, zeta, p = model.pole_parameters()
    return {"identified_wn_hz": float(wn) / HZ, "identified_zeta": float(zeta), "identified_p_hz": float(p) / HZ,
            "identified_dc": float(model.dc)}


def _fit(method: str, log, prob, c):
    from research.identification import PSOSettings, RegressionOptions, bounded_fit, least_squares, particle_swarm

    if method == "ls_thesis":
        return least_squares(log, RegressionOptions.thesis())
    if method == "ls":
        return least_squares(prob.regression)
    if method == "pso":
        return particle_swarm(prob, seed=c.pso_seed, settings=PSOSettings(swarms=c.pso_swarms))
    return bounded_fit(prob)


def settle_iteration(history: np.ndarray, band: float = SETTLE_BAND) -> int:
    """First iteration (1-based) from which every pole parameter of a PSO gbest ``history`` (rows: iteration;
    columns: objective, wn, zeta, p) stays within ``band`` (relative) of its final value."""
    h = np.asarray(history)[:, 1:]
    outside = np.any(np.abs(h - h[-1]) > band * np.abs(h[-1]), axis=1)
    return int(np.flatnonzero(outside)[-1] + 2) if outside.any() else 1


def identification_ch6_stage(c, base: Path) -> tuple[dict, dict, dict]:
    """Run ``c`` (paths relative to ``base``).

    Returns:
        ``(scalars, details, arrays)``: per method and for the truth (``actual.``) ``identified_wn_hz``,
        ``identified_zeta``, ``identified_p_hz`` [Hz, -], ``identified_dc`` [mm/s^2]; per method ``wn_error``,
        ``zeta_error``, ``p_error``, ``dc_error`` (relative to the truth) and ``frf_error``; with PSO
        ``pso_settle_iteration`` and (with LS) ``pso_ls_difference``; with EMPS ``emps.<vp|oe>.emps_fit_estimation``,
        ``emps_fit_validation`` [%], ``emps_rms_validation`` [mm]. Arrays: ``ident.f`` [Hz],
        ``ident.<actual|method>.tracking`` / ``.disturbance`` (complex FRFs), ``ident.pso.history`` (objective, wn,
        zeta, p [rad/s] per iteration); EMPS ``emps.t``, ``emps.reference``, ``emps.actual``, ``emps.<vp|oe>.simulated``
        [s, mm].
    """
    from research.drives import ClosedLoopModel, Encoder, frequency_response, virtual_drive
    from research.identification import ProjectedProblem, build_regression, identification_program, synthetic_log

    base_model = virtual_drive(c.truth)
    truth = ClosedLoopModel(base_model.a1, base_model.a2, base_model.a3, base_model.b0, base_model.b1, base_model.b2,
                            c.friction_mm_per_s2)
    ref = identification_program(0, n_moves=c.n_moves).trajectory()
    log = synthetic_log(truth, ref, encoder=Encoder(c.resolution_um * 1e-3, c.noise_um * 1e-3), seed=c.seed)
    prob = ProjectedProblem.from_regression(build_regression(log))
    f = np.logspace(np.log10(c.start_hz), np.log10(c.stop_hz), c.num)
    true_fr = frequency_response(truth, f)
    true = _poles(truth)
    scalars = {f"actual.{k}": v for k, v in true.items()}
    arrays = {"ident.f": f, "ident.actual.tracking": np.asarray(true_fr.tracking),
              "ident.actual.disturbance": np.asarray(true_fr.disturbance)}
    low = f <= c.agreement_hz
    fits = {}
    for m in c.methods:
        fits[m] = fit = _fit(m, log, prob, c)
        got = _poles(fit)
        fr = frequency_response(fit.model(), f)
        track = np.asarray(fr.tracking)
        scalars |= {f"{m}.{k}": v for k, v in got.items()}
        scalars |= {f"{m}.{k.split('_')[1]}_error": abs(got[k] - true[k]) / abs(true[k]) for k in true}
        scalars[f"{m}.frf_error"] = float(np.max(np.abs(track - arrays["ident.actual.tracking"])[low]
                                                 / np.abs(arrays["ident.actual.tracking"][low])))
        arrays |= {f"ident.{m}.tracking": track, f"ident.{m}.disturbance": np.asarray(fr.disturbance)}
    if "pso" in fits:
        arrays["ident.pso.history"] = np.asarray(fits["pso"].history)
        scalars["pso_settle_iteration"] = float(settle_iteration(fits["pso"].history))
        if "ls" in fits:
            keys = ("identified_wn_hz", "identified_zeta", "identified_p_hz")
            scalars["pso_ls_difference"] = max(abs(scalars[f"pso.{k}"] - scalars[f"ls.{k}"]) / abs(scalars[f"ls.{k}"])
                                               for k in keys)
    details = {"methods": list(c.methods), "samples": int(log.n_samples)}
    if c.emps_log_file is not None:
        from research.identification import identify_emps

        vp, oe = identify_emps(base / c.emps_log_file, split_s=c.emps_split_s, max_steps=c.emps_max_steps)
        elog = vp.log
        arrays |= {"emps.t": np.asarray(elog.t), "emps.reference": np.asarray(elog.reference),
                   "emps.actual": np.asarray(elog.actual)}
        for name, rep in (("vp", vp), ("oe", oe)):
            scalars |= {f"emps.{name}.emps_fit_estimation": float(rep.fits["estimation"]["tracking_error"]),
                        f"emps.{name}.emps_fit_validation": float(rep.fits["validation"]["tracking_error"]),
                        f"emps.{name}.emps_rms_validation": float(rep.rms_error_um["validation"]) * 1e-3}
            arrays[f"emps.{name}.simulated"] = np.asarray(rep.simulated)
        details["emps"] = {"split_s": c.emps_split_s, "samples": int(elog.n_samples)}
    return scalars, details, arrays
