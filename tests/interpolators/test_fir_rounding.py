"""The FIR planner's checks against the rounding of long profiles (``_fir_verify.profile_rounding``).

Regression: the exact profile was built in absolute time, so its rounding grew with the time it
spans (about as its square: 0.6 nm after 427 s, 10 nm after 1,696 s on an adaptive-clearing
program). The checks held it to the tolerance up to 1 pm, so on long programs they "repaired"
rounding: arcs whose eq 8 feed puts their deviation at the tolerance exactly were slowed by 2 %
from some 530 s into the program on, which made the plan of a stretch depend on when it ran (and
the branch and bound check more candidates the longer the program: planning ~ blocks^1.4). The
checks then accepted the measured rounding as slack; since the breaks and running integrals are
double-doubles (``_fir_profile``) the rounding itself stays at the picometre level.
"""

from __future__ import annotations

import numpy as np
import pytest

from research.interpolators import plan_fir
from research.interpolators._fir_kernels import VERIFY_ATOL
from research.interpolators._fir_verify import profile_rounding
from research.paths.gcode import parse_gcode
from research.paths.toolpath import ToolPath
from research.piecewise import NumpyPiecewise

DELAYS = (0.06, 0.03)  # T1, T2 [s]
EPS = 0.05  # [mm]


def _loops(seed: int, loops: int) -> ToolPath:
    """A trochoidal clearing pass as G-code (3 decimals of mm, as posts write): per loop a G1 step,
    a G3 arc of radius 0.4-2 mm (centre words), a G1 link and a G2 return arc (R word), F 2400."""
    rng = np.random.default_rng(seed)
    out, x, y = ["G21 G90 G17 F2400"], 0.0, 0.0
    for _ in range(loops):
        r, step = rng.uniform(0.4, 2.0), rng.uniform(0.2, 0.6)
        x = round(x + step, 3)
        out.append(f"G1 X{x:.3f} Y{y:.3f}")
        cx, cy = x, y + r
        ex, ey = round(cx + r * np.sin(2.5), 3), round(cy - r * np.cos(2.5), 3)
        out.append(f"G3 X{ex:.3f} Y{ey:.3f} I{cx - x:.3f} J{cy - y:.3f}")
        x, y = round(ex + 0.3, 3), round(ey - 0.2, 3)
        out.append(f"G1 X{x:.3f} Y{y:.3f}")
        tx = round(x + 0.5, 3)
        out.append(f"G2 X{tx:.3f} Y0 R{0.5 * np.hypot(tx - x, y) + 0.3:.3f}")
        x, y = tx, 0.0
    return parse_gcode("\n".join(out + ["M2"]) + "\n", source="loops").blocks


def _after_lead_in(path: ToolPath, lead: float) -> tuple[ToolPath, np.ndarray]:
    """``path`` after a straight lead-in of ``lead`` seconds at 1 mm/s along its first direction
    (the rest at 40 mm/s, the loops' F 2400): the path and its block feeds [mm/s]."""
    u = path.tangents()[0][0]
    late = ToolPath(path.start - lead * 1.0 * u, np.vstack([path.start[None], path.ends]),
                    np.vstack([np.full((1, path.dim), np.nan), path.centers]),
                    np.vstack([np.zeros((1, 3)), path.normals]), np.concatenate([[0.0], path.sweeps]), path.axes)
    feed = np.full(late.n_blocks, 40.0)
    feed[0] = 1.0
    return late, feed


@pytest.fixture(scope="module")
def plans():
    """The loops after a lead-in of 10 s and of 20,000 s (5.6 h: the same stretch late in a long
    program, where each piece's times carry 2,000 times the rounding)."""
    loops = _loops(3, 150)
    out = {}
    for lead in (10.0, 20000.0):
        path, feed = _after_lead_in(loops, lead)
        out[lead] = (plan_fir(path, feed, DELAYS, EPS), path)
    return out


def test_a_stretch_plans_the_same_whenever_it_runs(plans):
    """The FIR output at ``t`` averages the input over ``[t - T_d, t]`` (Sencer 2015 eq 1-6), so the
    loops take the same time after a lead-in of 20,000 s as after one of 10 s (the cycle time less
    the lead-in's). Expected from that time invariance, up to 1 us (a thousand times the rounding
    of the time sums); before the fix the late copy took 0.307 s (0.5 %) longer: arcs slowed by
    2 % and more where only the profile's rounding (4.6 nm) broke the tolerance."""
    early, late = (float(plans[lead][0].cycle_time) - lead for lead in (10.0, 20000.0))
    assert late == pytest.approx(early, abs=1e-6)


def test_profile_rounding_is_the_end_points_distance(plans):
    """``profile_rounding`` is the distance from a profile's last value to the point its input ends
    at (independent: a hand-made profile that ends 3 um off its end point). Regression: the late
    plan's was 4.7 nm (its breaks' rounding at 20,000 s, ~4e-12 s, moved every piece's local time
    and the running sums lost the digits of a large displacement); with the breaks and the running
    integrals as double-doubles (``_fir_profile._between``, ``_add``) it is below the 1 pm of
    ``VERIFY_ATOL``, as early in a program."""
    coeffs = np.zeros((2, 1, 2))
    coeffs[-1, 0] = [1.0, 2.0 + 3e-6]
    assert profile_rounding(NumpyPiecewise(np.array([0.0, 1.0, 1.0]), coeffs), np.array([1.0, 2.0])) == pytest.approx(3e-6)
    for lead in (10.0, 20000.0):
        plan, path = plans[lead]
        position = plan.position
        drift = profile_rounding(NumpyPiecewise(np.asarray(position.breaks), np.asarray(position.coeffs)), path.ends[-1])
        assert drift < VERIFY_ATOL
