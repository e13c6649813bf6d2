"""Sweep figures a reviewer accepts (issue 16 item 6): no colour map of solver noise, log scale where the
values span decades, the base (paper) point and eq 10's nulls located, lines for small discrete grids."""

import numpy as np
import pytest

from research.experiments.config import validate
from research.experiments.sweep_figure import base_value, colour_scale, eq10_nulls

DELAYS = {"name": "d", "reproduces": "-", "path": {"name": "diamond"},
          "interpolator": {"delays_ms": [148.0, 89.0]},
          "drive": {"modes": [{"axis": "x", "frequency_hz": 11.4}, {"axis": "y", "frequency_hz": 6.8}]}}


@pytest.mark.parametrize("values, kind", [
    (0.5 + 1e-11 * np.arange(5), "constant"),   # the corner error = eps everywhere, plus rounding noise
    (np.array([0.014, 0.05, 0.5]), "log"),      # the residual-vibration valley (14 um) under 500 um peaks
    (np.array([1.65, 1.8, 1.95]), "linear"),
    (np.array([-1.0, 1.0]), "linear"),
    (np.array([np.nan, np.nan]), "constant"),
])
def test_colour_scale(values, kind):
    assert colour_scale(values) == kind


def test_base_point_and_eq10_nulls_of_the_delay_sweep():
    """Sencer 2015 eq 10: a chain zero on a mode of frequency f at T = k / f; 1/6.8 Hz = 147.06 ms,
    1/11.4 Hz = 87.72 ms, 2/11.4 Hz = 175.44 ms."""
    cfg = validate(DELAYS, "d.toml")
    assert base_value("interpolator.delays_ms[0]", cfg) == 148.0
    assert base_value("drive.modes[1].frequency_hz", cfg) == 6.8
    assert base_value("interpolator.nope", cfg) is None
    t1 = eq10_nulls("interpolator.delays_ms[0]", cfg, 120.0, 180.0)
    assert [round(T, 2) for T, _ in t1] == [175.44, 147.06]
    assert "1/f_y" in t1[1][1]
    assert [round(T, 2) for T, _ in eq10_nulls("interpolator.delays_ms[1]", cfg, 70.0, 110.0)] == [87.72]
    assert eq10_nulls("interpolator.tolerance_um", cfg, 0.0, 1e9) == []


def test_small_grid_is_drawn_as_lines_and_large_grid_as_a_map(tmp_path, monkeypatch):
    """A 4 x 3 grid (the identification study's shape) is drawn as lines, one per value of the field with
    fewer values (no colour map with invented cells); a 7 x 8 grid as a colour map with the base point."""
    import matplotlib.axes

    from research.experiments.sweep import SweepResult
    from research.experiments.sweep_figure import plot_sweep

    calls = {"plot": 0, "pcolormesh": 0}
    for name in calls:
        original = getattr(matplotlib.axes.Axes, name)

        def spy(self, *a, _name=name, _original=original, **k):
            calls[_name] += 1
            return _original(self, *a, **k)
        monkeypatch.setattr(matplotlib.axes.Axes, name, spy)
    raw = DELAYS | {"sweep": {"parameters": {"interpolator.delays_ms[0]": [1.0], "interpolator.delays_ms[1]": [1.0]}}}
    cfg = validate(raw, "d.toml")

    def result(n0, n1):
        rows = [{"index": i * n1 + j, "status": "ok", "interpolator.delays_ms[0]": 120.0 + 10 * i,
                 "interpolator.delays_ms[1]": 70.0 + 5 * j, "cycle_time": 1.6 + 0.01 * i + 0.002 * j,
                 "residual_vibration": 0.014 * (1 + i + j) ** 2}
                for i in range(n0) for j in range(n1)]
        return SweepResult(cfg, ["interpolator.delays_ms[0]", "interpolator.delays_ms[1]"], rows, {}, tmp_path, None)

    plot_sweep(result(4, 3), tmp_path / "small.png")
    assert calls == {"plot": 2 * 3, "pcolormesh": 0}  # 3 lines (the 3-valued field) in each of 2 panels
    calls.update(plot=0)
    plot_sweep(result(7, 8), tmp_path / "large.png")
    assert calls["pcolormesh"] >= 2 and calls["plot"] >= 2  # maps (colour bars draw with it too), base point starred
    assert (tmp_path / "small.png").stat().st_size > 0 and (tmp_path / "large.png").stat().st_size > 0
