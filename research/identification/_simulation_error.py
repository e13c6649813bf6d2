"""The default identification: simulation-error (output-error) fit with the linear parameters projected out.

Why this, and not the thesis' equation error (eq 6.10) or an instrumental variable: eq 6.9 regresses the
measured position on its own numerical derivatives, so encoder noise enters the regressor and the least
squares estimate is biased (errors in variables; 5 um noise on the §6.5 program moves wn by 32 % and
zeta by 2.2x, ``experiments/sensitivity_identification.toml``); a prefilter only trades that bias for
another. The simulation error ``x - x_sim(theta)`` compares the measured position with the model's free-run
response to the noise-free reference, so measurement noise enters the criterion additively and not the
regressors: the estimate is consistent for white or coloured output noise (Ljung 1999, §8.3, the
output-error model; thesis ref [53]), and the criterion is what a model is used for, simulating the axis.

The problem is separable: for fixed poles the simulated position is linear in the numerator, friction,
offset and initial state (:mod:`research.identification._simulation`), so those are eliminated by linear
least squares at every evaluation (variable projection, Golub & Pereyra 1973) and only the pole parameters
``(wn, zeta[, p])`` are searched, with ``scipy.optimize.least_squares`` (trust-region reflective, bounds =
stability bounds, log-scaled). Friction signs are those of the *simulated* velocity (noise free); they are
held fixed during an optimizer pass and updated from the exact simulation before and between passes until
the final model's own signs equal the ones held (the fit is then an exact stationary point of the exact
simulation error). Grid starts are ranked with the signs of the low-passed measured velocity. Starts: a coarse grid
over the pole parameters (cheap: one projection each) plus any given starts (e.g. the thesis LS), the best
few polished. ``d_c >= 0`` is kept by re-solving with ``d_c = 0`` when the free solution is negative (exact
for one inequality).
"""

from __future__ import annotations

import itertools
import time

import numpy as np
from scipy.linalg import lstsq
from scipy.optimize import least_squares as scipy_least_squares
from scipy.signal import butter, sosfiltfilt

from research.errors import DriveLogError, ParameterError
from research.identification._log import DriveLog
from research.identification._simulation import Reference, consistent_signs, linear_part, responses
from research.identification._structure import HZ, ModelStructure, structure as as_structure
from research.identification._structure_fit import StructureFit

INITIAL_MODES = ("estimate", "rest")
#: optimizer tolerance of the screening pass that only ranks the starts' basins (the chosen one is then
#: polished to ``tol``); swept in ``benchmarks/bench_identification.py``
SCREEN_TOL = 1e-3
#: a reference within AFFINE_RTOL of its stroke from a straight line in time does not accelerate: 1e-9 of the
#: stroke is below any encoder's resolution (1 nm on a 1 m stroke)
AFFINE_RTOL = 1e-9
#: damping values of the start grid (under-, well- and over-damped pairs)
GRID_ZETA = (0.25, 0.5, 0.8, 1.1)


def _columns(st: ModelStructure, R, signs, initial, force=None):
    """Regressor of the linear parameters (``b1..bm``, ``dc``, ``offset``, initial state) and the known part."""
    cols = [R.S[:, i] for i in range(1, st.n_zeros + 1)]
    if st.friction:
        cols.append(-R.disturbance_position(signs))
    if st.offset:
        cols.append(-R.offset_pos)
    if st.force:
        cols.append(R.disturbance_position(force))
    if initial == "estimate":
        cols += list(R.modes_pos.T)
    return np.column_stack(cols), R.den[-1] * R.S[:, 0]


def _lsq(A, y):
    """Least squares by the column-scaled normal equations plus one step of iterative refinement (accuracy
    ~ cond(A) eps; a few passes over ``A`` instead of a QR or SVD of the N x m matrix), SVD when the scaled
    Gram matrix is ill conditioned (cond > 1e12: the refinement no longer recovers the digits)."""
    G, g = A.T @ A, A.T @ y
    scale = np.sqrt(np.diag(G))
    scale[scale == 0] = 1.0
    Gs = G / np.outer(scale, scale)
    if np.linalg.cond(Gs) > 1e12:
        return lstsq(A / scale, y, lapack_driver="gelsd")[0] / scale
    x = np.linalg.solve(Gs, g / scale) / scale
    x += np.linalg.solve(Gs, (A.T @ (y - A @ x)) / scale) / scale
    return x


