"""The window lower bound (B2, ``_fir_window_bound``) on fixed-delay FIR plans, against verified
plans and a brute-force search of the family on short-block paths."""

import numpy as np
import pytest

from research.errors import ParameterError
from research.interpolators import _fir_smooth as sm
from research.interpolators import plan_fir
from research.interpolators._fir_bound import fir_cycle_lower_bound
from research.interpolators._fir_window_bound import kernel_cell_masses, window_lower_bound
from research.paths import Polyline, named_path
from research.paths.library import random_program

from ._paths import turning_path

DELAYS = (0.06, 0.03)
F, EPS = 200.0, 0.05


def short_path(seed: int, n: int = 3) -> Polyline:
    """Seeded 2-D path of ``n`` blocks of 2-6 mm (shorter than F T_d = 18 mm) turning by up to +-60 deg."""
    return turning_path(seed, n, (2.0, 6.0), 60.0)


def test_kernel_cell_masses_are_the_trapezoid():
    """Two boxes T1 > T2: the kernel is the trapezoid rising over [0, T2] to 1/T1, flat to T1,
    falling to T1 + T2; its cell masses integrated in closed form per cell."""
    T1, T2, ds = 0.06, 0.03, 1e-3
    H = kernel_cell_masses((T1, T2), ds)

    def cdf(x):
        x = np.clip(x, 0.0, T1 + T2)
        rise = np.minimum(x, T2) ** 2 / (2 * T1 * T2)
        flat = np.clip(x - T2, 0.0, T1 - T2) / T1
        y = np.clip(x - T1, 0.0, T2)
        fall = (y - y * y / (2 * T2)) / T1
        return rise + flat + fall

    edges = np.arange(H.size + 1) * ds
    np.testing.assert_allclose(H, np.diff(cdf(edges)), atol=1e-12)
    assert H.sum() == pytest.approx(1.0, abs=1e-12)


def brute_force_times(path: Polyline, rng, n_plans: int, shares=(0.25, 0.5, 0.25)):
    """Cycle times of random plans of the family (per-piece feeds in [0.15 F, F], gaps in
    [0, T_d]) whose corner error, *sampled* on the closed-form profile (S1), is <= eps: the sampled
    minimum distance is >= the true one, so every plan kept truly meets the tolerance."""
    layout = sm.Layout.build(path.points, F, DELAYS, shares)
    tmin = (layout.shares[None, :] * layout.L[:, None]).ravel() / F
    Td, M = layout.Td, layout.M
    out = []
    for _ in range(n_plans):
        tau = tmin / rng.uniform(0.15, 1.0, tmin.size) ** rng.choice([0.0, 1.0], tmin.size, p=[0.4, 0.6])
        gaps = Td * rng.uniform(0.0, 1.0, M - 1) ** 0.5
        z = np.concatenate([tau, gaps, np.zeros(M - 1)])
        T = float(layout.end_row() @ z + Td)
        t = np.linspace(0.0, T, 2501)
        q = sm.position(layout, z, t)
        err = np.min(np.linalg.norm(q[:, None, :] - path.points[None, 1:-1], axis=2), axis=0)
        if np.all(err <= EPS):
            out.append(T)
    return np.array(out)


@pytest.mark.parametrize("seed", [1, 3])
def test_bound_below_every_verified_plan_on_short_blocks(seed):
    """On random 3-block paths of 2-6 mm (B1 trivial there): (B2) <= the plain and the refined
    plan_fir (each verified on its exact profile) and <= every brute-force plan of the family
    that meets eps; and it is not trivial (above sum L / F + T_d) where the corners need a loss."""
    path = short_path(seed)
    bound, losses = window_lower_bound(path, F, DELAYS, EPS, ds=1e-4)
    trivial, ok = fir_cycle_lower_bound(path, F, DELAYS, EPS)
    assert not ok  # B1 does not state a corner bound here
    for refine in (False, True):
        plan = plan_fir(path, F, DELAYS, EPS, refine=refine)
        assert float(np.max(np.asarray(plan.corner_errors))) <= EPS * (1 + 1e-9) + 1e-9
        assert bound <= float(plan.cycle_time)
    times = brute_force_times(path, np.random.default_rng(seed), 100)
    assert times.size > 0 and bound <= times.min()
    assert bound > trivial + 1e-3 and np.all(losses >= 0)


def test_bound_below_plans_on_random_programs():
    """Seeded CAM-like line programs (blocks of 0.02-30 mm at any turn, bench_cam's draws): (B2)
    never exceeds the verified plain plan_fir's cycle time."""
    for seed in (4, 9):
        tp = random_program(np.random.default_rng(seed), arcs=False)
        path = Polyline(np.vstack([tp.start, tp.ends]))
        plan = plan_fir(path, F, DELAYS, EPS)
        bound, _ = window_lower_bound(path, F, DELAYS, EPS, ds=1e-4, n_directions=24)
        assert bound <= float(plan.cycle_time)


def test_bound_is_tight_where_b1_proves_the_plan_optimal():
    """corner90 at the study setting: B1 equals the plain plan (its dwell is B1's extremal,
    test_fir_smooth); (B2) agrees with both to the quadrature's resolution and stays below."""
    path = named_path("corner90")
    F2, D2, eps2 = 250.0, (0.148, 0.089), 0.5
    bound, _ = window_lower_bound(path, F2, D2, eps2)
    plan = float(plan_fir(path, F2, D2, eps2).cycle_time)
    assert bound <= plan and bound == pytest.approx(plan, rel=1e-3)


def test_bound_does_not_grow_with_the_tolerance():
    """l*_k is the least loss with m(l) <= eps and m does not depend on eps: a looser tolerance
    never raises the bound."""
    path = short_path(5)
    values = [window_lower_bound(path, F, DELAYS, e, ds=1e-4, n_directions=24)[0] for e in (0.02, 0.05, 0.2)]
    assert values[0] >= values[1] >= values[2]


@pytest.mark.parametrize("kw", [dict(feed=0.0), dict(tolerance=0.0), dict(delays=(0.06, -0.01))])
def test_bad_input_is_refused(kw):
    args = dict(feed=F, delays=DELAYS, tolerance=EPS) | kw
    with pytest.raises(ParameterError):
        window_lower_bound(short_path(1), **args)
