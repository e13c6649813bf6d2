"""Research toolkit for CNC motion control.

Data flows one way (see ``../shared/DESIGN.md``)::

    paths -> interpolators -> Trajectory -> drives -> contour -> metrics -> experiments -> figures

Units inside the package: mm, s, rad. float64 everywhere: importing the package sets
``jax_enable_x64``.
"""

import jax as _jax

_jax.config.update("jax_enable_x64", True)

from research.errors import (  # noqa: E402
    ConfigError,
    DriveLogError,
    GCodeError,
    InfeasibleProblem,
    ParameterError,
    PathError,
    ResearchError,
)
from research.piecewise import PiecewisePolynomial  # noqa: E402
from research.trajectory import Trajectory  # noqa: E402

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
