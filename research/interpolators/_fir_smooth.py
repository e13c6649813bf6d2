"""The FIR plan as a smooth NLP with its break order fixed (issue 19, item 2).

A named extension, not Sencer 2015's method. With the filter delays ``T_1 .. T_n`` fixed, a G01
block ``k`` cut into pieces of fixed shares ``s_p`` is a sum of velocity pulses (eq 5), piece
``j`` moving ``d_j = s_p (P_k+1 - P_k)`` in ``tau_j`` seconds from ``sigma_j``. Filtered by the
``n`` moving averages (eq 2-4) each pulse becomes the CDF of a sum of ``n + 1`` uniform variables
of widths ``w = (tau_j, T_1 .. T_n)``, so the whole profile is, in closed form,

    q(t) = P_0 + sum_j d_j G(t - sigma_j; w_j),
    G^(nu)(t; w) = 1 / ((n + 1 - nu)! prod w) sum_{S subset w} (-1)^|S| (t - sum S)_+^(n + 1 - nu)   (S1)

(the B-spline form of a cascade of box filters; ``nu`` = 0..n+1 is the derivative order). The
break points are ``sigma_j + e tau_j + sum S`` (``e`` = 0, 1). With their *order* fixed, every
``(.)_+`` in (S1) has a known sign at any time placed between two given breaks, so positions,
velocities, accelerations and jerks there are polynomials in the plan variables
``z = [tau_j, g_k, c_k]`` (piece lengths [s], corner gaps ``g_k = T_d - T_k`` [s], corner
instants [s]), all break times are affine in ``z``, and:

- the cycle time (eq 11) ``sum tau + sum g + T_d`` is linear;
- acceleration (degree 1 for two filters) peaks at breaks and jerk is constant between them, so
  their limits at the breaks / mid-intervals are exact; velocity and the tube are imposed at
  :data:`INTERIOR` points of every interval (plus the breaks);
- the corner error (eq 13/14: distance from the vertex to the motion) is at most
  ``|q(c_k) - V_k|`` for any instant ``c_k``, a free variable;
- the residual vibration of a mode on axis ``a`` (eq V1-V3 of ``research.optimal._vibration``) is,
  with ``lambda = -zeta wn + i wd``, ``A = exp(-zeta wn T_end) |sum_j d_j,a exp(-lambda sigma_j)
  lambda prod_w (1 - exp(-lambda w)) / (lambda w)| / wd``  (S2: the Laplace transform of the
  filtered acceleration, ``L[G''] = lambda prod_w (1 - e^{-lambda w}) / (lambda w)``);
- keeping the order is a set of linear inequalities between consecutive events.

:func:`solve_fixed_order` builds this NLP in CasADi at a plan ``z`` and solves it with IPOPT;
``_fir_optimize.optimize_fir`` re-linearises the order at the answer (swapping tied events whose
multiplier asks for it) a bounded number of times and accepts only answers that the exact
profile (``plan_fir``'s ``build_profile`` and checks) verifies.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

from research.errors import ParameterError

#: interior points (fractions of each interval between events) where velocity and tube are imposed
INTERIOR = (0.5,)
#: events closer than this [s] count as tied when the order is re-linearised
TIE = 1e-9


@dataclass(frozen=True)
class Layout:
    """The geometry and timing structure of a plan (no decision values).

    Attributes:
        shares: ``(P,)`` fixed shares of each block's length taken by its pieces.
        disp: ``(M P, d)`` displacement ``d_j`` of every piece [mm].
        L: ``(M,)`` block lengths [mm]; ``points``: ``(M + 1, d)`` path points [mm].
        delays: ``(n,)`` filter delays [s]; ``Td``: their sum.
        feed: commanded feed ``F`` [mm/s] (every piece's upper feed bound).
    """

    shares: np.ndarray
    disp: np.ndarray
    L: np.ndarray
    points: np.ndarray
    delays: np.ndarray
    Td: float
    feed: float

    @property
    def M(self) -> int:
        return self.L.size

    @property
    def n_pieces(self) -> int:
        return self.disp.shape[0]

    @property
    def n_vars(self) -> int:
        return self.n_pieces + 2 * (self.M - 1)

    @staticmethod
    def build(points: np.ndarray, feed: float, delays, shares=(0.25, 0.5, 0.25)) -> "Layout":
        points = np.asarray(points, dtype=np.float64)
        shares = np.asarray(shares, dtype=np.float64)
        if shares.ndim != 1 or np.any(shares <= 0) or abs(shares.sum() - 1.0) > 1e-12:
            raise ParameterError(f"piece shares must be a 1-D list > 0 adding to 1, got {np.array2string(shares, threshold=8)}")
        seg = np.diff(points, axis=0)
        disp = (shares[None, :, None] * seg[:, None, :]).reshape(-1, points.shape[1])
        d = np.asarray(delays, dtype=np.float64)
        return Layout(shares, disp, np.linalg.norm(seg, axis=1), points, d, float(d.sum()), float(feed))

    # -- affine maps of z ----------------------------------------------------------------------
    def starts_matrix(self) -> np.ndarray:
        """``(M P, n_vars)``: ``sigma = S z`` (pieces back to back, gap ``g_k`` after block ``k``)."""
        n, P = self.n_pieces, self.shares.size
        S = np.zeros((n, self.n_vars))
        for j in range(1, n):
            S[j] = S[j - 1]
            S[j, j - 1] += 1.0
            if j % P == 0:  # first piece of block j // P: after the gap of the previous corner
                S[j, n + j // P - 1] += 1.0
        return S

    def end_row(self) -> np.ndarray:
        """``T_end = row . z + T_d``: end of the last pulse plus the filters' delay."""
        row = self.starts_matrix()[-1].copy()
        row[self.n_pieces - 1] += 1.0
        return row

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Bounds of ``z``: ``s L / F <= tau <= s L / (1e-3 F)``, ``0 <= g <= T_d``, ``c`` free."""
        M = self.M
        tmin = (self.shares[None, :] * self.L[:, None]).ravel() / self.feed
        lo = np.concatenate([tmin, np.zeros(M - 1), np.full(M - 1, -np.inf)])
        hi = np.concatenate([tmin * 1e3, np.full(M - 1, self.Td), np.full(M - 1, np.inf)])
        return lo, hi


def terms(layout: Layout):
    """Every break of (S1): ``(piece, e, subset sum of the delays, sign)``."""
    subsets = [(sum(c), (-1) ** r) for r in range(layout.delays.size + 1)
               for c in itertools.combinations(layout.delays.tolist(), r)]
    return [(j, e, off, sgn * (-1) ** e) for j in range(layout.n_pieces) for e in (0, 1) for off, sgn in subsets]


def events(layout: Layout) -> tuple[np.ndarray, np.ndarray]:
    """Affine rows ``(E, n_vars)`` and constants ``(E,)`` of every event: the breaks of (S1)
    and the corner instants ``c_k``."""
    S = layout.starts_matrix()
    rows, const = [], []
    for j, e, off, _ in terms(layout):
        r = S[j].copy()
        r[j] += e
        rows.append(r)
        const.append(off)
    n = layout.n_pieces + layout.M - 1
    for k in range(layout.M - 1):
        r = np.zeros(layout.n_vars)
        r[n + k] = 1.0
        rows.append(r)
        const.append(0.0)
    return np.array(rows), np.array(const)


def order_of(values: np.ndarray, previous: np.ndarray | None = None, swap=None) -> np.ndarray:
    """Permutation sorting event ``values``; ties (within :data:`TIE`) keep ``previous``'s order
    except for the pairs in ``swap`` (``(a, b)`` event indices: ``b`` goes first)."""
    rank = np.empty(values.size)
    rank[previous if previous is not None else np.argsort(values, kind="stable")] = np.arange(values.size)
    for a, b in swap or ():
        rank[a], rank[b] = rank[b], rank[a]
    key = np.round(values / TIE)
    return np.lexsort((rank, key))


@dataclass(frozen=True)
class FixedOrder:
    """The NLP of one break order: CasADi functions and the pieces needed to re-linearise."""

    order: np.ndarray
    ev_rows: np.ndarray
    ev_const: np.ndarray
    n_order: int


def _basis(t, beta, sign, deg: int):
    """``sign (t - beta)^deg / deg!`` (the active term of S1; ``deg`` = 0 is the step)."""
    if deg == 0:
        return sign * ca.SX.ones(t.shape)
    return sign * (t - beta) ** deg / math.factorial(deg)


def build_nlp(layout: Layout, z0: np.ndarray, limits, eps: float, modes=(), residual=None, *,
              margin: float = 0.0, previous=None, swap=None):
    """The NLP of the break order at ``z0``.

    Args:
        layout: the plan's structure.
        z0: ``(n_vars,)`` plan at which the order (and each tube sample's nearest path feature) is taken.
        limits: ``AxisLimits`` or ``None``.
        eps: cornering / tube tolerance [mm].
        modes: ``(axis, frequency_hz, damping)`` per structural mode; ``residual``: ``(m,)`` bounds [mm].
        margin: relative tightening of the sampled velocity and tube constraints.
        previous, swap: see :func:`order_of`.

    Returns:
        ``(nlp dict for ca.nlpsol, lbg, ubg, FixedOrder)``.
    """
    ev_rows, ev_const = events(layout)
    values = ev_rows @ z0 + ev_const
    order = order_of(values, previous, swap)
    z = ca.SX.sym("z", layout.n_vars)
    n_p, M, d = layout.n_pieces, layout.M, layout.points.shape[1]
    tau = z[:n_p]
    S = layout.starts_matrix()
    n_deg = layout.delays.size + 1  # degree of the position polynomials
    prod_T = float(np.prod(layout.delays))
    g_parts, lbg, ubg = [], [], []

    # order: consecutive events stay ordered (only rows that depend on z)
    diff = ev_rows[order[1:]] - ev_rows[order[:-1]]
    dconst = ev_const[order[1:]] - ev_const[order[:-1]]
    keep = np.any(np.abs(diff) > 0, axis=1)
    g_parts.append(ca.mtimes(ca.DM(diff[keep]), z) + dconst[keep])
    lbg.append(np.zeros(int(keep.sum())))
    ubg.append(np.full(int(keep.sum()), np.inf))
    n_order = int(keep.sum())

    # sample times: every event, and interior points of every interval between consecutive events
    sorted_rows, sorted_const = ev_rows[order], ev_const[order]
    samples_r, samples_c, kind = [sorted_rows], [sorted_const], [np.zeros(order.size, dtype=int)]
    for th in INTERIOR:
        samples_r.append((1 - th) * sorted_rows[:-1] + th * sorted_rows[1:])
        samples_c.append((1 - th) * sorted_const[:-1] + th * sorted_const[1:])
        kind.append(np.full(order.size - 1, 2 if th == 0.5 else 1))
    A_s, c_s, kind = np.vstack(samples_r), np.concatenate(samples_c), np.concatenate(kind)
    # an event sample sits at its own break: its position is fixed by the order, so activity of
    # the terms is decided by the sample's rank (events before it are active), interior samples
    # by the interval they lie in
    pos_of_event = np.empty(order.size, dtype=int)
    pos_of_event[order] = np.arange(order.size)
    E = order.size
    rank_s = np.concatenate([np.arange(E) - 0.5] + [np.arange(E - 1) + 0.5] * len(INTERIOR))  # term active iff its rank < rank_s
    t_sym = ca.mtimes(ca.DM(A_s), z) + c_s
    n_s = c_s.size
    derivs = {nu: [ca.SX.zeros(n_s) for _ in range(d)] for nu in range(4)}
    tlist = terms(layout)
    for j in range(n_p):
        first, last = 2 * (2 ** layout.delays.size) * j, 2 * (2 ** layout.delays.size) * (j + 1)
        ranks = pos_of_event[first:last]
        lo_r, hi_r = ranks.min(), ranks.max()
        idx = np.nonzero((rank_s > lo_r) & (rank_s < hi_r))[0]
        done = np.nonzero(rank_s > hi_r)[0]
        for a in range(d):
            if layout.disp[j, a] != 0.0 and done.size:
                derivs[0][a][done.tolist()] = derivs[0][a][done.tolist()] + layout.disp[j, a]
        if idx.size == 0:
            continue
        t_j = t_sym[idx.tolist()]
        scale = 1.0 / (tau[j] * prod_T)
        acc = {nu: ca.SX.zeros(idx.size) for nu in range(4)}
        for m, (jj, e, off, sgn) in enumerate(tlist[first:last]):
            active = (ranks[m] < rank_s[idx]).astype(float)
            if not active.any():
                continue
            beta = ca.mtimes(ca.DM(S[j][None, :]), z) + e * tau[j] + off
            mask = ca.DM(active)
            for nu in range(min(4, n_deg + 1)):
                acc[nu] = acc[nu] + mask * _basis(t_j, beta, sgn, n_deg - nu)
        for nu in range(min(4, n_deg + 1)):
            val = scale * acc[nu]
            for a in range(d):
                if layout.disp[j, a] != 0.0:
                    derivs[nu][a][idx.tolist()] = derivs[nu][a][idx.tolist()] + layout.disp[j, a] * val
    q = ca.horzcat(*[derivs[0][a] + layout.points[0, a] for a in range(d)])  # (n_s, d)

    # limits: velocity at every sample, acceleration at events, jerk at mid-intervals
    # interval lengths (affine), for the mid-interval jerk samples
    h_rows, h_const = sorted_rows[1:] - sorted_rows[:-1], sorted_const[1:] - sorted_const[:-1]
    h_mid, h_num = ca.mtimes(ca.DM(h_rows), z) + h_const, h_rows @ z0 + h_const
    if limits is not None:
        lim = np.stack([limits.velocity, limits.acceleration, limits.jerk])
        # jerk: constant between breaks for two filters (mid-intervals exact), else linear (events too)
        jerk_rows = np.nonzero(kind == 2)[0] if n_deg == 3 else np.nonzero(kind != 1)[0]
        for nu, rows in ((1, np.arange(n_s)), (2, np.nonzero(kind == 0)[0]), (3, jerk_rows)):
            if nu > n_deg:
                continue
            for a in range(d):
                if not np.isfinite(lim[nu - 1, a]):
                    continue
                bound = lim[nu - 1, a] * ((1.0 - margin if nu == 1 else 1.0) - 2e-8)
                val = derivs[nu][a][rows.tolist()] / bound
                if nu == 3 and n_deg == 3:
                    # constant jerk on each interval; an interval empty at z0 (tied breaks, e.g.
                    # at an exact stop) whose jerk would break the limit stays empty (h = 0)
                    v0 = np.abs(ca.Function("j", [z], [val])(z0).full().ravel())
                    shut = (h_num <= TIE) & (v0 > 1.0)
                    g_parts += [val[np.nonzero(~shut)[0].tolist()], h_mid[np.nonzero(shut)[0].tolist()] / 1e-6]
                    lbg += [np.full(int((~shut).sum()), -1.0), np.zeros(int(shut.sum()))]
                    ubg += [np.full(int((~shut).sum()), 1.0), np.zeros(int(shut.sum()))]
                    continue
                g_parts.append(val)
                lbg.append(np.full(rows.size, -1.0))
                ubg.append(np.full(rows.size, 1.0))

    # tube: each sample within eps of the path feature nearest to it at z0
    q_num = ca.Function("q", [z], [q])(z0).full()
    P0, P1 = layout.points[:-1], layout.points[1:]
    seg = P1 - P0
    w = q_num[:, None, :] - P0[None]
    s = np.clip(np.einsum("nkd,kd->nk", w, seg) / np.sum(seg * seg, axis=1)[None], 0.0, 1.0)
    dist = np.linalg.norm(w - s[..., None] * seg[None], axis=-1)
    k_near = np.argmin(dist, axis=1)
    s_near = s[np.arange(n_s), k_near]
    e2 = (eps * (1.0 - margin - 1e-6)) ** 2
    tube = []
    for i in range(n_s):
        k = k_near[i]
        if 0.0 < s_near[i] < 1.0:
            u = seg[k] / np.linalg.norm(seg[k])
            r = q[i, :].T - P0[k]
            perp = r - ca.dot(r, ca.DM(u)) * ca.DM(u)
            tube.append(ca.dot(perp, perp))
        else:
            r = q[i, :].T - (P0[k] if s_near[i] <= 0.0 else P1[k])
            tube.append(ca.dot(r, r))
    g_parts.append(ca.vertcat(*tube) / e2)
    lbg.append(np.full(n_s, -np.inf))
    ubg.append(np.ones(n_s))

    # corners: |q(c_k) - V_k| <= eps (an upper bound on the corner error)
    corner_samples = pos_of_event[np.arange(E - (M - 1), E)]  # event samples come first, in sorted order
    for k in range(M - 1):
        r = q[int(corner_samples[k]), :].T - layout.points[k + 1]
        g_parts.append(ca.dot(r, r) / (eps * (1.0 - 1e-6)) ** 2)
        lbg.append(np.full(1, -np.inf))
        ubg.append(np.ones(1))

    # residual vibration (S2)
    t_end = ca.dot(ca.DM(layout.end_row()), z) + layout.Td
    if modes:
        sig = ca.mtimes(ca.DM(S), z)
        for (axis, f_hz, zeta), bound in zip(modes, residual):
            amp2 = residual_squared(layout, tau, sig, t_end, axis, f_hz, zeta)
            g_parts.append(amp2 / max(bound, 1e-9) ** 2)
            lbg.append(np.full(1, -np.inf))
            ubg.append(np.ones(1))

    g = ca.vertcat(*g_parts)
    nlp = {"x": z, "f": t_end, "g": g}
    return nlp, np.concatenate(lbg), np.concatenate(ubg), FixedOrder(order, ev_rows, ev_const, n_order)


def residual_squared(layout: Layout, tau, sigma, t_end, axis: int, f_hz: float, zeta: float):
    """Squared residual envelope ``A^2`` [mm^2] of one mode (S2), for numeric or CasADi inputs."""
    wn = 2 * math.pi * f_hz
    s, wd = zeta * wn, wn * math.sqrt(1 - zeta * zeta)
    lam = complex(-s, wd)
    re, im = 0.0, 0.0
    for j in range(layout.n_pieces):
        dj = float(layout.disp[j, axis])
        if dj == 0.0:
            continue
        # exp(-lambda sigma) = exp(s sigma) (cos(wd sigma) - i sin(wd sigma))
        fr, fi = _cexp_neg(lam, sigma[j])
        for w in [tau[j]] + layout.delays.tolist():
            hr, hi = _box(lam, w)
            fr, fi = fr * hr - fi * hi, fr * hi + fi * hr
        re = re + dj * (fr * lam.real - fi * lam.imag)
        im = im + dj * (fr * lam.imag + fi * lam.real)
    return _exp(-2 * s * t_end) * (re * re + im * im) / wd ** 2


def _exp(x):
    return ca.exp(x) if isinstance(x, (ca.SX, ca.MX)) else math.exp(x)


def _cexp_neg(lam: complex, x):
    """``exp(-lambda x)`` as (re, im)."""
    cos, sin = (ca.cos, ca.sin) if isinstance(x, (ca.SX, ca.MX)) else (math.cos, math.sin)
    m = _exp(-lam.real * x)
    return m * cos(lam.imag * x), -m * sin(lam.imag * x)


def _box(lam: complex, w):
    """``(1 - exp(-lambda w)) / (lambda w)`` as (re, im): the Laplace transform of a unit box of width ``w``."""
    er, ei = _cexp_neg(lam, w)
    nr, ni = 1.0 - er, -ei
    den = lam * 1.0
    dr, di = den.real * w, den.imag * w
    mag = dr * dr + di * di
    return (nr * dr + ni * di) / mag, (ni * dr - nr * di) / mag


def position(layout: Layout, z: np.ndarray, t: np.ndarray, nu: int = 0) -> np.ndarray:
    """(S1) evaluated directly (no order needed): ``(len(t), d)`` derivative ``nu`` of the position."""
    t = np.asarray(t, dtype=np.float64)
    S = layout.starts_matrix()
    sigma, tau = S @ z, z[: layout.n_pieces]
    n_deg = layout.delays.size + 1
    out = np.zeros((t.size, layout.points.shape[1])) + (layout.points[0] if nu == 0 else 0.0)
    prod_T = float(np.prod(layout.delays))
    for j, e, off, sgn in terms(layout):
        x = t - (sigma[j] + e * tau[j] + off)
        deg = n_deg - nu
        val = np.where(x > 0, x, 0.0) ** deg / math.factorial(deg) if deg > 0 else (x > 0).astype(float)
        out += np.outer(sgn * val / (tau[j] * prod_T), layout.disp[j])
    return out


def solve(nlp, lbg, ubg, z0, lo, hi, max_iter: int, options=None):
    """IPOPT on ``nlp`` from ``z0``: ``(z, multipliers of g, status, iterations)``."""
    solver = ca.nlpsol("fir_smooth", "ipopt", nlp, {
        "ipopt.print_level": 0, "print_time": False, "ipopt.max_iter": int(max_iter), "ipopt.tol": 1e-9, "ipopt.constr_viol_tol": 1e-10, "ipopt.bound_relax_factor": 0.0,
        "ipopt.mu_strategy": "adaptive", "ipopt.sb": "yes", **(options or {})})
    lo_f, hi_f = np.where(np.isfinite(lo), lo, -1e20), np.where(np.isfinite(hi), hi, 1e20)
    res = solver(x0=np.clip(z0, lo, hi), lbx=lo_f, ubx=hi_f, lbg=lbg, ubg=ubg)
    stats = solver.stats()
    return np.asarray(res["x"]).ravel(), np.asarray(res["lam_g"]).ravel(), stats["return_status"], int(stats["iter_count"])


def tied_swaps(fixed: FixedOrder, z: np.ndarray, lam_g: np.ndarray) -> list[tuple[int, int]]:
    """Consecutive events that the answer left tied and whose order constraint is active with a
    multiplier asking to cross (IPOPT's ``lam_g < 0`` on ``b_i+1 - b_i >= 0``): swap them next."""
    vals = fixed.ev_rows @ z + fixed.ev_const
    o = fixed.order
    diff = fixed.ev_rows[o[1:]] - fixed.ev_rows[o[:-1]]
    keep = np.nonzero(np.any(np.abs(diff) > 0, axis=1))[0]
    out = []
    for m, i in enumerate(keep):
        a, b = o[i], o[i + 1]
        if abs(vals[b] - vals[a]) <= TIE * 10 and lam_g[m] < -1e-10:
            out.append((int(a), int(b)))
    return out