def _solve_linear(Phi, target, dc_index):
    theta = _lsq(Phi, target)
    if dc_index is not None and theta[dc_index] < 0:  # d_c >= 0: one active bound -> solve on it
        keep = np.arange(Phi.shape[1]) != dc_index
        theta = np.zeros(Phi.shape[1])
        theta[keep] = _lsq(Phi[:, keep], target)
    return theta


class _Problem:
    def __init__(self, st, log, initial, force=None):
        self.st, self.initial, self.force = st, initial, force
        self.ref = Reference.from_samples(log.reference, log.sample_period)
        self.y = log.actual - self.ref.x0
        self.dc_index = st.n_zeros if st.friction else None
        self.evaluations = 0

    def project(self, sigma, signs):
        """``(residual, theta, responses)`` for pole parameters ``sigma`` and friction signs held fixed."""
        self.evaluations += 1
        R = responses(self.st, sigma, self.ref)
        Phi, known = _columns(self.st, R, signs, self.initial, self.force)
        theta = _solve_linear(Phi, self.y - known, self.dc_index)
        return self.y - known - Phi @ theta, theta, R

    def split(self, theta):
        m, st = self.st.n_zeros, self.st
        b = theta[:m]
        k = m
        dc = float(theta[k]) if st.friction else 0.0
        k += int(st.friction)
        off = float(theta[k]) if st.offset else 0.0
        k += int(st.offset)
        g = float(theta[k]) if st.force else None
        k += int(st.force)
        c = theta[k:] if self.initial == "estimate" else None
        return b, dc, off, c, g

    def exact(self, sigma, theta, R, signs):
        """Exact simulation (friction signs consistent) -> ``(position - x_r0, signs)``."""
        b, dc, off, c, g = self.split(theta)
        force = None if g is None else (g, self.force)
        pos, _, s, _ = consistent_signs(R, *linear_part(self.st, R, b, off, c, force), dc, signs)
        return pos, s


def _check_excitation(log: DriveLog) -> None:
    """Refuse logs that cannot identify a closed loop: a constant or constant-speed reference (no acceleration:
    every structure's response to it is the same ramp), or a measured position that does not move."""
    ref, act = log.columns.get("reference", "reference"), log.columns.get("actual", "actual")
    span = float(np.ptp(log.reference))
    if span == 0:
        raise DriveLogError(f"{log.source}: the reference column {ref!r} is constant; an identification log must move "
                            "the axis (use the §6.5 program)")
    t = log.t - log.t[0]
    dev = float(np.max(np.abs(log.reference - np.polyval(np.polyfit(t, log.reference, 1), t))))
    if dev <= AFFINE_RTOL * span:
        raise DriveLogError(f"{log.source}: the reference column {ref!r} moves at constant speed (it deviates "
                            f"{dev:.3g} mm from a straight line in time over a {span:.6g} mm stroke); it does not excite "
                            "the drive's dynamics: an identification log needs accelerations (the §6.5 program)")
    if np.ptp(log.actual) == 0:
        raise DriveLogError(f"{log.source}: the measured position column {act!r} is constant while the reference "
                            f"{ref!r} moves {span:.6g} mm; is the drive enabled and is it the encoder column?")


def _thesis_starts(log) -> list:
    """Pole parameters of the prefiltered LS (when stable) and of the bounded fit: good starts at low noise,
    rough ones at high noise (their bias is what this fit removes)."""
    from research.identification._bounded import bounded_fit
    from research.identification._least_squares import least_squares

    out = []
    try:
        for r in (least_squares(log), bounded_fit(log)):
            sig = np.array(r.pole_parameters())
            if r.stable and np.all(np.isfinite(sig)) and np.all(sig > 0):
                out.append(sig)
    except (DriveLogError, ParameterError):  # not enough excitation for eq 6.9: the grid alone starts the fit
        pass
    return out


def _grid(st: ModelStructure, lo, hi, Ts, n):
    f = np.geomspace(max(lo[0], 1.0 * HZ), min(hi[0], 0.2 / Ts * HZ), n)
    pairs = [(w, z) for w in f for z in GRID_ZETA]
    out = []
    for combo in itertools.combinations_with_replacement(range(len(pairs)), st.n_pairs):
        sig = [v for i in combo for v in pairs[i]]
        if st.has_real_pole:
            out += [sig + [p] for p in f]
        else:
            out.append(sig)
    return np.clip(np.array(out), lo, hi)


