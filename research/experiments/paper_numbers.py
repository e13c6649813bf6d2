"""The paper numbers a config declares (``[[paper]]`` tables), checked against a result record.

A key is either a result scalar (``"half.cycle_time"``, as in ``record["scalars"]``) or a path into the
record's details, ``"details.<label>.<field>"`` with ``[i]`` list indices
(``"details.full.metrics.peak_acceleration[1]"``).

Example:
    >>> rec = {"scalars": {"cycle_time": 0.14}, "details": {"fir": {"overlap_times": [0.0]}}}
    >>> lookup(rec, "details.fir.overlap_times[0]"), lookup(rec, "cycle_time")
    (0.0, 0.14)
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from research.errors import ConfigError


@dataclass(frozen=True)
class PaperCheck:
    """One declared paper number against the result.

    Attributes:
        key, expected, tolerance, source: as declared; value: the result's; ok: ``|value - expected| <= tolerance``.
    """

    key: str
    value: float
    expected: float
    tolerance: float
    source: str
    reproduced: bool = True
    reason: str | None = None

    @property
    def ok(self) -> bool:
        return abs(self.value - self.expected) <= self.tolerance

    @property
    def verdict(self) -> str:
        """``PASS`` / ``MISS`` for a number the config reproduces; for one declared not reproduced,
        ``NOT REPRODUCED (reason)``, or ``MISS`` should it now agree (the declaration is out of date)."""
        if self.reproduced:
            return "PASS" if self.ok else "MISS"
        return f"NOT REPRODUCED ({self.reason})" if not self.ok else "MISS (declared not reproduced, but agrees)"

    def line(self) -> str:
        """``key = value (paper expected +- tolerance, source): verdict``."""
        return (f"{self.key} = {self.value:.6g} (paper {self.expected:.6g} +- {self.tolerance:.3g}; {self.source}): "
                + self.verdict)

    @property
    def holds(self) -> bool:
        """What the figure tests assert: a reproduced number agrees, a number declared not reproduced does not."""
        return self.ok == self.reproduced


def lookup(record: dict, key: str) -> float:
    """The number ``key`` names in ``record`` (module docstring).

    Raises:
        ConfigError: no such scalar or detail (the known scalars are listed).
    """
    if key in record.get("scalars", {}):
        return float(record["scalars"][key])
    if not key.startswith("details."):
        raise ConfigError(f"paper number key {key!r}: no such result scalar; scalars: {sorted(record.get('scalars', {}))} "
                          "(or give a path details.<label>.<field>[i])")
    node = record
    for part in re.findall(r"[^.\[\]]+|\[\d+\]", key):
        try:
            node = node[int(part[1:-1])] if part.startswith("[") else node[part]
        except (KeyError, IndexError, TypeError):
            raise ConfigError(f"paper number key {key!r}: {part!r} not found in the result record") from None
    if isinstance(node, (list, dict)):
        raise ConfigError(f"paper number key {key!r} names a {type(node).__name__}, not a number; add [i] or a field")
    return float(node)


def check_paper_numbers(cfg, record: dict) -> list[PaperCheck]:
    """Every ``[[paper]]`` number of ``cfg`` against ``record``.

    Raises:
        ConfigError: a key the record does not have.
    """
    return [PaperCheck(p.key, lookup(record, p.key), p.value, p.tolerance, p.source, p.reproduced, p.reason)
            for p in cfg.paper]
