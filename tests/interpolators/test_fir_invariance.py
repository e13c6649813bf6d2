"""The plan does not depend on where the part sits on the table: a program moved by a work offset
(machine coordinates of a metre and more) or turned in its plane runs in the same time.

Reference: the FIR chain filters every axis alike and the tolerance is a Euclidean distance, so
without per-axis limits translating or rotating the path moves the trajectory with it and leaves
every corner error, deviation and cycle time unchanged (Sencer 2015 eqs 1-8: all terms are
differences of positions and norms of velocity changes). What is tested is the planner's rounding:
its decisions are thresholds on computed errors, and a bad conditioning of large coordinates (a
distance taken between points of 1e3 mm to a few nm) would flip them. Measured on 240 plans: at
most 1.1e-10 relative."""

import numpy as np
import pytest

from research.interpolators import plan_fir
from research.paths.library import random_program
from research.paths.toolpath import ToolPath

DELAYS = (0.06, 0.03)


def _moved(tp: ToolPath, shift, angle: float) -> ToolPath:
    """``tp`` turned by ``angle`` [rad] about the origin, then moved by ``shift`` [mm] (2-D)."""
    c, s = np.cos(angle), np.sin(angle)
    R = np.array([[c, -s], [s, c]])

    def f(p):
        return np.asarray(p) @ R.T + np.asarray(shift)

    centers = np.where(np.isnan(tp.centers), np.nan, f(np.nan_to_num(tp.centers)))
    return ToolPath(f(tp.start), f(tp.ends), centers, tp.normals, tp.sweeps)


@pytest.mark.parametrize("arcs", [False, True])
def test_cycle_time_is_unchanged_by_a_work_offset_and_a_rotation(arcs):
    """Random programs (seeds 0-9) moved by (1234.5, -678.9) mm and turned by 0.7 rad: the same
    cycle time to 1e-9 relative, and the same largest corner error to 1e-9 mm."""
    for seed in range(10):
        rng = np.random.default_rng(seed)
        tp = random_program(rng, arcs=arcs)
        eps, feed = float(np.exp(rng.uniform(np.log(0.005), np.log(0.5)))), float(rng.uniform(20.0, 300.0))
        base = plan_fir(tp, feed, DELAYS, eps)
        for shift, angle in (((1234.5, -678.9), 0.0), ((0.0, 0.0), 0.7), ((-2500.0, 3100.0), -2.1)):
            moved = plan_fir(_moved(tp, shift, angle), feed, DELAYS, eps)
            assert float(moved.cycle_time) == pytest.approx(float(base.cycle_time), rel=1e-9), (seed, shift, angle)
            assert float(np.max(moved.corner_errors, initial=0.0)) == pytest.approx(
                float(np.max(base.corner_errors, initial=0.0)), abs=1e-9), (seed, shift, angle)
