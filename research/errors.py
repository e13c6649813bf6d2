"""Specific exceptions for bad input. Each message names the file, line, field or index at fault
and what was expected, so a user can fix the input without reading the code."""


class ResearchError(Exception):
    """Base class of every error this package raises on purpose."""


class PathError(ResearchError, ValueError):
    """A tool path is unusable: empty, NaN coordinates, zero-length segment, wrong shape."""


class GCodeError(PathError):
    """Malformed or unsupported G-code.

    Attributes:
        source: file name or ``"<string>"``.
        line: 1-based line number.
        column: 1-based column of the offending word.
    """

    def __init__(self, message: str, *, source: str = "<string>", line: int = 0, column: int = 0):
        self.source, self.line, self.column = source, line, column
        super().__init__(f"{source}:{line}:{column}: {message}")


class ParameterError(ResearchError, ValueError):
    """A numeric parameter is out of its domain (feed <= 0, delay <= 0, tolerance < 0, NaN ...)."""


class ConfigError(ResearchError, ValueError):
    """An experiment config has a typo, a wrong type or a wrong unit; the message names file and key."""


class DriveLogError(ResearchError, ValueError):
    """A drive log is unusable (NaN, non-monotonic time, missing column); names file, column, index."""


class StoreError(ResearchError, OSError):
    """The results store (or an output folder) cannot be read or written: full disk, no permission,
    read-only file system, or an entry that changed under the reader; names the folder or file."""


class InfeasibleProblem(ResearchError, RuntimeError):
    """An optimisation problem has no solution under the stated limits; carries diagnostics."""


class ConvergenceError(ResearchError, RuntimeError):
    """An iteration stopped before reaching its tolerance (e.g. the CEC mirror loop).

    Attributes:
        residual: the size of the residual when it stopped, in the unit the message states.
        steps: iterations taken.
        result: the last iterate (or a result object holding it), for inspection only.
    """

    def __init__(self, message: str, *, residual: float, steps: int, result=None):
        self.residual, self.steps, self.result = residual, steps, result
        super().__init__(message)


class UnstableGainsError(ParameterError):
    """A controller gain set gives an unstable closed loop (research.control); names the axis or
    direction and the offending discrete-time eigenvalue.

    Attributes:
        where: axis (``"x"`` ... ``"c"``) or Frenet direction (``"tangent"``, ``"normal"``, ``"binormal"``).
        eigenvalue: the closed-loop eigenvalue ``z`` with ``|z| >= 1`` (complex).
    """

    def __init__(self, message: str, *, where: str, eigenvalue: complex):
        self.where, self.eigenvalue = where, eigenvalue
        super().__init__(message)


class FrenetFrameError(PathError):
    """The Frenet frame of a tool-tip path is undefined (zero curvature or zero path speed) over a
    stretch; names the parameter range and what was expected (research.control)."""
