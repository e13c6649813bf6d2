"""Export a :class:`~research.trajectory.Trajectory` (issue 16 item 7): a CSV table of the samples with
units in the header, and a G-code stream a controller can run (one ``G1`` per sample period).

- :func:`trajectory_csv`: columns ``t [s]``, then ``q_<axis> [mm]``, ``v_<axis> [mm/s]``,
  ``a_<axis> [mm/s^2]``, ``j_<axis> [mm/s^3]`` for each axis.
- :func:`trajectory_gcode`: ``G21 G90 G94``, the path mode (``G64 P<tol>`` with a tolerance, ``G61``
  exact path without), a ``G0`` to the first sample, then one ``G1`` per sample step at its mean
  speed ``F = |q_k+1 - q_k| / Ts`` [mm/min]. Samples that move less than ``min_step_mm`` are merged
  into the next move, whose feed then covers their time, so the stream keeps the trajectory's timing
  (no ``G4`` dwell: the package's reader has no pauses). Coordinates are written with the shortest
  decimal that reads back as the same float.

Example:
    >>> import numpy as np
    >>> tr = Trajectory.from_positions(np.arange(3) * 1e-3, np.array([[0.0, 0.0], [0.1, 0.0], [0.2, 0.1]]), ("x", "y"))
    >>> print(trajectory_gcode(tr), end="")
    %
    (research.experiments.export: 3 samples, Ts = 1 ms, duration 0.002 s)
    G21 G90 G17 G94
    G61
    G0 X0 Y0
    G1 X0.1 F6000
    X0.2 Y0.1 F8485.2814
    M30
    %
"""

from __future__ import annotations

import io

import numpy as np

from research.errors import ParameterError
from research.trajectory import Trajectory

#: default smallest move written as its own G1 [mm]; shorter steps are merged into the next move
MIN_STEP_MM = 1e-6
#: axis letters a G-code stream may carry
GCODE_AXES = ("x", "y", "z")


def trajectory_csv(traj: Trajectory) -> str:
    """The samples as CSV text (header with units; ``repr`` precision, so values read back exactly)."""
    names = ["t [s]"] + [f"{k}_{a} [{u}]" for k, u in (("q", "mm"), ("v", "mm/s"), ("a", "mm/s^2"), ("j", "mm/s^3"))
                         for a in traj.axes]
    table = np.column_stack([np.asarray(traj.t)] + [np.asarray(getattr(traj, k)) for k in ("q", "v", "a", "j")])
    buf = io.StringIO()
    buf.write(",".join(names) + "\n")
    np.savetxt(buf, table, delimiter=",", fmt="%.17g")
    return buf.getvalue()


def _num(v: float) -> str:
    return np.format_float_positional(float(v), unique=True, trim="-")


def trajectory_gcode(traj: Trajectory, tolerance_mm: float = 0.0, *, min_step_mm: float = MIN_STEP_MM,
                     feed_digits: int = 4) -> str:
    """The trajectory as a G-code stream (module docstring).

    Args:
        traj: a sampled trajectory on axes among ``x, y, z`` [mm].
        tolerance_mm: path-blending tolerance the controller may use between the samples: ``G64 P<tol>``
            when > 0, else ``G61`` (exact path).
        min_step_mm: steps shorter than this are merged into the next move [mm].
        feed_digits: decimals of the F words [mm/min].
    Returns:
        the program text, ending with ``M30`` and ``%``.
    Raises:
        ParameterError: an axis other than x, y, z, a negative tolerance, or a non-positive ``min_step_mm``.
    """
    bad = [a for a in traj.axes if a not in GCODE_AXES]
    if bad:
        raise ParameterError(f"a G-code stream carries axes {GCODE_AXES}; the trajectory has {bad}")
    if not (np.isfinite(tolerance_mm) and tolerance_mm >= 0):
        raise ParameterError(f"tolerance_mm must be a finite length >= 0 mm, got {tolerance_mm!r}")
    if not min_step_mm > 0:
        raise ParameterError(f"min_step_mm must be > 0 mm, got {min_step_mm!r}")
    t, q = np.asarray(traj.t, dtype=np.float64), np.asarray(traj.q, dtype=np.float64)
    letters = [a.upper() for a in traj.axes]
    out = ["%", f"(research.experiments.export: {t.size} samples, Ts = {traj.sample_period * 1e3:g} ms, "
                f"duration {float(traj.duration):g} s)", "G21 G90 G17 G94",
           f"G64 P{_num(tolerance_mm)}" if tolerance_mm > 0 else "G61",
           "G0 " + " ".join(f"{L}{_num(x)}" for L, x in zip(letters, q[0]))]
    last, last_t, mode, feed = q[0], t[0], "G0", None
    for k in range(1, t.size):
        step = float(np.linalg.norm(q[k] - last))
        if step < min_step_mm and k < t.size - 1:
            continue
        if step == 0.0:
            break
        words = [f"{L}{_num(x)}" for L, x, p in zip(letters, q[k], last) if x != p]
        f = round(step / (t[k] - last_t) * 60.0, feed_digits)
        if f <= 0:
            raise ParameterError(f"sample {k}: a feed of {step / (t[k] - last_t) * 60.0:g} mm/min rounds to 0; "
                                 "raise feed_digits or min_step_mm")
        if f != feed:
            words.append(f"F{_num(f)}")
        out.append(("G1 " if mode != "G1" else "") + " ".join(words))
        last, last_t, mode, feed = q[k], t[k], "G1", f
    return "\n".join(out + ["M30", "%"]) + "\n"
