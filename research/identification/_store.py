"""Storing an identified drive so that later configs and runs can use it without refitting.

:func:`save_identified` writes one JSON file (readable, diffable, exact: Python writes the shortest repr that
reads back to the same float64) holding the model structure, every parameter with its standard deviation, the
sample period and units of the estimation log, the fit report (simulation fit %, RMS and max error on that
log, convergence, poles) and the provenance: the log's source, window and number of samples and, when the
log is a file, its path and SHA-256. :func:`load_identified` validates the file and returns the same model
type that was saved: a :class:`StructureFit` (the default fit, :func:`simulation_error_fit`, and
:meth:`PhysicalModel.closed_loop`; simulate it with ``.simulate(log)`` or, for eq 6.3, convert it with
``.closed_loop_model()`` for :func:`research.drives.simulate`) or an :class:`IdentifiedDrive` (the thesis'
LS / PSO / optimistix / output-error fits; ``.model()``).

Non-finite numbers (the NaN loss of a physical model, an undefined standard deviation) are written as
``null`` and read back as NaN; parameters and coefficients must be finite.
"""

from __future__ import annotations

import hashlib
import json
import math
from pathlib import Path

import numpy as np

from research.errors import ConfigError, ParameterError, StoreError
from research.identification._compare import compare
from research.identification._log import DriveLog
from research.identification._result import COEFFICIENTS, IdentifiedDrive
from research.identification._structure import ModelStructure
from research.identification._structure_fit import StructureFit

#: the ``format`` tag of every stored model file
FORMAT = "research.identified_drive"
#: the layout version this code writes and reads
VERSION = 1
#: units of the stored numbers
UNITS = {"time": "s", "position": "mm (rad for rotary axes)", "pole_frequency": "rad/s",
         "disturbance": "mm/s^2 (friction dc, offset; force_gain per unit of the force column)"}
KINDS = ("structure_fit", "identified_drive")


