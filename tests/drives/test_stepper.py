"""The fused per-axis simulation loop against a plain NumPy loop over the same discretization."""

import numpy as np
import pytest

from research.drives import (
    FlexibleMode,
    discretize,
    simulate,
    table_6_1_closed_loop,
    table_6_1_ppi,
)
from research.drives._discretize import continuous_system
from tests.drives._helpers import sine_trajectory

Ts = 1e-3


def _reference_loop(model, mode, tr, hold):
    """``z_{k+1} = Ad z_k + G c_k + Gw w_k`` with the full (drive + mode) state, one axis at a time."""
    r = model.realization()
    Ad, G, Gw = (np.asarray(x) for x in discretize(*continuous_system(model, mode), Ts, hold))
    C, D, Dw = np.asarray(r.C), np.asarray(r.D), np.asarray(r.Dw)
    fc, fff = float(r.friction_amplitude), float(r.friction_feedforward)
    q, v, a, j = (np.asarray(x) for x in (tr.q, tr.v, tr.a, tr.j))
    N, n_axes = q.shape
    out = {k: np.zeros((N, n_axes)) for k in ("position", "velocity", "control", "deflection", "friction")}
    n0 = C.shape[1]
    for ax in range(n_axes):
        z = np.zeros(Ad.shape[0])
        z[r.position_index], z[r.velocity_index] = q[0, ax], v[0, ax]
        for k in range(N):
            ref = np.array([q[k, ax], v[k, ax], a[k, ax]])
            if hold == "cubic":
                c = np.append(ref, j[k, ax])
            else:
                k1 = min(k + 1, N - 1)
                c = np.concatenate([ref, (np.array([q[k1, ax], v[k1, ax], a[k1, ax]]) - ref) / Ts])
            w = np.array([fc * np.sign(z[r.velocity_index]), fff * np.sign(v[k, ax])])
            out["position"][k, ax], out["velocity"][k, ax] = z[r.position_index], z[r.velocity_index]
            out["control"][k, ax] = C[2] @ z[:n0] + D[2] @ ref + Dw[2] @ w
            out["deflection"][k, ax] = z[n0]
            out["friction"][k, ax] = w[0] - w[1]
            z = Ad @ z + G @ c + Gw @ w
    return out


@pytest.mark.parametrize("model, hold", [(table_6_1_ppi(), "foh"), (table_6_1_closed_loop(), "cubic")])
def test_loop_with_mode_and_control_matches_numpy_recursion(model, hold):
    """Drive states stepped first, then the mode (and the control signal) from the stored drive states:
    the same recursion as stepping the full state, to rounding."""
    mode = FlexibleMode.from_hz(11.4, 0.02)
    tr = sine_trajectory(2.0, 1.0, 1200, Ts, axes=("x", "y"))
    res = simulate(model, tr, modes=mode, hold=hold)
    ref = _reference_loop(model, mode, tr, hold)
    for name in ("position", "velocity", "deflection", "friction"):
        np.testing.assert_allclose(getattr(res, name), ref[name], rtol=0, atol=1e-12 * np.max(np.abs(ref[name])) + 1e-15,
                                   err_msg=name)
    if res.control is not None:
        np.testing.assert_allclose(res.control, ref["control"], rtol=0, atol=1e-12 * np.max(np.abs(ref["control"])))
    else:
        assert model.realization().has_control is False