def simulation_error_fit(
    log: DriveLog,
    structure="eq6.3",
    *,
    initial: str = "estimate",
    bounds: tuple | None = None,
    starts=(),
    grid_points: int | None = None,
    n_polish: int = 4,
    thesis_starts: bool = True,
    max_nfev: int = 200,
    max_passes: int = 8,
    tol: float = 1e-10,
    force=None,
) -> StructureFit:
    """Fit ``structure`` to ``log`` by simulation error (module docstring).

    Args:
        log: estimation log [s, mm].
        structure: a :class:`ModelStructure` or its name (``"eq6.3"``, ``"pp2"``, ...).
        initial: ``"estimate"``: the initial state is fitted with the linear parameters (a log may start
            mid-move); ``"rest"``: the loop starts at rest at ``x_r[0]``.
        bounds: ``(lower, upper)`` of the pole parameters; default ``structure.default_bounds(Ts)``.
        starts: extra starting pole parameters (e.g. from the thesis LS), each in ``structure.pole_names`` order.
        grid_points: frequencies per axis of the start grid (default 5 for one pair, 4 for more).
        n_polish: best grid starts that the optimizer polishes (given starts are always polished).
        thesis_starts: for one-pair-plus-real-pole structures (eq 6.3) also start from the equation-error LS
            (eq 6.12, prefiltered) and the bounded variable-projection fit (§6.4) of the same log.
        max_nfev: optimizer evaluations per pass.
        max_passes: friction-sign passes (each a full optimizer run warm-started).
        tol: ``ftol = xtol = gtol`` of the optimizer.
        force: ``(N,)`` measured external force (any unit) for structures with ``force=True``.
    Returns:
        :class:`StructureFit`; ``converged`` is true when the last pass met ``tol`` and its friction signs are the
        final model's own.
    Raises:
        DriveLogError: the log is shorter than 10 samples per parameter or does not move.
        ParameterError: unknown ``initial`` or bad bounds.
    """
    t_start = time.perf_counter()
    st = as_structure(structure)
    if initial not in INITIAL_MODES:
        raise ParameterError(f"initial must be one of {INITIAL_MODES}, got {initial!r}")
    n_par = st.n_parameters + (st.n_poles if initial == "estimate" else 0)
    if log.n_samples < 10 * n_par:
        raise DriveLogError(f"{log.source}: {log.n_samples} samples are too few for the {n_par} parameters of structure "
                            f"{st.name!r} (need at least {10 * n_par})")
    _check_excitation(log)
    Ts = log.sample_period
    lo, hi = st.default_bounds(Ts) if bounds is None else (np.asarray(bounds[0], float), np.asarray(bounds[1], float))
    if lo.shape != (len(st.pole_names),) or hi.shape != lo.shape or not np.all((0 < lo) & (lo < hi)):
        raise ParameterError(f"bounds of structure {st.name!r} must be two arrays of {len(st.pole_names)} values "
                             f"{st.pole_names} with 0 < lower < upper, got {lo!r}, {hi!r}")
    if thesis_starts and st.n_pairs == 1 and st.has_real_pole:
        starts = list(starts) + _thesis_starts(log)
    if st.force:
        if force is None:
            raise DriveLogError(f"{log.source}: structure {st.name!r} has a force input; pass force= (N,) samples")
        force = np.asarray(force, dtype=np.float64)
        if force.shape != (log.n_samples,) or not np.all(np.isfinite(force)):
            raise DriveLogError(f"{log.source}: force must be {log.n_samples} finite samples (one per log sample), "
                                f"got shape {force.shape}")
    prob = _Problem(st, log, initial, force if st.force else None)
    # first guess of the friction signs: the measured direction of motion, low-passed (20 Hz, zero phase) so
    # that encoder noise at rest does not flip it; each polished start then uses its own simulated signs
    signs = np.sign(np.gradient(sosfiltfilt(butter(4, min(20.0, 0.2 / Ts), fs=1.0 / Ts, output="sos"), log.actual), Ts))
    cands = [np.clip(np.asarray(s, float), lo, hi) for s in starts if np.all(np.isfinite(s))]
    n_grid = grid_points or (5 if st.n_pairs == 1 else 4)
    cand = np.vstack([_grid(st, lo, hi, Ts, n_grid)] + ([np.array(cands)] if cands else []))
    losses = np.array([float(np.sum(prob.project(s, signs)[0] ** 2)) for s in cand])
    order = list(np.argsort(losses)[:n_polish]) + list(range(len(cand) - len(cands), len(cand)))
    ulo, uhi = np.log(lo), np.log(hi)

    def fun(u, s):
        return prob.project(np.exp(u), s)[0]

    def trf(u, s, tol_):
        return scipy_least_squares(fun, u, args=(s,), bounds=(ulo, uhi), method="trf", ftol=tol_, xtol=tol_,
                                   gtol=tol_, max_nfev=max_nfev)

    def own_signs(u, s):
        """Exact simulation of the model at ``u`` (its linear part projected with signs ``s`` held) ->
        ``(its own friction signs, exact squared simulation error)``."""
        _, theta, R = prob.project(np.exp(u), s)
        pos, s_new = prob.exact(np.exp(u), theta, R, s)
        return s_new, float(np.sum((prob.y - pos) ** 2))

    def screen(u, s):
        """One optimizer pass at SCREEN_TOL with the start model's own signs: which basin a start falls in."""
        s = own_signs(u, s)[0]
        u = trf(u, s, SCREEN_TOL).x
        return (u, *own_signs(u, s))

    def polish(u, s):
        """Optimizer passes at ``tol`` with the friction signs held, updated between passes until consistent."""
        status, consistent, passes = 0, False, 0
        for passes in range(1, max_passes + 1):
            sol = trf(u, s, tol)
            u, status = sol.x, sol.status
            s_new, err = own_signs(u, s)
            if np.array_equal(s_new, s):
                consistent = True
                break
            s = s_new
        return u, s, status, consistent, passes, err

    # every start screened (unique, best first), the best basin by its exact simulation error polished
    screened = [screen(np.clip(np.log(cand[i]), ulo + 1e-9, uhi - 1e-9), signs) for i in dict.fromkeys(order)]
    u0, s0, _ = min(screened, key=lambda r: r[-1])
    best = polish(u0, s0)
    u, s, status, consistent, passes, _ = best
    sigma = np.exp(u)
    r, theta, R = prob.project(sigma, s)
    pos, s = prob.exact(sigma, theta, R, s)
    res = prob.y - pos
    std = _covariance(prob, sigma, theta, s, res)
    names = st.pole_names + st.linear_names
    b, dc, off, c, g = prob.split(theta)
    values = (list(sigma) + list(b) + ([dc] if st.friction else []) + ([off] if st.offset else [])
              + ([g] if st.force else []))
    at_bound = tuple(k for k, v, a, z in zip(st.pole_names, u, ulo, uhi) if min(v - a, z - v) < 1e-6)
    return StructureFit(
        structure=st, parameters={k: float(v) for k, v in zip(names, values)}, std=dict(zip(names, std)),
        loss=0.5 * float(res @ res), rms_um=1e3 * float(np.sqrt(np.mean(res**2))),
        converged=bool(consistent and status > 0), at_bound=at_bound, initial=initial, method="simulation_error",
        source=log.source, wall_time_s=time.perf_counter() - t_start,
        info={"optimizer_status": int(status), "sign_passes": passes, "signs_consistent": consistent,
              "evaluations": prob.evaluations, "grid_starts": int(len(cand) - len(cands)), "given_starts": len(cands),
              "bounds_lower": lo.tolist(), "bounds_upper": hi.tolist(),
              "initial_state": None if c is None else [float(v) for v in c]},
    )


