"""A controller's log in a config (issue 14 item 7: "column mapping and units in the config and API"):
``[identification] columns``, ``units`` and ``counts_per_mm`` read a log whose columns have other names and
units. Expected: the same identified model as the same data written in the canonical form (t [s], x_ref
[mm], x_act [mm]), the unit conversions done by hand here (ms, m, counts at a stated resolution)."""

import numpy as np
import pytest

from research.drives import Encoder, virtual_drive
from research.errors import ConfigError, DriveLogError
from research.experiments.config import validate
from research.experiments.evaluate import evaluate
from research.identification import identification_program, synthetic_log

COUNTS_PER_MM = 20_000.0  # a 0.05 um encoder: the thesis' resolution, so the counts are whole numbers


def write_logs(folder):
    """The same noise-free synthetic log twice: canonical, and as a controller would write it."""
    ref = identification_program(0, n_moves=4).trajectory()
    log = synthetic_log(virtual_drive("sencer2009_table6_1"), ref, encoder=Encoder(1.0 / COUNTS_PER_MM, 0.0), seed=0)
    t, x_ref, x_act = (np.asarray(v, dtype=np.float64) for v in (log.t, log.reference, log.actual))
    np.savetxt(folder / "canonical.csv", np.column_stack([t, x_ref, x_act]), delimiter=",", header="t,x_ref,x_act",
               comments="", fmt="%.17g")
    counts = np.round(x_act * COUNTS_PER_MM)
    np.savetxt(folder / "controller.csv", np.column_stack([t * 1e3, x_ref * 1e-3, counts]), delimiter=",",
               header="time_ms,X_cmd,X_enc", comments="", fmt="%.17g")


def identify(folder, **table):
    cfg = validate({"name": "t", "reproduces": "-", "identification": {"method": "ls"} | table}, folder / "t.toml")
    return evaluate(cfg, folder).record["details"]["identification"]


def test_mapped_columns_and_units_give_the_canonical_fit(tmp_path):
    write_logs(tmp_path)
    canonical = identify(tmp_path, log_file="canonical.csv")
    mapped = identify(tmp_path, log_file="controller.csv", columns={"t": "time_ms", "x_ref": "X_cmd", "x_act": "X_enc"},
                      units={"t": "ms", "x_ref": "m", "x_act": "counts"}, counts_per_mm=COUNTS_PER_MM)
    for key in ("wn_rad_per_s", "zeta", "p_rad_per_s", "dc"):
        assert mapped[key] == pytest.approx(canonical[key], rel=1e-6), key


def test_counts_without_a_resolution_name_the_column(tmp_path):
    write_logs(tmp_path)
    with pytest.raises(DriveLogError, match="X_enc"):
        identify(tmp_path, log_file="controller.csv", columns={"t": "time_ms", "x_ref": "X_cmd", "x_act": "X_enc"},
                 units={"t": "ms", "x_ref": "m", "x_act": "counts"})


@pytest.mark.parametrize("table, message", [
    ({"columns": {"t": "time"}}, r"columns describe log_file, which is not given"),
    ({"log_file": "a.csv", "columns": {"time": "t"}}, r"key 'identification.columns.time'"),
    ({"log_file": "a.csv", "counts_per_mm": 1.0, "counts_per_rev": 1.0}, r"not both"),
    ({"log_file": "a.csv", "counts_per_mm": -1.0}, r"key 'identification.counts_per_mm'"),
])
def test_log_options_are_validated(tmp_path, table, message):
    (tmp_path / "a.csv").write_text("t,x_ref,x_act\n")
    with pytest.raises(ConfigError, match=message):
        validate({"name": "t", "reproduces": "-", "identification": table}, tmp_path / "t.toml")