def sha256(path) -> str:
    """Hex SHA-256 of a file's bytes."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _plain(o):
    """``o`` with numpy scalars/arrays as Python numbers/lists and non-finite floats as None (JSON null)."""
    if isinstance(o, dict):
        return {str(k): _plain(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [_plain(v) for v in o]
    if isinstance(o, np.ndarray):
        return _plain(o.tolist())
    if isinstance(o, (bool, np.bool_)):
        return bool(o)
    if isinstance(o, (np.integer, int)):
        return int(o)
    if isinstance(o, (np.floating, float)):
        return float(o) if math.isfinite(o) else None
    if o is None or isinstance(o, str):
        return o
    return repr(o)


def save_identified(result, path, *, log: DriveLog, log_file=None) -> Path:
    """Write an identified model (module docstring) to ``path`` (``.json``).

    Args:
        result: :class:`StructureFit` or :class:`IdentifiedDrive`.
        path: the file to write.
        log: the estimation log the model was fitted on (sample period, units, window, fit report).
        log_file: the file that log was read from, hashed for provenance; default ``log.source`` when that
            names an existing file (a window or axis of a file gives a source that does not: pass it).
    Returns:
        the path written.
    Raises:
        ParameterError: ``result`` is not an identified model or ``log`` not a :class:`DriveLog`.
        StoreError: the file cannot be written (names the path).
    """
    path = Path(path)
    if not isinstance(log, DriveLog):
        raise ParameterError(f"save_identified: log must be the DriveLog the model was fitted on, got {type(log).__name__}")
    if isinstance(result, StructureFit):
        kind = "structure_fit"
        model = {"structure": result.structure.to_dict(), "parameters": result.parameters, "std": result.std,
                 "loss": result.loss, "rms_um": result.rms_um, "converged": result.converged,
                 "at_bound": list(result.at_bound), "initial": result.initial, "method": result.method,
                 "source": result.source, "wall_time_s": result.wall_time_s, "info": result.info}
    elif isinstance(result, IdentifiedDrive):
        kind = "identified_drive"
        model = {"method": result.method, "coefficients": result.coefficients, "loss": result.loss,
                 "loss_kind": result.loss_kind, "wall_time_s": result.wall_time_s, "iterations": result.iterations,
                 "source": result.source, "history": result.history, "info": result.info}
    else:
        raise ParameterError(f"save_identified: expected a StructureFit or IdentifiedDrive, got {type(result).__name__}")
    if log_file is None and Path(log.source).is_file():
        log_file = log.source
    provenance = {"log_source": log.source, "log_columns": log.columns, "t_start_s": float(log.t[0]),
                  "t_stop_s": float(log.t[-1]), "n_samples": log.n_samples,
                  "log_file": None if log_file is None else str(log_file),
                  "log_sha256": None if log_file is None else sha256(log_file)}
    if isinstance(result, StructureFit) and result.structure.force:
        report = {"reason": "structure with a force input: the report needs the force column (not stored)"}
    else:
        report = compare(result, log)["all"]
    doc = {"format": FORMAT, "version": VERSION, "kind": kind, "sample_period_s": log.sample_period,
           "units": {**UNITS, "log": log.units}, "model": model, "poles_rad_s": [[p.real, p.imag] for p in result.poles()],
           "stable": bool(result.stable), "fit_report": report, "provenance": provenance}
    try:
        path.write_text(json.dumps(_plain(doc), indent=1, allow_nan=False) + "\n", encoding="utf-8")
    except OSError as e:
        raise StoreError(f"{path}: cannot write the identified model ({e.strerror or e})") from None
    return path


# -- loading and validation ------------------------------------------------------------------------
def _get(d: dict, key: str, kind, where: str, *, nullable: bool = False):
    if not isinstance(d, dict) or key not in d:
        raise ConfigError(f"{where}: missing key {key!r}")
    v = d[key]
    if v is None and nullable:
        return None
    ok = (isinstance(v, kind) and not isinstance(v, bool)) if kind in (int, float, (int, float)) else isinstance(v, kind)
    if not ok:
        raise ConfigError(f"{where}: key {key!r} must be {getattr(kind, '__name__', kind)}, got {v!r}")
    return v


def _finite_map(d, names, where: str, *, nullable: bool = False) -> dict:
    if not isinstance(d, dict) or set(d) != set(names):
        raise ConfigError(f"{where}: expected exactly the keys {sorted(names)}, got "
                          f"{sorted(d) if isinstance(d, dict) else d!r}")
    out = {}
    for k in names:
        v = d[k]
        if v is None and nullable:
            out[k] = float("nan")
        elif isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise ConfigError(f"{where}: {k!r} must be a finite number, got {v!r}")
        else:
            out[k] = float(v)
    return out


def _num(v) -> float:
    return float("nan") if v is None else float(v)


def load_identified(path, *, log_file=None):
    """Read a file written by :func:`save_identified` and return the model it holds.

    Args:
        path: the ``.json`` file.
        log_file: when given, its SHA-256 must equal the recorded one (the model belongs to this log).
    Returns:
        :class:`StructureFit` or :class:`IdentifiedDrive`, as saved; ``info["stored"]`` holds the file's sample
        period, units, fit report and provenance.
    Raises:
        ConfigError: a missing or unreadable file, invalid JSON (line and column named), another format or
            version, a missing or mistyped key, parameters that do not match the structure, non-finite or
            unstable parameters, or a ``log_file`` whose SHA-256 differs; every message names the file and key.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ConfigError(f"{path}: identified-model file not found") from None
    except (OSError, UnicodeDecodeError) as e:
        raise ConfigError(f"{path}: cannot read the identified-model file ({e})") from None
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as e:
        raise ConfigError(f"{path}:{e.lineno}:{e.colno}: not valid JSON ({e.msg}); the file is corrupt or truncated") from None
    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        got = doc.get("format") if isinstance(doc, dict) else type(doc).__name__
        raise ConfigError(f"{path}: key 'format' is {got!r}; expected {FORMAT!r} (a file written by save_identified)")
    version = doc.get("version")
    if version != VERSION:
        raise ConfigError(f"{path}: key 'version' is {version!r}; this code reads version {VERSION} (re-identify, or "
                          "load it with the version of the toolkit that wrote it)")
    kind = _get(doc, "kind", str, str(path))
    if kind not in KINDS:
        raise ConfigError(f"{path}: key 'kind' is {kind!r}; expected one of {KINDS}")
    Ts = _get(doc, "sample_period_s", (int, float), str(path))
    if not (math.isfinite(Ts) and Ts > 0):
        raise ConfigError(f"{path}: key 'sample_period_s' must be a finite number > 0, got {Ts!r}")
    prov = _get(doc, "provenance", dict, str(path))
    recorded = _get(prov, "log_sha256", str, f"{path}: provenance", nullable=True)
    if log_file is not None:
        actual = sha256(log_file)
        if recorded is None or actual != recorded:
            raise ConfigError(f"{path}: provenance.log_sha256 is {recorded!r} but {log_file} hashes to {actual}; the "
                              "model was identified on another log")
    stored = {"sample_period_s": float(Ts), "units": doc.get("units"), "fit_report": doc.get("fit_report"),
              "provenance": prov, "file": str(path)}
    m = _get(doc, "model", dict, str(path))
    where = f"{path}: model"
    if kind == "structure_fit":
        return _structure_fit(m, where, stored)
    return _identified_drive(m, where, stored)


