"""Stored identified drives (issue 14 item 8): save, load, validate, provenance."""

import hashlib
import json

import numpy as np
import pytest

from research.errors import ConfigError, ParameterError
from research.identification import (
    EQ_6_3,
    PP2,
    DriveLog,
    PhysicalModel,
    StructureFit,
    identification_program,
    least_squares,
    load_identified,
    save_drive_log,
    save_identified,
    simulation_error_fit,
)
from research.identification._simulation import Reference, consistent_signs, linear_part, responses


@pytest.fixture(scope="module")
def pp2_log(tmp_path_factory):
    """A pp2 loop (wn 25 Hz, zeta 0.55, b1 40 1/s, dc 150, offset -40 mm/s^2) on a short §6.5 program, 1 um noise,
    written to a CSV file so that it has a SHA-256."""
    ref = identification_program(4, n_moves=8).trajectory()
    q, Ts = np.asarray(ref.q[:, 0]), ref.sample_period
    R = responses(PP2, [2 * np.pi * 25, 0.55], Reference.from_samples(q, Ts))
    x = consistent_signs(R, *linear_part(PP2, R, [40.0, 0.0], -40.0, None), 150.0)[0] + q[0]
    x = x + 1e-3 * np.random.default_rng(0).standard_normal(q.size)
    path = save_drive_log(DriveLog(np.arange(q.size) * Ts, q, x), tmp_path_factory.mktemp("store") / "pp2.csv")
    from research.identification import load_drive_log

    return load_drive_log(path), path


@pytest.fixture(scope="module")
def stored(pp2_log, tmp_path_factory):
    log, _ = pp2_log
    fit = simulation_error_fit(log, "pp2")
    return fit, save_identified(fit, tmp_path_factory.mktemp("model") / "pp2.json", log=log)


def test_round_trip_is_exact_and_records_provenance(pp2_log, stored):
    log, csv = pp2_log
    fit, path = stored
    back = load_identified(path, log_file=csv)
    assert isinstance(back, StructureFit) and back.structure == PP2
    assert back.parameters == fit.parameters and back.std == fit.std  # exact float64 round trip
    assert back.converged == fit.converged and back.initial == fit.initial
    np.testing.assert_array_equal(back.simulate(log), fit.simulate(log))
    st = back.info["stored"]
    assert st["provenance"]["log_sha256"] == hashlib.sha256(csv.read_bytes()).hexdigest()  # independent hash
    assert st["provenance"]["n_samples"] == log.n_samples and st["sample_period_s"] == log.sample_period
    assert st["fit_report"]["rms_um"] == pytest.approx(fit.rms_um, rel=1e-6)  # compare on the same log
    doc = json.loads(path.read_text())
    assert doc["units"]["pole_frequency"] == "rad/s" and doc["stable"] is True and len(doc["poles_rad_s"]) == 2


def test_eq_6_3_loads_into_the_drive_simulators_model(pp2_log, tmp_path):
    log, _ = pp2_log
    fit = simulation_error_fit(log, EQ_6_3, thesis_starts=False, n_polish=1)
    back = load_identified(save_identified(fit, tmp_path / "eq63.json", log=log))
    assert back.closed_loop_model() == fit.closed_loop_model()


def test_thesis_fit_and_physical_model_round_trip(pp2_log, tmp_path):
    """An IdentifiedDrive (LS, eq 6.12) keeps its coefficients and its stability flag; a physical model's NaN
    loss (it is not fitted by simulation error) is written as null and read back as NaN."""
    log, _ = pp2_log
    ls = least_squares(log)
    back = load_identified(save_identified(ls, tmp_path / "ls.json", log=log))
    assert back.coefficients == ls.coefficients and back.stable == ls.stable and back.method == "ls"
    phys = PhysicalModel(20.0, 50.0, 8.0, -2.0, {}, 10.0, 100.0, 50.0, 20.0, 0.1).closed_loop("sim")
    p = save_identified(phys, tmp_path / "phys.json", log=log)
    assert '"loss": null' in p.read_text()
    back = load_identified(p)
    assert np.isnan(back.loss) and back.parameters == phys.parameters and back.method == "physical"


def _edit(path, tmp_path, fn, name="bad.json"):
    doc = json.loads(path.read_text())
    fn(doc)
    out = tmp_path / name
    out.write_text(json.dumps(doc))
    return out


@pytest.mark.parametrize("edit, match", [
    (lambda d: d.update(version=2), r"bad\.json: key 'version' is 2; this code reads version 1"),
    (lambda d: d.update(format="something"), r"bad\.json: key 'format' is 'something'"),
    (lambda d: d["model"]["parameters"].pop("dc"), r"bad\.json: model\.parameters: expected exactly the keys"),
    (lambda d: d["model"]["parameters"].update(wn=-3.0), r"bad\.json: model\.parameters: pole parameters \['wn'\]"),
    (lambda d: d["model"]["parameters"].update(zeta="0.5"), r"bad\.json: model\.parameters: 'zeta' must be a finite"),
    (lambda d: d["model"]["structure"].update(n_poles=1), r"bad\.json: model\.structure: not a valid model structure"),
    (lambda d: d["model"].pop("converged"), r"bad\.json: model: missing key 'converged'"),
    (lambda d: d.update(sample_period_s=0), r"bad\.json: key 'sample_period_s' must be a finite number > 0"),
    (lambda d: d.update(kind="matrix"), r"bad\.json: key 'kind' is 'matrix'"),
])
def test_corrupt_or_wrong_version_files_raise_config_errors_naming_the_key(stored, tmp_path, edit, match):
    _, path = stored
    with pytest.raises(ConfigError, match=match):
        load_identified(_edit(path, tmp_path, edit))


def test_truncated_missing_and_foreign_log_files(stored, tmp_path):
    _, path = stored
    cut = tmp_path / "cut.json"
    cut.write_text(path.read_text()[:200])
    with pytest.raises(ConfigError, match=r"cut\.json:\d+:\d+: not valid JSON.*truncated"):
        load_identified(cut)
    with pytest.raises(ConfigError, match=r"nope\.json: identified-model file not found"):
        load_identified(tmp_path / "nope.json")
    other = tmp_path / "other.csv"
    other.write_text("t,x_ref,x_act\n")
    with pytest.raises(ConfigError, match=r"pp2\.json: provenance\.log_sha256 .*other\.csv hashes to"):
        load_identified(path, log_file=other)
    with pytest.raises(ParameterError, match="expected a StructureFit or IdentifiedDrive"):
        save_identified({"wn": 1.0}, tmp_path / "x.json", log=_a_log())


def _a_log():
    t = np.arange(100) * 1e-3
    return DriveLog(t, np.sin(t), np.sin(t))
