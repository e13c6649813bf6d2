"""The ``[drive]`` table: the drive model the references run through (ideal, a thesis catalog drive,
eq 6.3 parameters, or an identified model), its structural modes (Sencer 2015 §4) and its
frequency-response study (thesis eq 6.1, 6.13).
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from research.experiments.config_stages import ClosedLoopConfig, FrequencyResponseConfig, _Strict

DRIVE_MODELS = ("ideal", "sencer2009_table6_1", "sencer2009_table6_1_ppi", "sencer2009_table6_2", "sencer2009_table6_2_pid",
                "sencer2009_table6_3", "sencer2009_table6_3_ppi", "parameters", "identified")
#: catalog drives with one model per axis (thesis Table 6.3: axes x, y, z, a, c)
PER_AXIS_DRIVES = {"sencer2009_table6_3": "table_6_3_closed_loop", "sencer2009_table6_3_ppi": "table_6_3_ppi"}


class ModeConfig(_Strict):
    """A lightly damped structural mode excited by one axis' acceleration (the beams of Sencer 2015 §4)."""

    axis: str = Field(..., description="axis letter that excites it (x, y, z)")
    frequency_hz: float = Field(..., gt=0, description="natural frequency [Hz]")
    damping: float = Field(0.02, gt=0, lt=1, description="damping ratio [-] (2 %: the paper gives none)")


class DriveConfig(_Strict):
    """Drive model the references run through. ``ideal``: the axes follow the reference exactly and the
    modes see the reference acceleration; a thesis catalog drive (Table 6.1 / 6.2 on every axis, Table 6.3
    per axis); ``parameters``: the eq 6.3 model in ``[drive.parameters]``; ``identified``: the drive the
    config's ``[identification]`` fits, or the model file ``identified_file`` (written by
    :func:`research.identification.save_identified`, e.g. ``drive_model.json`` of an earlier run)."""

    model: Literal[DRIVE_MODELS] = Field("ideal", description=f"one of {DRIVE_MODELS}")
    parameters: ClosedLoopConfig | None = Field(None, description="eq 6.3 parameters (model = \"parameters\")")
    identified_file: str | None = Field(
        None, description="identified-model file written by save_identified (model = \"identified\"), relative to the "
                          "config file, e.g. \"../results/<name>/drive_model.json\" of an earlier run; its bytes are "
                          "part of the results key")
    modes: list[ModeConfig] = Field([], description="structural modes")
    settle_time_s: float = Field(1.5, gt=0, description="rest simulated after the motion [s] (catalog drives)")
    frequency_response: FrequencyResponseConfig | None = Field(
        None, description="tracking / disturbance responses, poles and bandwidth of the drive (a drive model, not ideal)")

    @model_validator(mode="after")
    def _parameters_with_model(self):
        if (self.model == "parameters") != (self.parameters is not None):
            raise ValueError("model = \"parameters\" and a [drive.parameters] table go together "
                             f"(got model = {self.model!r}, parameters {'given' if self.parameters else 'missing'})")
        if self.identified_file is not None and self.model != "identified":
            raise ValueError(f"identified_file goes with model = \"identified\" (got model = {self.model!r})")
        return self
