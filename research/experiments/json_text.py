"""Readable JSON for result files: objects indented, every list of numbers on one line.

``json.dumps(..., indent=2)`` puts each number of a list on its own line and runs the pure-Python
encoder (the C one serves only unindented output): a 76,461-chord program's ``results.json`` was
17 MB, 1.4 million lines, and took 2 s to write (twice: the store's ``record.json`` too). Here the
lists of numbers are encoded apart, unindented (the C encoder), and put back into the indented
text: the same values in the same ``repr`` digits, the same structure for ``json.load``.
"""

from __future__ import annotations

import json
import re
import secrets

import numpy as np


def dumps(obj, indent: int = 2, default=None) -> str:
    """``json.dumps(obj, indent=indent, default=default)`` with every list (or tuple) whose items
    are all numbers written on one line.

    Example:
        >>> print(dumps({"a": [1, 2.5], "b": {"c": "x"}}))
        {
          "a": [1, 2.5],
          "b": {
            "c": "x"
          }
        }
    """
    token = secrets.token_hex(8)  # a marker no string of the document holds
    inline: list[str] = []

    def walk(x):
        if isinstance(x, dict):
            return {k: walk(v) for k, v in x.items()}
        if isinstance(x, (list, tuple)):
            if x and all(_is_number(v) for v in x):
                inline.append(json.dumps(list(x), default=default))
                return f"{token}{len(inline) - 1}"
            return [walk(v) for v in x]
        return x

    text = json.dumps(walk(obj), indent=indent, default=default)
    return re.sub(f'"{token}(\\d+)"', lambda m: inline[int(m.group(1))], text)


def _is_number(v) -> bool:
    """A JSON number: an int or float, NumPy's too (written through ``default``), not a bool."""
    return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool)
