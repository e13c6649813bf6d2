"""Lazy public names of a package (PEP 562): a package's ``__init__`` maps each public name to the private
module defining it, and the module is imported on first use of the name, so importing the package costs
nothing (see :mod:`research.identification`, :mod:`research.experiments`)."""

from __future__ import annotations

import importlib


def lazy_exports(package: str, exports: dict[str, str], namespace: dict):
    """``(__getattr__, __dir__)`` for the package ``package`` whose public name ``n`` lives in the module
    ``package + "." + exports[n]``; a name, once imported, is stored in ``namespace`` (the package's
    ``globals()``), so later lookups are plain attribute reads.

    Raises (from ``__getattr__``):
        AttributeError: a name not in ``exports``, as for any module.
    """

    def __getattr__(name: str):
        if name not in exports:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(f"{package}.{exports[name]}"), name)
        namespace[name] = value
        return value

    def __dir__():
        return sorted(set(namespace) | set(exports))

    return __getattr__, __dir__
