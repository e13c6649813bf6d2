"""Schema of the ``[identification_ch6]`` stage (thesis ch 6, §6.5.1-6.5.2): the Table 6.1 P-PI virtual drive
identified by several methods on one synthetic log of the §6.5 program (true model known), their FRFs (Fig 6.7),
the PSO convergence (Fig 6.8), and optionally the real EMPS ball-screw axis fitted on its first seconds and
validated on the rest. Units are in the key names; every default is in its ``Field``."""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from research.experiments.config_stages import _Strict

#: the identification methods compared: eq 6.9 as the thesis prints it, LS with the trapezoid regressor and
#: prefilter (research.identification.least_squares defaults), PSO (§6.4) and the optimistix bounded fit
IDENTIFICATION_METHODS = ("ls_thesis", "ls", "pso", "optimistix")

#: metrics of the stage (units of :data:`~research.experiments.config.METRIC_UNITS`)
IDENTIFICATION_CH6_METRIC_UNITS = {
    "identified_wn_hz": "Hz",  # eq 6.13 poles of an identified (or the true) model
    "identified_zeta": "-",
    "identified_p_hz": "Hz",
    "identified_dc": "mm/s^2",  # eq 6.3 friction term
    "frf_error": "-",  # max |G_fit - G_true| / |G_true| of x/x_r up to agreement_hz
    "pso_settle_iteration": "-",  # first PSO iteration after which wn, zeta, p stay within 1 % of their final values
    "pso_ls_difference": "-",  # max relative difference of the PSO and LS poles (wn, zeta, p)
    "emps_fit_estimation": "%",  # tracking-error fit (100 (1 - |e - e_sim| / |e - mean e|)) on the estimation window
    "emps_fit_validation": "%",  # the same on the held-out window
    "emps_rms_validation": "mm",  # RMS of x - x_sim on the held-out window
}


class IdentificationCh6Config(_Strict):
    """Virtual drive of thesis Table 6.1 (its coefficients, friction ``friction_mm_per_s2``) run on ``n_moves``
    moves of the §6.5 program, measured by an encoder of ``resolution_um`` (plus ``noise_um``), identified by each of
    ``methods``; with ``emps_log_file``, the EMPS log fitted by bounded variable projection and output error."""

    truth: Literal["sencer2009_table6_1"] = Field("sencer2009_table6_1", description="the true closed-loop drive")
    friction_mm_per_s2: float = Field(300.0, ge=0, description="eq 6.3 friction dc of the true drive [mm/s^2] (the "
                                                               "thesis prints it only as 2.6815 N m; research."
                                                               "identification.ASSUMED_FRICTION)")
    n_moves: int = Field(70, ge=1, description="moves of the §6.5 program (thesis: 70)")
    resolution_um: float = Field(0.05, ge=0, description="encoder resolution [um] (0.05 um: the EMPS benchmark's)")
    noise_um: float = Field(0.0, ge=0, description="encoder noise standard deviation [um]")
    seed: int = Field(1, ge=0, description="seed of the noise (the program is seed 0, the thesis' one program)")
    methods: list[Literal[IDENTIFICATION_METHODS]] = Field(
        ["ls_thesis", "ls", "pso"], min_length=1, description=f"methods compared, of {IDENTIFICATION_METHODS}")
    pso_swarms: int = Field(16, ge=1, description="independent PSO swarms, the best kept (§6.4; 200 particles, "
                                                  "100 iterations each, research.identification.PSOSettings)")
    pso_seed: int = Field(0, ge=0, description="PSO seed")
    start_hz: float = Field(1.0, gt=0, description="FRF start [Hz] (Fig 6.7: 1 Hz)")
    stop_hz: float = Field(100.0, gt=0, description="FRF stop [Hz] (Fig 6.7: 100 Hz)")
    num: int = Field(300, ge=2, description="FRF frequencies, log spaced")
    agreement_hz: float = Field(30.0, gt=0, description="upper end of the FRF comparison [Hz] (§6.5.1: 'good agreement "
                                                        "up to the frequency range 30 Hz')")
    emps_log_file: str | None = Field(None, description="EMPS estimation log (.mat, relative to the config file), "
                                                        "e.g. ../../../shared/data/emps/emps_estimation_first15s.mat")
    emps_split_s: float = Field(12.0, gt=0, description="EMPS: fit on t < split, validate on the rest [s]")
    emps_max_steps: int = Field(20, ge=1, description="EMPS: output-error solver steps")

    @model_validator(mode="after")
    def _ranges(self):
        if not self.start_hz < self.agreement_hz <= self.stop_hz:
            raise ValueError(f"agreement_hz = {self.agreement_hz:g} must lie in (start_hz, stop_hz] = "
                             f"({self.start_hz:g}, {self.stop_hz:g}] Hz")
        if len(set(self.methods)) != len(self.methods):
            raise ValueError(f"methods = {self.methods} repeats a method")
        return self
