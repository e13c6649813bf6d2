"""Schema of the config stages beyond the FIR planner (issue 16 item 1): axis limits, the S-curve,
geometric-blend and sigmoid interpolators, a drive given by its eq 6.3 parameters, the ``contour``
stage (exact contour error and the thesis' estimators) and the ``compensation`` stage (CEC, Prévost
2012). Units are in the key names; every default is in its ``Field``.

:mod:`research.experiments.config` assembles them into :class:`~research.experiments.config.ExperimentConfig`.
"""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

#: what an envelope default means: the nominal limits of an FIR with these delays (Sencer 2015 §2.1,
#: ``v = F, a = F/T1, j = F/(T1 T2)``), the paper's §4 filters [ms]
PAPER_DELAYS_MS = [148.0, 89.0]


class _Strict(BaseModel):
    """Base of every table: unknown keys refused, no coercion, finite numbers only."""

    model_config = ConfigDict(extra="forbid", frozen=True, strict=True, allow_inf_nan=False)


class LimitsConfig(_Strict):
    """Per-axis velocity / acceleration / jerk bounds (:class:`research.limits.AxisLimits`); one value
    for every axis, or one per axis of the path."""

    velocity_mm_per_s: float | list[float] = Field(..., description="|q'| bound per axis [mm/s]")
    acceleration_mm_per_s2: float | list[float] = Field(..., description="|q''| bound per axis [mm/s^2]")
    jerk_mm_per_s3: float | list[float] | None = Field(None, description="|q'''| bound per axis [mm/s^3] (none: unbounded)")

    @model_validator(mode="after")
    def _positive(self):
        for key in ("velocity_mm_per_s", "acceleration_mm_per_s2", "jerk_mm_per_s3"):
            value = getattr(self, key)
            values = [] if value is None else value if isinstance(value, list) else [value]
            if isinstance(value, list) and not value:
                raise ValueError(f"{key} = [] is empty; give one value, or one per axis")
            bad = [v for v in values if not v > 0]
            if bad:
                raise ValueError(f"{key} = {value} must be > 0")
        return self

    def axis_limits(self, n_axes: int):
        """The :class:`~research.limits.AxisLimits` for ``n_axes`` axes [mm, s].

        Raises:
            ConfigError: a per-axis list whose length is not ``n_axes``.
        """
        import numpy as np

        from research.errors import ConfigError
        from research.limits import AxisLimits

        def per_axis(key, value):
            v = np.atleast_1d(np.asarray(np.inf if value is None else value, dtype=np.float64))
            if v.size not in (1, n_axes):
                raise ConfigError(f"key 'limits.{key}': {v.size} values for a path with {n_axes} axes; give one, or one per axis")
            return np.broadcast_to(v, (n_axes,))

        return AxisLimits(per_axis("velocity_mm_per_s", self.velocity_mm_per_s),
                          per_axis("acceleration_mm_per_s2", self.acceleration_mm_per_s2),
                          per_axis("jerk_mm_per_s3", self.jerk_mm_per_s3))


class SCurveConfig(_Strict):
    """Jerk-limited S-curve with an exact stop at every vertex (:func:`research.interpolators.scurve_interpolate`),
    under ``limits`` or, without them, the nominal envelope of an FIR with ``envelope_delays_ms``."""

    kind: Literal["scurve"]
    label: str | None = Field(None, description="name in results (default: kind)")
    feed_mm_per_s: float = Field(250.0, gt=0, description="commanded feed F [mm/s]")
    limits: LimitsConfig | None = Field(None, description="axis limits (default: the FIR envelope of envelope_delays_ms)")
    envelope_delays_ms: list[float] = Field(PAPER_DELAYS_MS, min_length=1, description="FIR delays setting the default limits [ms]")
    sample_period_ms: float = Field(1.0, gt=0, description="interpolation period Ts [ms]")


