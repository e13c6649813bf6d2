"""The ``[interpolator]`` tables: the Sencer 2015 FIR planner (:class:`FIRConfig`), the CasADi
minimum-time reference (:class:`TimeOptimalConfig`), and the S-curve, blend and sigmoid kinds of
:mod:`~research.experiments.config_stages`, one discriminated union :data:`Interpolator` on ``kind``.
Feeds in mm/s, delays and sample periods in ms, tolerances in um.
"""

from __future__ import annotations

from typing import Annotated, Literal, Union

from pydantic import Field, model_validator

from research.experiments.config_stages import BlendConfig, LimitsConfig, SCurveConfig, SigmoidConfig, _Strict

#: plausible feed range [mm/s] (issue 16): below 1 mm/s is a unit slip (m/s typed in a mm/s key), above
#: 10 m/s beyond any machine tool (mm/min typed in a mm/s key); outside it a config is refused
FEED_RANGE_MM_PER_S = (1.0, 10_000.0)


class FIRConfig(_Strict):
    """Sencer 2015 FIR-overlap interpolator settings (defaults: the paper's §4 experiment)."""

    kind: Literal["fir"] = "fir"
    label: str | None = Field(None, description="name in results (default: kind)")
    feed_mm_per_s: float = Field(250.0, gt=0, description="commanded feed F [mm/s]")
    delays_ms: list[float] = Field([148.0, 89.0], min_length=1, description="FIR delays T_i [ms]")
    tolerance_um: float = Field(500.0, ge=0, description="cornering tolerance epsilon [um]")
    sample_period_ms: float = Field(1.0, gt=0, description="interpolation period Ts [ms]")
    refine: bool = Field(True, description="short-segment rule (verified overlap)")
    limits: LimitsConfig | None = Field(None, description="axis limits the FIR also holds (plan_fir(limits=...), "
                                                          "beyond the paper; none: the paper's planner)")
    optimized: bool = Field(False, description="per-corner overlaps and per-block feeds chosen for the least cycle "
                                               "time (research.interpolators.optimize_fir, beyond the paper): G01 "
                                               "paths with one feed and tolerance, eps > 0")
    mirror: bool = Field(False, description="the filters' input pre-compensated by mirror passes so that their output "
                                            "keeps the programmed path at higher feeds "
                                            "(research.interpolators.plan_fir_mirror, beyond the paper; never "
                                            "slower than plan_fir)")
    corner_speed: Literal["step", "turn"] = Field(
        "step", description="the speed change eq 13/14 rounds a corner between unequal feeds for (plan_fir's "
                            "corner_speed): 'step' the velocity step, 'turn' the turn at the larger feed (a straight "
                            "feed step is no corner); the same at equal feeds")

    @model_validator(mode="after")
    def _positive_delays(self):
        bad = [i for i, d in enumerate(self.delays_ms) if not d > 0]
        if bad:
            raise ValueError(f"delays_ms[{bad[0]}] must be > 0 ms, got {self.delays_ms[bad[0]]}")
        _plausible_units(self.feed_mm_per_s, self.delays_ms, self.sample_period_ms, "delays_ms")
        if self.optimized and not self.tolerance_um > 0:
            raise ValueError("optimized = true needs a cornering tolerance tolerance_um > 0 um (optimize_fir)")
        if self.mirror and (self.optimized or not self.refine or self.corner_speed != "step"):
            raise ValueError("mirror = true plans by plan_fir_mirror's own verified search: it takes neither "
                             "optimized = true, refine = false nor corner_speed (it plans with 'turn')")
        if self.optimized and self.corner_speed != "step":
            raise ValueError("optimized = true chooses every corner's overlap itself (optimize_fir): it takes no "
                             "corner_speed")
        return self


class TimeOptimalConfig(_Strict):
    """CasADi minimum-time reference (:func:`research.optimal.time_optimal`) in the tolerance tube,
    under the nominal envelope of an FIR with ``envelope_delays_ms`` (``v = F, a = F/T1, j = F/(T1 T2)``)."""

    kind: Literal["time_optimal"]
    label: str | None = Field(None, description="name in results (default: kind)")
    feed_mm_per_s: float = Field(250.0, gt=0, description="path speed bound F and envelope feed [mm/s]")
    tolerance_um: float = Field(500.0, gt=0, description="tube radius epsilon [um]")
    envelope_delays_ms: list[float] = Field([148.0, 89.0], min_length=1, description="FIR delays setting the limits [ms]")
    intervals_per_segment: int = Field(16, ge=3, description="jerk intervals per segment")
    window: int | None = Field(None, ge=1, description="segments per receding window (none: whole path)")
    lookahead: Literal["segments", "braking"] = Field(
        "segments", description="what a window keeps after what it commits: 'segments' 4 segments whatever their "
                                "length, 'braking' at least the braking distance from the feed bound "
                                "(time_optimal(lookahead='braking')); on short chords a window must be several "
                                "braking distances long either way")
    sample_period_ms: float = Field(1.0, gt=0, description="sample period of the returned trajectory [ms]")

    @model_validator(mode="after")
    def _plausible(self):
        _plausible_units(self.feed_mm_per_s, self.envelope_delays_ms, self.sample_period_ms, "envelope_delays_ms")
        return self


def _plausible_units(feed: float, delays_ms: list[float], sample_period_ms: float, delays_key: str) -> None:
    """Refuse the unit slips the key names invite (issue 16): a feed outside :data:`FEED_RANGE_MM_PER_S`
    and a delay shorter than the sample period (an FIR shorter than Ts has no sample inside it; a value
    such as 0.06 in a ``_ms`` key is most likely seconds)."""
    lo, hi = FEED_RANGE_MM_PER_S
    if feed < lo:
        raise ValueError(f"feed_mm_per_s = {feed:g} mm/s is below {lo:g} mm/s; the key is in mm/s: was it m/s "
                         f"({feed:g} m/s = {feed * 1e3:g} mm/s)?")
    if feed > hi:
        raise ValueError(f"feed_mm_per_s = {feed:g} mm/s is above {hi:g} mm/s (10 m/s); the key is in mm/s: was it "
                         f"mm/min ({feed:g} mm/min = {feed / 60:g} mm/s)?")
    for i, d in enumerate(delays_ms):
        if d < sample_period_ms:
            hint = (f"; the key is in ms: was it seconds ({d:g} s = {d * 1e3:g} ms)?" if d < 1.0
                    else "; lengthen the delay or shorten sample_period_ms")
            raise ValueError(f"{delays_key}[{i}] = {d:g} ms is below the sample period sample_period_ms = "
                             f"{sample_period_ms:g} ms{hint}")


Interpolator = Annotated[Union[FIRConfig, TimeOptimalConfig, SCurveConfig, BlendConfig, SigmoidConfig],
                         Field(discriminator="kind")]
#: the interpolator kinds a config may name
INTERPOLATOR_KINDS = ("fir", "time_optimal", "scurve", "blend", "sigmoid")
