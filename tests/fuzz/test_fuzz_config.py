"""Fuzz tests of the experiment-config loader: random TOML documents over the schema's keys with values of
every TOML type (finite, huge, inf, nan, bools, strings, arrays, tables), and random byte damage of a valid file.

Only :class:`ConfigError` may escape ``load_config``; an accepted config must round-trip (its JSON dump
validates again to an equal config) and hold only finite numbers.

Examples per test: ``RESEARCH_FUZZ_EXAMPLES`` (default 100; the file runs in a few seconds); set it to
10000 for a long run.
"""

from __future__ import annotations

import math
import os
import tempfile
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from research.errors import ConfigError
from research.experiments.config import ExperimentConfig, load_config, validate

EXAMPLES = int(os.environ.get("RESEARCH_FUZZ_EXAMPLES", "100"))
FUZZ = settings(max_examples=EXAMPLES, deadline=None, derandomize=EXAMPLES <= 200,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
FOLDER = Path(tempfile.mkdtemp(prefix="fuzz_config_"))

SCALARS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True), st.floats(-1e3, 1e3, allow_nan=False),
    st.integers(-10, 10**6), st.integers(), st.booleans(),
    st.sampled_from(["", "250", "250 mm/s", "fir", "x", "..", "diamond", "corner90", "ls", "grid", "ideal",
                     "sencer2009_table6_1", "a\u00e9", "yes", "inf"]),
)
VALUES = st.recursive(SCALARS, lambda inner: st.lists(inner, max_size=4), max_leaves=8)
KEYS = {
    "path": ["name", "gcode", "points_mm", "chord_tolerance_um", "nme"],
    "interpolator": ["kind", "label", "feed_mm_per_s", "delays_ms", "tolerance_um", "sample_period_ms", "refine",
                     "envelope_delays_ms", "intervals_per_segment", "window", "feed_mm_per_min"],
    "drive": ["model", "modes", "settle_time_s"],
    "identification": ["method", "truth", "n_moves", "noise_um", "resolution_um", "seed"],
    "output": ["figure"],
}
POINTS = st.lists(st.lists(st.one_of(st.floats(-100, 100, allow_nan=False), st.integers(-5, 5), SCALARS),
                           min_size=0, max_size=4), max_size=6)
MODES = st.lists(st.fixed_dictionaries({"axis": st.sampled_from(["x", "y", "z", "q", 1]),
                                        "frequency_hz": SCALARS, "damping": SCALARS}), max_size=2)


POSITIVE = st.one_of(st.floats(0.01, 1000.0), st.integers(1, 1000))
PLAUSIBLE = {  # values the schema accepts, so that accepted configs (and their round trip) are exercised
    "chord_tolerance_um": POSITIVE, "feed_mm_per_s": POSITIVE, "tolerance_um": POSITIVE, "sample_period_ms": POSITIVE,
    "delays_ms": st.lists(POSITIVE, min_size=1, max_size=3), "envelope_delays_ms": st.lists(POSITIVE, min_size=1, max_size=3),
    "refine": st.booleans(), "intervals_per_segment": st.integers(3, 30), "window": st.integers(1, 5),
    "settle_time_s": POSITIVE, "n_moves": st.integers(1, 100), "noise_um": POSITIVE, "resolution_um": POSITIVE,
    "seed": st.integers(0, 2**32), "figure": st.booleans(), "label": st.text(max_size=5),
    "model": st.sampled_from(["ideal", "sencer2009_table6_1"]), "method": st.sampled_from(["ls", "pso"]),
    "kind": st.sampled_from(["fir", "time_optimal"]),
    "points_mm": st.lists(st.tuples(st.floats(-100, 100), st.floats(-100, 100)).map(list), min_size=2, max_size=5),
    "modes": st.lists(st.fixed_dictionaries({"axis": st.sampled_from(["x", "y"]), "frequency_hz": POSITIVE}), max_size=2),
}


