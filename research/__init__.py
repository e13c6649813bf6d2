"""Research toolkit for CNC motion control.

Data flows one way (see ``../shared/DESIGN.md``)::

    paths -> interpolators -> Trajectory -> drives -> contour -> metrics -> experiments -> figures

Units inside the package: mm, s, rad. float64 everywhere: importing the package sets
``jax_enable_x64``.

Compiled JAX functions are kept on disk (JAX's persistent compilation cache), so a path size seen
once does not cost a fresh compile in a later process: in ``$RESEARCH_JAX_CACHE`` if set (``off``
disables it), else ``~/.cache/research/jax``. Array shapes are also bucketed (16 sizes per octave,
see :func:`research.piecewise.bucket_size`), so paths of similar size share one compiled function.
The FIR planner's Numba kernels are compiled on their first use after an install and kept in
``__pycache__`` beside their modules (Numba's own cache; ``$NUMBA_CACHE_DIR`` moves it): the first
plan of a fresh install pays that once (``benchmarks/bench_cold_start.py``), later processes load it.
"""

import os as _os
import sys as _sys

# float64 and the disk cache are set through JAX's environment variables, read when jax is imported,
# so `import research` (and `python -m research figures --list`) does not import jax itself; where jax
# is already imported the same settings go through its config.
_os.environ["JAX_ENABLE_X64"] = "1"


def _compilation_cache() -> None:
    where = _os.environ.get("RESEARCH_JAX_CACHE", _os.path.join(_os.path.expanduser("~"), ".cache", "research", "jax"))
    if where.lower() in ("off", "0", "none", ""):
        return
    try:
        _os.makedirs(where, exist_ok=True)
    except OSError:  # read-only home: run without the disk cache
        return
    _os.environ["JAX_COMPILATION_CACHE_DIR"] = where
    _os.environ["JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS"] = "0.2"
    if "jax" in _sys.modules:
        _sys.modules["jax"].config.update("jax_compilation_cache_dir", where)
        _sys.modules["jax"].config.update("jax_persistent_cache_min_compile_time_secs", 0.2)


if "jax" in _sys.modules:
    _sys.modules["jax"].config.update("jax_enable_x64", True)
_compilation_cache()

from research.errors import (  # noqa: E402
    ConfigError,
    DriveLogError,
    GCodeError,
    InfeasibleProblem,
    ParameterError,
    PathError,
    ResearchError,
)


def __getattr__(name: str):
    """``research.PiecewisePolynomial`` and ``research.Trajectory`` are imported on first use (they import jax)."""
    if name == "PiecewisePolynomial":
        from research.piecewise import PiecewisePolynomial

        return PiecewisePolynomial
    if name == "Trajectory":
        from research.trajectory import Trajectory

        return Trajectory
    raise AttributeError(f"module 'research' has no attribute {name!r}")


__all__ = [
    "ConfigError",
    "DriveLogError",
    "GCodeError",
    "InfeasibleProblem",
    "ParameterError",
    "PathError",
    "PiecewisePolynomial",
    "ResearchError",
    "Trajectory",
]
__version__ = "0.1.0"
