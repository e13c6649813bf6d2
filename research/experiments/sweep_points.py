"""Sweep points: expand a ``[sweep]`` table into per-point configs (grid or list over any field).

Fields are addressed in the config's own key names: ``"interpolator.delays_ms[0]"``,
``"interpolator.tolerance_um"``, ``"drive.modes[1].frequency_hz"``, ``"identification.noise_um"``.
A single ``[interpolator]`` table needs no index (``interpolator.x`` means ``interpolator[0].x``).
Each point is the base config with its fields replaced, validated again: a value out of range makes
that point fail (recorded, the sweep goes on), a field that does not exist is a
:class:`~research.errors.ConfigError` before anything runs.

Example:
    >>> from research.experiments.config import validate
    >>> cfg = validate({"name": "s", "reproduces": "-", "path": {"name": "diamond"},
    ...                 "sweep": {"parameters": {"interpolator.delays_ms[0]": [100.0, 148.0],
    ...                                          "interpolator.tolerance_um": [50.0, 500.0]}}}, "s.toml")
    >>> points = expand(cfg, "s.toml")
    >>> len(points), points[3].values
    (4, {'interpolator.delays_ms[0]': 148.0, 'interpolator.tolerance_um': 500.0})
"""

from __future__ import annotations

import difflib
import itertools
import re
from dataclasses import dataclass
from pathlib import Path

from research.errors import ConfigError
from research.experiments.config import ExperimentConfig, validate

_TOKEN = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)|\[(\d+)\]|\.")


@dataclass(frozen=True)
class Point:
    """One sweep point: its index, the swept values, and its validated config (``None`` with ``error``)."""

    index: int
    values: dict
    config: ExperimentConfig | None
    error: str | None = None


def parse_field(field: str) -> list[str | int]:
    """``"drive.modes[1].frequency_hz"`` -> ``["drive", "modes", 1, "frequency_hz"]``."""
    parts, pos = [], 0
    for m in _TOKEN.finditer(field):
        if m.start() != pos:
            break
        pos = m.end()
        if m.group(1):
            parts.append(m.group(1))
        elif m.group(2):
            parts.append(int(m.group(2)))
    if pos != len(field) or not parts:
        raise ValueError(f"cannot parse field {field!r}; write e.g. 'interpolator.delays_ms[0]'")
    return parts


def set_field(raw: dict, field: str, value, template: dict | None = None) -> dict:
    """A copy of ``raw`` with ``field`` set to ``value`` (raises ``KeyError``/``IndexError`` if absent).

    ``template``: the same config with every field (its defaults too); a field ``raw`` leaves out
    (a default the config did not write) is added where ``template`` has it, a table on the way as
    an empty one (its other fields stay defaults, not written), a list as the template's."""
    parts = parse_field(field)
    out = _copy(raw)
    node, tnode = out, template
    for i, part in enumerate(parts):
        last = i == len(parts) - 1
        if isinstance(part, str) and isinstance(node, list) and len(node) == 1:
            node = node[0]  # interpolator.x on a single interpolator
            tnode = tnode[0] if isinstance(tnode, list) and len(tnode) == 1 else None
        if isinstance(part, int):
            if not isinstance(node, list) or not 0 <= part < len(node):
                raise IndexError(f"index [{part}] out of range")
        elif not isinstance(node, dict) or part not in node:
            if not (isinstance(node, dict) and isinstance(tnode, dict) and tnode.get(part) is not None):
                raise KeyError(part)
            node[part] = {} if isinstance(tnode[part], dict) else _copy(tnode[part])
        if last:
            node[part] = value
        else:
            if node[part] is None:
                raise KeyError(part)
            node = node[part]
            tnode = _child(tnode, part)
    return out


def _child(tnode, part):
    """``tnode[part]`` of a template node, or None where it has none."""
    if isinstance(part, int):
        return tnode[part] if isinstance(tnode, list) and 0 <= part < len(tnode) else None
    return tnode.get(part) if isinstance(tnode, dict) else None


def expand(cfg: ExperimentConfig, file: str | Path) -> list[Point]:
    """All points of ``cfg.sweep`` (grid: every combination, first field slowest; list: zipped).

    Raises:
        ConfigError: a swept field the config does not have, or list sweeps of unequal lengths.
    """
    sweep = cfg.sweep
    if sweep is None:
        raise ConfigError(f"{file}: no [sweep] table; add [sweep.parameters] with the fields to sweep")
    values = sweep.values()
    fields = list(values)
    if sweep.mode == "list":
        lengths = {k: len(v) for k, v in values.items()}
        if len(set(lengths.values())) != 1:
            raise ConfigError(f"{file}: key 'sweep.parameters': list sweeps need equal lengths, got {lengths}")
        combos = list(zip(*values.values()))
    else:
        combos = list(itertools.product(*values.values()))
    # each point is the config as written (the fields it sets) with the swept ones set: a default it
    # did not write stays unwritten (stages read what a config sets: a G-code program's own F words
    # unless [interpolator] sets feed_mm_per_s), the full config only says which fields exist
    template = cfg.model_dump(mode="json", exclude={"sweep"}, exclude_none=True)
    base = cfg.model_dump(mode="json", exclude={"sweep"}, exclude_none=True, exclude_unset=True)
    for f in fields:  # a field that does not exist is an error of the config, not of a point
        try:
            set_field(base, f, values[f][0], template)
        except ValueError as e:
            raise ConfigError(f"{file}: key 'sweep.parameters.\"{f}\"': {e}") from None
        except (KeyError, IndexError) as e:
            close = difflib.get_close_matches(f, field_names(template), n=1, cutoff=0.6)
            raise ConfigError(f"{file}: key 'sweep.parameters.\"{f}\"': the config has no field {f!r} "
                              f"({e.args[0] if e.args else e})" + (f"; did you mean {close[0]!r}?" if close else "")
                              + "; fields are written as in the config, e.g. 'interpolator.delays_ms[0]'") from None
    points = []
    for i, combo in enumerate(combos):
        raw = base
        for f, v in zip(fields, combo):
            raw = set_field(raw, f, v, template)
        point_values = dict(zip(fields, combo))
        try:
            points.append(Point(i, point_values, validate(raw, file)))
        except ConfigError as e:
            points.append(Point(i, point_values, None, f"ConfigError: {e}"))
    return points


def field_names(raw: dict) -> list[str]:
    """Every sweepable field of a config dictionary, dotted as :func:`parse_field` reads them
    (``"interpolator.delays_ms[0]"``; a single interpolator also without its index)."""
    out = []

    def walk(node, prefix):
        if isinstance(node, dict):
            for k, v in node.items():
                walk(v, f"{prefix}.{k}" if prefix else k)
        elif isinstance(node, list) and node:
            if len(node) == 1 and isinstance(node[0], dict):
                walk(node[0], prefix)  # interpolator.x on a single interpolator
            for i, v in enumerate(node):
                walk(v, f"{prefix}[{i}]")
            if not isinstance(node[0], (dict, list)):
                out.append(prefix)
        elif prefix:
            out.append(prefix)

    walk(raw, "")
    return out


def _copy(x):
    if isinstance(x, dict):
        return {k: _copy(v) for k, v in x.items()}
    if isinstance(x, list):
        return [_copy(v) for v in x]
    return x
