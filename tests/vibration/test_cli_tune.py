"""``python -m research tune LOG --path diamond``: modes -> eq 10 delays -> a config that loads."""

import numpy as np

from research.cli import main
from research.experiments.config import load_config
from research.vibration import save_accel_log


def test_tune_writes_a_loadable_config_and_reports_before_after(tmp_path, sweep_log, capsys):
    log = save_accel_log(sweep_log, tmp_path / "resonances.csv")
    out = tmp_path / "tuned.toml"
    assert main(["tune", str(log), "--path", "diamond", "--out", str(out), "--before-ms", "120", "70"]) == 0
    text = capsys.readouterr().out
    assert "before delays [120.0, 70.0] ms" in text and "after" in text and "robustness" in text
    cfg, _ = load_config(out)
    modes = {m.axis: m for m in cfg.drive.modes}
    assert set(modes) == {"x", "y"}
    assert abs(modes["x"].frequency_hz / 11.4 - 1) < 0.01 and abs(modes["y"].frequency_hz / 6.8 - 1) < 0.01
    delays = cfg.interpolators[0].delays_ms
    np.testing.assert_allclose(delays, [1e3 / modes["y"].frequency_hz, 1e3 / modes["x"].frequency_hz], rtol=1e-12)
    # the residual vibration printed after tuning is below the untuned one for both modes (model prediction)
    lines = {ln.split()[0]: ln for ln in text.splitlines() if ln.strip().startswith(("before", "after"))}
    um = {k: [float(w) for w, nxt in zip(v.split(), v.split()[1:]) if nxt.startswith("um")] for k, v in lines.items()}
    assert all(a < b for a, b in zip(um["after"], um["before"]))


def test_tune_refuses_a_log_without_motion(tmp_path, capsys):
    rng = np.random.default_rng(1)
    t = np.arange(4000) / 800.0
    a = rng.normal(0, 20.0, (t.size, 3)) + [0.0, 0.0, 9806.65]
    p = tmp_path / "rest.csv"
    np.savetxt(p, np.column_stack([t, a]), delimiter=",", header="#time,accel_x,accel_y,accel_z", comments="")
    assert main(["tune", str(p), "--path", "diamond", "--out", str(tmp_path / "x.toml")]) == 2
    assert "no motion" in capsys.readouterr().err
    assert not (tmp_path / "x.toml").exists()