@st.composite
def documents(draw) -> dict:
    doc = {"name": draw(st.one_of(st.just("fz"), st.just("fz"), st.text(max_size=8))),
           "reproduces": draw(st.one_of(st.just("-"), st.just("-"), SCALARS))}
    if draw(st.booleans()):
        doc["metrics"] = draw(st.one_of(st.lists(st.sampled_from(["cycle_time", "peak_feed", "nope"]), max_size=3), SCALARS))
    for table, keys in KEYS.items():
        if not draw(st.integers(0, 2)) and table != "path":
            continue
        chosen = draw(st.lists(st.sampled_from(keys), max_size=4, unique=True))
        t = {}
        for k in chosen:
            wild = POINTS if k == "points_mm" else MODES if k == "modes" else VALUES
            t[k] = draw(st.one_of(PLAUSIBLE[k], PLAUSIBLE[k], wild) if k in PLAUSIBLE else wild)
        if table == "path" and "points_mm" not in t and draw(st.integers(0, 3)):
            t = {"name": "corner90"} | {k: v for k, v in t.items() if k == "chord_tolerance_um"}
        doc[table] = t
    return doc


def toml(doc: dict) -> str:
    """A TOML text of ``doc`` (top-level scalars, then one table per dict; inline tables in arrays)."""
    head = [f"{k} = {_value(v)}" for k, v in doc.items() if not isinstance(v, dict)]
    tables = [f"[{k}]\n" + "\n".join(f"{kk} = {_value(vv)}" for kk, vv in v.items())
              for k, v in doc.items() if isinstance(v, dict)]
    return "\n".join(head) + "\n" + "\n".join(tables) + "\n"


def _value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return "nan" if math.isnan(v) else ("inf" if v > 0 else "-inf") if math.isinf(v) else repr(v)
    if isinstance(v, int):
        return str(v)
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, dict):
        return "{" + ", ".join(f"{k} = {_value(x)}" for k, x in v.items()) + "}"
    return "[" + ", ".join(_value(x) for x in v) + "]"


def _finite_numbers(x) -> bool:
    if isinstance(x, float):
        return math.isfinite(x)
    if isinstance(x, dict):
        return all(_finite_numbers(v) for v in x.values())
    if isinstance(x, (list, tuple)):
        return all(_finite_numbers(v) for v in x)
    return True


def _check_accepted(cfg: ExperimentConfig, file: Path) -> None:
    dumped = cfg.model_dump(mode="json")
    assert _finite_numbers(dumped)
    assert validate(dumped, file) == cfg  # round trip: the dump is itself a valid config



def _accepted_or_refused(f):
    """Load ``f``: a refusal must be a ConfigError naming the file (returns None); an accepted config
    must pass :func:`_check_accepted` (returned)."""
    try:
        cfg, _ = load_config(f)
    except ConfigError as e:
        assert str(f) in str(e)
        return None
    _check_accepted(cfg, f)
    return cfg

@FUZZ
@given(documents())
def test_random_documents_raise_only_config_error_and_accepted_ones_round_trip(doc):
    f = FOLDER / "doc.toml"
    f.write_text(toml(doc))
    cfg = _accepted_or_refused(f)
    if cfg is None:
        return
    if cfg.path is not None and cfg.path.points_mm is not None:
        pts = cfg.path.points_mm
        assert len(pts) >= 2 and len({len(p) for p in pts}) == 1 and 1 <= len(pts[0]) <= 3
        assert all(a != b for a, b in zip(pts, pts[1:]))


GOOD = (b'name = "g"\nreproduces = "-"\n[path]\npoints_mm = [[0.0, 0.0], [10.0, 0.0], [10.0, 5.0]]\n'
        b'[interpolator]\nfeed_mm_per_s = 200.0\ndelays_ms = [50.0, 30.0]\ntolerance_um = 100.0\n'
        b'[drive]\nmodes = [{axis = "x", frequency_hz = 11.4}]\n[identification]\nn_moves = 10\n')


@FUZZ
@given(st.lists(st.tuples(st.integers(0, len(GOOD) - 1), st.binary(min_size=0, max_size=3)), min_size=1, max_size=4))
def test_damaged_bytes_raise_only_config_error(edits):
    data = bytearray(GOOD)
    for pos, new in edits:
        pos = min(pos, len(data))
        data[pos:pos + 1] = new
    f = FOLDER / "damaged.toml"
    f.write_bytes(bytes(data))
    _accepted_or_refused(f)