def _structure_fit(m: dict, where: str, stored: dict) -> StructureFit:
    sd = _get(m, "structure", dict, where)
    try:
        st = ModelStructure(**sd)
    except (TypeError, ParameterError) as e:
        raise ConfigError(f"{where}.structure: not a valid model structure ({e})") from None
    names = st.pole_names + st.linear_names
    params = _finite_map(_get(m, "parameters", dict, where), names, f"{where}.parameters")
    std = _finite_map(_get(m, "std", dict, where), names, f"{where}.std", nullable=True) if m.get("std") else {}
    bad = [k for k in st.pole_names if not params[k] > 0]
    if bad:
        raise ConfigError(f"{where}.parameters: pole parameters {bad} must be > 0 (every structure's poles are stable "
                          f"for wn, zeta, p > 0), got {[params[k] for k in bad]}")
    initial = _get(m, "initial", str, where)
    info = dict(_get(m, "info", dict, where)) | {"stored": stored}
    return StructureFit(
        structure=st, parameters=params, std=std, loss=_num(_get(m, "loss", (int, float), where, nullable=True)),
        rms_um=_num(_get(m, "rms_um", (int, float), where, nullable=True)), converged=_get(m, "converged", bool, where),
        at_bound=tuple(_get(m, "at_bound", list, where)), initial=initial, method=_get(m, "method", str, where),
        source=_get(m, "source", str, where),
        wall_time_s=_num(_get(m, "wall_time_s", (int, float), where, nullable=True)), info=info)


def _identified_drive(m: dict, where: str, stored: dict) -> IdentifiedDrive:
    coeffs = _finite_map(_get(m, "coefficients", dict, where), COEFFICIENTS, f"{where}.coefficients")
    hist = m.get("history")
    if hist is not None:
        try:
            hist = np.array(hist, dtype=np.float64)
        except (TypeError, ValueError):
            raise ConfigError(f"{where}.history: must be a table of numbers") from None
    info = dict(_get(m, "info", dict, where)) | {"stored": stored}
    return IdentifiedDrive(
        method=_get(m, "method", str, where), coefficients=coeffs,
        loss=_num(_get(m, "loss", (int, float), where, nullable=True)), loss_kind=_get(m, "loss_kind", str, where),
        wall_time_s=_num(_get(m, "wall_time_s", (int, float), where, nullable=True)),
        iterations=_get(m, "iterations", int, where), source=_get(m, "source", str, where), history=hist, info=info)