class BlendConfig(_Strict):
    """Geometric corner smoothing within ``tolerance_um`` (the Sencer 2015 Fig 6 baseline,
    :func:`research.interpolators.blend_interpolate`), limits as for the S-curve."""

    kind: Literal["blend"]
    label: str | None = Field(None, description="name in results (default: kind)")
    feed_mm_per_s: float = Field(250.0, gt=0, description="commanded feed F [mm/s]")
    tolerance_um: float = Field(500.0, gt=0, description="corner deviation epsilon [um]")
    limits: LimitsConfig | None = Field(None, description="axis limits (default: the FIR envelope of envelope_delays_ms)")
    limits_from: str | None = Field(None, description="label of an earlier interpolator of the config whose own per-axis "
                                                      "peak |v|, |a|, |j| are the limits (Sencer 2015 Fig 6: the blend "
                                                      "held to the FIR's peaks); not with limits")
    envelope_delays_ms: list[float] = Field(PAPER_DELAYS_MS, min_length=1, description="FIR delays setting the default limits [ms]")
    sample_period_ms: float = Field(1.0, gt=0, description="interpolation period Ts [ms]")


class SigmoidConfig(_Strict):
    """DiMarco 2015 sigmoid (``order = 3``, eq 2) or exponential (``order = 1``) interpolator: each segment
    a rest-to-rest move ``m t + A sin(w t)`` blended in and out (:func:`research.interpolators.mtp_motion`),
    the moves one after the other. Defaults: DiMarco's MTP experiment (§4: m = 10 mm/s on a 20 mm line)
    without the modulation (A = 0)."""

    kind: Literal["sigmoid"]
    label: str | None = Field(None, description="name in results (default: kind)")
    feed_mm_per_s: float = Field(10.0, gt=0, description="nominal feed m [mm/s]")
    acceleration_mm_per_s2: float = Field(250.0, gt=0, description="acceleration limit a_max [mm/s^2]")
    jerk_mm_per_s3: float | None = Field(None, gt=0, description="jerk limit [mm/s^3] (none: unbounded)")
    amplitude_mm: float = Field(0.0, ge=0, description="modulation amplitude A [mm] (0: plain moves)")
    frequency_hz: float = Field(0.0, ge=0, description="modulation frequency [Hz] (needed when A > 0)")
    order: Literal[1, 2, 3] = Field(3, description="blend exponent: 3 sigmoid (eq 2), 1 exponential")
    sample_period_ms: float = Field(1.0, gt=0, description="interpolation period Ts [ms]")

    @model_validator(mode="after")
    def _modulated(self):
        if self.amplitude_mm > 0 and not self.frequency_hz > 0:
            raise ValueError(f"frequency_hz = {self.frequency_hz:g} Hz: a modulation (amplitude_mm > 0) needs a frequency > 0")
        return self


