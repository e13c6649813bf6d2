"""The closed-form FIR-cornering model of the sweep fast path against the exact NumPy/JAX planner.

Tolerances: cycle time 1e-12 s and corner errors 1e-9 mm (both are the same closed forms as
``plan_fir`` when every block is longer than the filter); residual vibration 1e-3 relative against
the trapezoid rule on the exact profile sampled at 0.1 ms (error O((wn Ts)^2 / 12) = 4e-5 at 11.4 Hz;
1e-2 with one filter, whose acceleration jumps);
sensitivities 1e-6 relative against central differences.
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from research.drives import residual_vibration_sampled
from research.experiments.fir_model import fir_metrics, sensitivities
from research.interpolators import plan_fir
from research.paths import named_path

DIAMOND = named_path("diamond")
MODES = dict(mode_hz=jnp.array([11.4, 6.8]), mode_damping=jnp.array([0.02, 0.02]), axes=(0, 1))


_metrics = jax.jit(fir_metrics, static_argnames="axes")


def model(F, delays, eps, **kw):
    return _metrics(jnp.asarray(DIAMOND.points), F, jnp.asarray(delays), eps, **(MODES | kw))


@pytest.mark.parametrize("F, delays, eps", [(250.0, (0.148, 0.089), 0.5), (250.0, (0.10, 0.05), 0.2),
                                            (100.0, (0.148, 0.089), 0.05), (180.0, (0.06,), 0.3)])
def test_matches_plan_fir(F, delays, eps):
    m = model(F, delays, eps)
    plan = plan_fir(DIAMOND, F, delays, eps)
    assert bool(m["exact"])
    assert abs(float(m["cycle_time"]) - float(plan.cycle_time)) < 1e-12
    np.testing.assert_allclose(np.asarray(m["corner_errors"]), np.asarray(plan.corner_errors), rtol=0, atol=1e-9)
    traj = plan.trajectory(1e-4)
    a = np.asarray(traj.a)
    sampled = [residual_vibration_sampled(traj.t, a[:, 0], 11.4, 0.02), residual_vibration_sampled(traj.t, a[:, 1], 6.8, 0.02)]
    # one filter: the acceleration jumps, and the trapezoid rule is only O(Ts) across the jumps
    np.testing.assert_allclose(np.asarray(m["residual"]), sampled, rtol=1e-3 if len(delays) > 1 else 1e-2)


def test_delays_on_the_modes_leave_no_residual_vibration():
    """eq 10: T_i = 1 / f_i puts a spectral zero on each mode; undamped, nothing is left."""
    undamped = dict(mode_damping=jnp.array([1e-9, 1e-9]))
    tuned = model(250.0, (1 / 6.8, 1 / 11.4), 0.5, **undamped)
    detuned = model(250.0, (0.12, 0.07), 0.5, **undamped)
    assert float(tuned["residual_vibration"]) < 1e-6 * float(detuned["residual_vibration"])


def test_sensitivities_match_finite_differences():
    F, d, eps = 250.0, jnp.array([0.13, 0.08]), 0.3
    s = jax.jit(sensitivities, static_argnames="axes")(jnp.asarray(DIAMOND.points), F, d, eps, **MODES)
    h = 1e-6
    for name, shift in [("T1", (0, h, 0, 0)), ("T2", (0, 0, h, 0)), ("eps", (0, 0, 0, h)), ("F", (h * 1e3, 0, 0, 0))]:
        def at(sign):
            return model(F + sign * shift[0], d + sign * jnp.array(shift[1:3]), eps + sign * shift[3])
        step = 2 * max(shift)
        for metric in ("cycle_time", "residual_vibration"):
            fd = (float(at(1)[metric]) - float(at(-1)[metric])) / step
            assert float(s[f"d_{metric}/d_{name}"]) == pytest.approx(fd, rel=1e-6, abs=1e-9), (metric, name)
    assert float(s["d_max_corner_error/d_eps"]) == pytest.approx(1.0)  # the error sits on the tolerance (eq 14)
    # the cycle-time gradient agrees with jax.grad through the exact planner
    g = jax.grad(lambda T: plan_fir(DIAMOND, F, T, eps).cycle_time)(d)
    np.testing.assert_allclose([float(s["d_cycle_time/d_T1"]), float(s["d_cycle_time/d_T2"])], np.asarray(g), rtol=1e-9)


def test_short_blocks_are_flagged():
    assert not bool(model(1000.0, (0.148, 0.089), 0.5)["exact"])  # T_v = 71 ms < T_d = 237 ms
