"""Validation errors as :class:`~research.errors.ConfigError` lines: ``<file>: key '<dotted.key>': <what was
expected> (got <value>)``, with a hint for the usual slips (a bool or a string where a number goes, a decimal
point in an int, a scalar where an array goes) and ``did you mean`` for an unknown key close to a known one.
"""

from __future__ import annotations

import difflib
import re
from pathlib import Path
from typing import get_args

from pydantic import BaseModel

from research.experiments.config_interpolator import INTERPOLATOR_KINDS
from research.experiments.config_path import PATH_KINDS


def describe_error(err: dict, file: Path, single_interpolator: bool, root: type[BaseModel]) -> str:
    """One pydantic error ``err`` of validating ``file`` against the model ``root`` as a message line
    (``single_interpolator``: the config gave one ``[interpolator]`` table, so its list index is dropped)."""
    loc = list(err["loc"])
    if loc[:1] == ["interpolator"]:  # drop the union tag, and the list index of a single [interpolator] table
        loc = ["interpolator"] + [p for p in loc[1 + single_interpolator:] if p not in INTERPOLATOR_KINDS]
    elif loc[:1] == ["path"]:  # drop the path kind tag
        loc = ["path"] + [p for p in loc[1:] if p not in PATH_KINDS]
    key = "".join(f"[{p}]" if isinstance(p, int) else f".{p}" for p in loc).lstrip(".") or "(top level)"
    msg = err["msg"].removeprefix("Value error, ")
    kind, value = err["type"], err.get("input")
    named = re.match(r"([A-Za-z_]+(?:\[\d+\])?) = ", msg) if kind == "value_error" else None
    if named and isinstance(value, dict) and named.group(1).split("[")[0] in value:  # a table check naming its key
        key = f"{key}.{named.group(1)}"
    if kind == "extra_forbidden":
        msg = "unknown key (typo?" + _suggest(err["loc"], root) + ")"
    elif kind.startswith(("float", "int")) and isinstance(value, bool):
        msg += "; a bool is not a number"
    elif kind.startswith(("float", "int")) and isinstance(value, str):
        msg += ("; give a plain number, the unit is in the key name" if any(c.isalpha() for c in value)
                else "; give a number, not a string (no quotes)")
    elif kind == "int_type" and isinstance(value, float):
        msg += "; give a whole number without a decimal point"
    elif kind == "finite_number":
        msg += " (inf and nan are not allowed)"
    elif kind == "list_type" and isinstance(value, (str, int, float)):
        msg += f"; give an array, e.g. [{_toml(value)}]"
    elif kind == "bool_type":
        msg += "; give true or false (no quotes)"
    shown = repr(value)
    shown = shown if len(shown) <= 120 else shown[:100] + " ... " + shown[-15:]
    got = "" if kind in ("missing", "extra_forbidden") or isinstance(value, dict) else f" (got {shown})"
    return f"{file}: key '{key}': {msg}{got}"


def _toml(value) -> str:
    return f'"{value}"' if isinstance(value, str) else str(value).lower() if isinstance(value, bool) else repr(value)


def _suggest(loc: tuple, root: type[BaseModel]) -> str:
    """`` did you mean 'x'?`` for an unknown key close to a known one of the same table."""
    models = [root]
    for part in loc[:-1]:
        if not isinstance(part, str):
            continue
        tagged = [m for m in models if "kind" in m.model_fields and part in get_args(m.model_fields["kind"].annotation)]
        if tagged:  # a discriminated-union tag (interpolator kind)
            models = tagged
            continue
        field = next((m.model_fields[part] for m in models if part in m.model_fields), None)
        models = models_in(field.annotation) if field is not None else models
    known = [k for m in models for k in m.model_fields]
    close = difflib.get_close_matches(str(loc[-1]), known, n=1, cutoff=0.6)
    return f" did you mean '{close[0]}'?" if close else ""


def models_in(annotation) -> list[type[BaseModel]]:
    """Pydantic models inside an annotation (through Optional, list, Union, Annotated)."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation]
    return [m for a in get_args(annotation) for m in models_in(a)]
