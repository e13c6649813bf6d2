"""The look-ahead's arcs as turns (``_fir_lookahead._arc_turns``) against Sencer 2015 eq 8.

Eq 8 gives each filter's frequency response, ``M_i(j w) = e^{-j w T_i / 2} sin(w T_i / 2) / (w T_i / 2)``
("$$M_i(j\\omega) = ... \\left(\\frac{\\sin(\\omega T_i/2)}{\\omega T_i/2} \\right) \\quad (8)$$"): a
circle of radius ``R`` run at feed ``F`` (``w = F / R``) comes out of the chain as the circle of radius
``R prod_i sinc(F T_i / 2R)``, so the trajectory passes each point of the circle at
``R (1 - prod_i sinc)`` from it. The look-ahead's window error at a vertex of such a circle (the
windowed sum of the direction changes, ``_fir_feed``) must be that distance: an independent check of
the arcs' turns, which stand for each arc's continuous turning."""

import numpy as np
import pytest

from research.interpolators._fir_feed import ChainError
from research.interpolators._fir_lookahead import _arc_turns
from research.paths.toolpath import ToolPath

DELAYS = np.array([0.06, 0.03])  # [s]


def quarter_arcs(R: float) -> ToolPath:
    """A circle of radius ``R`` [mm] as four tangent quarter arcs (G3), from ``(R, 0)``."""
    ang = np.array([0.5, 1.0, 1.5, 2.0]) * np.pi
    ends = np.column_stack([R * np.cos(ang), R * np.sin(ang)])
    return ToolPath([R, 0.0], ends, np.zeros((4, 2)), np.tile([0.0, 0.0, 1.0], (4, 1)), np.full(4, 0.5 * np.pi))


@pytest.mark.parametrize("F", [30.0, 100.0, 200.0])  # windows of 1.35 to 9 mm against 7.85 mm quarter arcs
def test_window_error_at_the_junctions_of_a_circle_is_the_eq_8_shrink(F):
    """At the three junctions of the quarter arcs (tangent: no vertex turn), the window error equals
    ``R (1 - prod sinc(F T_i / 2R))`` within 0.2 % (the turns are chords of 0.1 um sagitta, 63 um
    apart: a midpoint rule, error ~ (63 um / window)^2). Without the two half-chord turns at each
    arc's ends, the windows miss the turning at the junctions: 8.9 / 2.8 / 1.5 % too small."""
    R = 5.0
    tp = quarter_arcs(R)
    t_in, t_out = tp.tangents()
    s_v = np.cumsum(tp.lengths)[:-1]
    du_v = t_in[1:] - t_out[:-1]
    s_a, du_a = _arc_turns(tp, 0.05)
    s, du = np.concatenate([s_v, s_a]), np.concatenate([du_v, du_a])
    order = np.argsort(s, kind="stable")
    got = np.linalg.norm(ChainError(s[order], du[order], DELAYS).displacement(s_v, np.full(s_v.size, F)), axis=1)
    want = R * (1.0 - np.prod(np.sinc(F * DELAYS / (2.0 * R) / np.pi)))
    np.testing.assert_allclose(got, want, rtol=2e-3)