class ClosedLoopConfig(_Strict):
    """An axis drive given by its thesis eq 6.3 parameters (every axis the same): the poles either as
    coefficients (``a1_per_s, a2_per_s2, a3_per_s3``) or as ``natural_frequency_hz, damping,
    real_pole_hz`` (eq 6.13), the zeros as ``b0, b1_per_s, b2_per_s2``, and the Coulomb friction."""

    a1_per_s: float | None = Field(None, description="a1 of eq 6.3 [1/s]")
    a2_per_s2: float | None = Field(None, description="a2 of eq 6.3 [1/s^2]")
    a3_per_s3: float | None = Field(None, description="a3 of eq 6.3 [1/s^3]")
    natural_frequency_hz: float | None = Field(None, gt=0, description="wn of the complex pole pair [Hz] (eq 6.13)")
    damping: float | None = Field(None, gt=0, description="zeta of the pair [-] (eq 6.13)")
    real_pole_hz: float | None = Field(None, gt=0, description="real pole p [Hz] (eq 6.13)")
    b0: float = Field(0.0, description="b0 of eq 6.3 [-]")
    b1_per_s: float = Field(0.0, description="b1 of eq 6.3 [1/s]")
    b2_per_s2: float = Field(0.0, description="b2 of eq 6.3 [1/s^2]")
    dc_mm_per_s2: float = Field(0.0, ge=0, description="average Coulomb friction d_c [mm/s^2] (eq 6.2)")

    @model_validator(mode="after")
    def _one_form(self):
        n_coeffs = sum(v is not None for v in (self.a1_per_s, self.a2_per_s2, self.a3_per_s3))
        n_poles = sum(v is not None for v in (self.natural_frequency_hz, self.damping, self.real_pole_hz))
        if (n_coeffs, n_poles) not in ((3, 0), (0, 3)):
            raise ValueError("give the poles either as a1_per_s, a2_per_s2, a3_per_s3 or as natural_frequency_hz, "
                             f"damping, real_pole_hz (all three of one form, none of the other; got {n_coeffs} and {n_poles})")
        return self

    def model(self):
        """The :class:`~research.drives.ClosedLoopModel` [mm, s]."""
        import numpy as np

        from research.drives import ClosedLoopModel

        if self.a1_per_s is not None:
            return ClosedLoopModel(self.a1_per_s, self.a2_per_s2, self.a3_per_s3, self.b0, self.b1_per_s, self.b2_per_s2,
                                   self.dc_mm_per_s2)
        hz = 2 * np.pi
        return ClosedLoopModel.from_poles(self.natural_frequency_hz * hz, self.damping, self.real_pole_hz * hz,
                                          self.b0, self.b1_per_s, self.b2_per_s2, self.dc_mm_per_s2)


class FrequencyResponseConfig(_Strict):
    """Frequency responses of the drive (thesis eq 6.1: tracking ``x/x_r`` and disturbance ``x/w``) on
    ``num`` log-spaced frequencies, with its poles (eq 6.13) and tracking bandwidth (-3 dB)."""

    start_hz: float = Field(1.0, gt=0, description="lowest frequency [Hz] (thesis Fig 6.7: 1 Hz)")
    stop_hz: float = Field(100.0, gt=0, description="highest frequency [Hz] (thesis Fig 6.7: 100 Hz)")
    num: int = Field(400, ge=2, description="log-spaced frequencies")

    @model_validator(mode="after")
    def _increasing(self):
        if not self.stop_hz > self.start_hz:
            raise ValueError(f"stop_hz = {self.stop_hz:g} Hz must be above start_hz = {self.start_hz:g} Hz")
        return self


ESTIMATORS = ("basic", "shifted", "compensated")


class ContourConfig(_Strict):
    """Contour error of the drive's actual motion: exact (against the CAM path, Prévost 2012 §2.2) and
    the thesis' Frenet-frame estimates (eq 4.20 basic, 4.21-4.22 shifted, 4.23-4.27 compensated),
    each compared with the exact error against the reference curve they approximate."""

    estimators: list[Literal[ESTIMATORS]] = Field(list(ESTIMATORS), description=f"estimators to evaluate, of {ESTIMATORS}")
    min_speed_ratio: float = Field(0.01, gt=0, lt=1, description="below this fraction of the peak reference speed "
                                                               "the eq 4.21 delay is taken as 0 [-]")


COMPENSATION_METHODS = ("single_pass", "passes", "fixed_point", "newton")


class CompensationConfig(_Strict):
    """CEC mirror compensation (Prévost 2012 eq 4) of each interpolator's setpoint through the drive,
    towards the CAM path: ``single_pass`` is the paper's method; ``passes`` (a fixed number),
    ``fixed_point`` (iterated to a tolerance) and ``newton`` (model inversion) are extensions."""

    method: Literal[COMPENSATION_METHODS] = Field("single_pass", description=f"one of {COMPENSATION_METHODS}")
    passes: int = Field(2, ge=1, description="mirror passes (method = passes)")
    tolerance_um: float = Field(2.0, gt=0, description="target max |e_T| (fixed_point, newton) [um]; Prévost "
                                                       "Application 1 reaches 2 um")
    max_steps: int = Field(20, ge=1, description="iteration cap (fixed_point, newton)")
    spacing_mm: float = Field(0.02, gt=0, description="largest piece of the in-loop target polyline [mm]")
    friction: Literal["exact", "smooth"] = Field("exact", description="Coulomb sign in the simulation (eq 6.2)")