def _covariance(prob: _Problem, sigma, theta, signs, res) -> list[float]:
    """Standard deviations of ``[poles, b, dc, offset]`` from ``s^2 (J^T J)^-1`` (Gauss-Newton, white residual),
    the Jacobian over every parameter (pole columns by central differences with the signs held)."""
    st = prob.st

    def predict(sig, th):
        R = responses(st, sig, prob.ref)
        Phi, known = _columns(st, R, signs, prob.initial, prob.force)
        return known + Phi @ th, Phi

    _, Phi = predict(sigma, theta)
    cols = []
    for i in range(sigma.size):
        h = 1e-6 * sigma[i]
        e = np.zeros_like(sigma)
        e[i] = h
        cols.append((predict(sigma + e, theta)[0] - predict(sigma - e, theta)[0]) / (2 * h))
    J = np.column_stack(cols + [Phi])
    if st.friction and theta[prob.dc_index] == 0:  # on its bound: not a free parameter
        J = np.delete(J, sigma.size + prob.dc_index, axis=1)
    dof = max(res.size - J.shape[1], 1)
    s2 = float(res @ res) / dof
    scale = np.linalg.norm(J, axis=0)
    scale[scale == 0] = 1.0
    try:
        cov = np.linalg.pinv((J / scale).T @ (J / scale)) / np.outer(scale, scale) * s2
        sd = np.sqrt(np.clip(np.diag(cov), 0, None))
    except np.linalg.LinAlgError:
        sd = np.full(J.shape[1], np.nan)
    if st.friction and theta[prob.dc_index] == 0:
        sd = np.insert(sd, sigma.size + prob.dc_index, 0.0)
    return [float(v) for v in sd[: st.n_parameters]]
