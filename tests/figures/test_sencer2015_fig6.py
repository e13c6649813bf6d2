"""Sencer 2015 Fig 6 from its config (experiments/figures/sencer2015_fig6_cornering_comparison.toml), drawn from the
stored result. The paper prints no Fig 6 number; its claims (§4, line 195): "proposed method delivers faster cycle
time", the beams "are excited in each direction around the corner blends" (geometric smoothing), and "corners are
turned without stopping and without triggering any vibration on the beams". Model predictions on the config's
assumed drive, damping and diamond size, tested as properties of the stored result."""

import numpy as np

from research.figures import render


def test_fig6_from_the_store(tmp_path):
    """The FIR finishes sooner than the blend held to its own axis peaks and leaves at least 5x less residual
    vibration on each beam (measured 12.5 / 12.9 um against 108 / 593 um); the blend is held to the FIR's peaks."""
    (tmp_path / "f").mkdir()
    out = render("sencer2015_fig6_cornering_comparison", tmp_path / "f", cache_dir=tmp_path / "c",
                 results_dir=tmp_path / "r")
    assert out.files[0].stat().st_size > 0
    rec, arrays = out.run.record, out.run.arrays()
    s = rec["scalars"]
    assert s["fir.cycle_time"] < s["blend.cycle_time"]
    for axis in ("x", "y"):
        assert 5 * s[f"fir.residual_vibration.{axis}"] < s[f"blend.residual_vibration.{axis}"]
    assert s["fir.residual_vibration"] < 0.02  # mm
    limits = rec["details"]["blend"]["limits"]
    fir_peak_a = np.abs(arrays["fir.a"]).max(axis=0)
    assert np.all(np.abs(arrays["blend.a"]).max(axis=0) <= np.asarray(limits["acceleration"]) * (1 + 1e-6))
    assert np.all(np.asarray(limits["acceleration"]) >= fir_peak_a * (1 - 1e-9))


def test_limits_from_names_an_earlier_interpolator():
    """``limits_from`` must name an earlier interpolator, and not come with ``limits``."""
    import pytest

    from research.errors import ConfigError
    from research.experiments.config import validate

    fir = {"label": "fir"}
    blend = {"kind": "blend", "label": "blend", "limits_from": "fir"}
    base = {"name": "t", "reproduces": "-", "path": {"name": "diamond"}}
    validate(base | {"interpolator": [fir, blend]}, "t.toml")
    for bad in ([blend, fir], [fir, blend | {"limits_from": "fr"}],
                [fir, blend | {"limits": {"velocity_mm_per_s": 1.0, "acceleration_mm_per_s2": 1.0}}]):
        with pytest.raises(ConfigError, match="limits_from"):
            validate(base | {"interpolator": bad}, "t.toml")