class TrueModeConfig(_Strict):
    """A mode of the synthetic machine a resonance-test log is made from."""

    axis: Literal["x", "y", "z"] = Field(..., description="axis letter")
    frequency_hz: float = Field(..., gt=0, description="natural frequency [Hz]")
    damping: float = Field(0.02, gt=0, lt=1, description="damping ratio [-] (2 %: Sencer 2015 gives none)")


class VibrationConfig(_Strict):
    """Resonance test -> modes -> eq 10 delays (Sencer 2015, :mod:`research.vibration`): a seeded synthetic
    sine-sweep log of ``modes`` (truth known), or a logged file (``log_file``, relative to the config)."""

    log_file: str | None = Field(None, description="accelerometer log (csv/npz/mat) instead of a synthetic one")
    unit: str = Field("mm/s^2", description="acceleration unit of log_file: mm/s^2, m/s^2 or g")
    modes: list[TrueModeConfig] = Field([], description="the synthetic machine's modes (synthetic log)")
    f0_hz: float = Field(2.0, gt=0, description="sweep start [Hz]")
    f1_hz: float = Field(40.0, gt=0, description="sweep end [Hz]")
    duration_s: float = Field(10.0, gt=0, description="sweep length [s]")
    rate_hz: float = Field(3200.0, gt=0, description="sample rate [Hz] (an ADXL345 at 3.2 kHz, as Klipper)")
    snr_db: float = Field(20.0, description="signal-to-noise ratio of the strongest axis [dB]")
    seed: int = Field(0, ge=0, description="noise seed")
    k: Literal[1, 2] = Field(1, description="eq 10 zero used for every delay (1: the shortest delay)")

    @model_validator(mode="after")
    def _one_source(self):
        if (self.log_file is None) == (not self.modes):
            raise ValueError("give either log_file or modes (a synthetic log of known modes), not both or neither")
        if not self.f1_hz > self.f0_hz:
            raise ValueError(f"f1_hz = {self.f1_hz:g} Hz must be above f0_hz = {self.f0_hz:g} Hz")
        return self


class SpectrumConfig(_Strict):
    """Frequency response of an FIR chain (Sencer 2015 eq 8-9) on ``num`` frequencies up to ``stop_hz``: each
    filter alone and the chain, and, for ``modes_hz`` (one per filter), the eq 10 delays ``T_i = k / f_i`` and
    their chain; the gain of every chain at every mode, and the largest chain gain at the zeros ``f = k / T_i``."""

    delays_ms: list[float] = Field(PAPER_DELAYS_MS, min_length=1, description="FIR delays T_i [ms] (Sencer 2015 §4: 148, 89)")
    modes_hz: list[float] = Field([], description="structural modes [Hz], one per filter (§4: Y 6.8, X 11.4), for eq 10")
    k: int = Field(1, ge=1, description="eq 10 ripple index of the tuned delays")
    zeros: int = Field(3, ge=1, description="zeros k / T_i, k = 1..zeros, at which the chain gain is reported")
    stop_hz: float = Field(40.0, gt=0, description="highest frequency [Hz]")
    num: int = Field(4000, ge=2, description="frequencies from 0 to stop_hz")

    @model_validator(mode="after")
    def _valid(self):
        bad = [d for d in self.delays_ms if not d > 0]
        if bad:
            raise ValueError(f"delays_ms = {self.delays_ms} must all be > 0 ms")
        if any(not m > 0 for m in self.modes_hz):
            raise ValueError(f"modes_hz = {self.modes_hz} must all be > 0 Hz")
        if self.modes_hz and len(self.modes_hz) != len(self.delays_ms):
            raise ValueError(f"modes_hz has {len(self.modes_hz)} values for {len(self.delays_ms)} filters; eq 10 tunes "
                             "one filter per mode")
        return self


class StartupConfig(_Strict):
    """Start of a linear move ``x = m t`` blended in by ``1 - exp(-alpha t^order)`` (DiMarco 2015 eq 3-5,
    :class:`research.interpolators.sigmoid.SigmoidMotion`) for each ``alpha``: position, feed and acceleration
    on ``num`` samples over ``duration_s``, and each feed's peak (where the acceleration crosses zero)."""

    feed_mm_per_s: float = Field(10.0, gt=0, description="nominal feed m [mm/s] (DiMarco §4: 10 mm/s)")
    alphas: list[float] = Field([1.0, 10.0, 100.0, 1000.0], min_length=1, description="blend rates alpha [1/s^order]")
    order: Literal[1, 2, 3] = Field(3, description="blend exponent (3: the sigmoid of eq 2)")
    duration_s: float = Field(2.5, gt=0, description="time span [s]")
    num: int = Field(5000, ge=3, description="samples over the span")

    @model_validator(mode="after")
    def _positive(self):
        if any(not a > 0 for a in self.alphas):
            raise ValueError(f"alphas = {self.alphas} must all be > 0")
        return self


class MTPConfig(_Strict):
    """A modulated tool path ``m t + A sin(2 pi f t)`` of length L along one axis (DiMarco 2015 §1-2) by the sigmoid
    interpolator and two linear interpolators of ``moves_per_period`` G01 moves per period (exact stop; blending with
    acc/dec after interpolation), each run through the config's ``[drive]``
    (:mod:`research.experiments.stage_mtp`)."""

    length_mm: float = Field(..., gt=0, description="move length L [mm]")
    feed_mm_per_s: float = Field(..., gt=0, description="nominal feed m [mm/s]")
    amplitude_mm: float = Field(..., ge=0, description="modulation amplitude A [mm]")
    frequency_hz: float = Field(..., gt=0, description="modulation frequency f [Hz]")
    acceleration_mm_per_s2: float = Field(..., gt=0, description="acceleration limit of every interpolator [mm/s^2]")
    jerk_mm_per_s3: float = Field(..., gt=0, description="jerk limit of every interpolator [mm/s^3]")
    moves_per_period: int = Field(16, ge=2, description="G01 moves per oscillation period (linear interpolators)")
    sample_period_ms: float = Field(0.1, gt=0, description="grid step of the references and the drive [ms]")
    settle_time_s: float = Field(0.2, gt=0, description="rest simulated after the longest reference [s]")


class FiveAxisContourConfig(_Strict):
    """Thesis §4.5 / Fig 4.6 (:func:`research.contour.five_axis_contour_study`): the eq 4.36 5-axis path (50 mm/s,
    1500 mm/s^2) through per-axis Table 6.3 drives, the exact tool-tip contour error against the basic (eq 4.20),
    shifted (eq 4.22) and compensated (eq 4.27) Frenet estimates, and the eq 4.21 delay."""

    drive: Literal["sencer2009_table6_3", "sencer2009_table6_3_ppi"] = Field(
        "sencer2009_table6_3", description="per-axis drives (thesis Table 6.3 closed loop, or its P-PI cascade)")
    sample_period_ms: float = Field(1.0, gt=0, description="sample period Ts [ms]")
    friction: Literal["exact", "smooth"] = Field("exact", description="Coulomb sign in the simulation (eq 6.2)")
    moving_speed_ratio: float = Field(0.01, gt=0, lt=1, description="samples whose linear-axis speed is above this "
                                                                    "fraction of the 50 mm/s feed count as moving [-]")
