"""The whole-array NumPy form of ``_fir_piece_peaks``' piece peaks, an independent reference for
its compiled passes: each derivative of order 1-3 peaks at a piece end or a real root of the next
one; roots in closed form to degree 2 (the compiled pass must reproduce these bit for bit), above
by the eigenvalues of the companion matrices (the compiled pass isolates them by the derivatives'
roots instead: the same roots up to rounding)."""

import numpy as np


def piece_ratios(coeffs: np.ndarray, h: np.ndarray, limit: np.ndarray) -> np.ndarray:
    """``(K,)`` largest ``peak / limit`` of each piece (``PiecePeaks``), by whole-array NumPy."""
    K, degree = coeffs.shape[0], coeffs.shape[1] - 1
    derivs = [coeffs]  # derivative coefficients of orders 1..4 at every piece
    for _ in range(4):
        c = derivs[-1]
        derivs.append(c[:, 1:, :] * np.arange(1, c.shape[1])[None, :, None] if c.shape[1] > 1 else np.zeros_like(c))
    A = coeffs.shape[2]
    ends = np.broadcast_to(np.stack([np.zeros(K), h], axis=1)[:, None, :], (K, A, 2))  # both ends of each piece
    ratio = np.zeros((K, 3, A))
    for order in (1, 2, 3):
        tau = ends  # (K, A, 2 + R): the ends, then each axis' own roots of the next derivative
        if order < degree:
            tau = np.concatenate([ends, real_roots(derivs[order + 1], h)], axis=2)
        peak = np.max(np.abs(horner_axes(derivs[order], tau)), axis=2)  # (K, A)
        ratio[:, order - 1, :] = peak / limit[order - 1][None, :]
    return ratio.reshape(K, -1).max(axis=1)


def horner_axes(c: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """``(K, A, R)`` values of each axis' polynomial ``c[:, :, a]`` at its own times ``tau[:, a, :]``."""
    out = np.broadcast_to(c[:, -1, :, None], tau.shape)
    for m in range(c.shape[1] - 2, -1, -1):
        out = out * tau + c[:, m, :, None]
    return out


def real_roots(c: np.ndarray, h: np.ndarray) -> np.ndarray:
    """Real roots in ``[0, h]`` of the per-piece, per-axis polynomials ``c`` (ascending, ``(K, m+1, A)``),
    as local times ``(K, A, R)`` (``R`` candidates per axis; out-of-range or complex ones replaced
    by 0). Degree <= 2 in closed form, higher degrees by the eigenvalues of the companion matrices."""
    deg = c.shape[1] - 1
    K, A = c.shape[0], c.shape[2]
    if deg == 1:
        a1, a0 = c[:, 1, :], c[:, 0, :]
        with np.errstate(divide="ignore", invalid="ignore"):
            r = np.where(a1 != 0, -a0 / np.where(a1 != 0, a1, 1.0), 0.0)
        out = r[:, :, None]
    elif deg == 2:
        a2, a1, a0 = c[:, 2, :], c[:, 1, :], c[:, 0, :]
        disc = a1**2 - 4 * a2 * a0
        sq = np.sqrt(np.maximum(disc, 0.0))
        with np.errstate(divide="ignore", invalid="ignore"):
            safe = np.where(a2 != 0, a2, 1.0)
            roots = [np.where((a2 != 0) & (disc >= 0), (-a1 + s * sq) / (2 * safe), 0.0) for s in (1.0, -1.0)]
            roots.append(np.where((a2 == 0) & (a1 != 0), -a0 / np.where(a1 != 0, a1, 1.0), 0.0))
        out = np.stack(roots, axis=2)
    elif deg > 2:
        # scale time to the piece length so the companion matrix is well conditioned
        hs = np.where(h > 0, h, 1.0)
        cs = c * hs[:, None, None] ** np.arange(deg + 1)[None, :, None]
        lead = cs[:, -1, :]
        ok = np.abs(lead) > 1e-14 * np.max(np.abs(cs), axis=1)
        comp = np.zeros((K, A, deg, deg))
        comp[:, :, 1:, :-1] = np.eye(deg - 1)
        with np.errstate(divide="ignore", invalid="ignore"):
            comp[:, :, :, -1] = -np.where(ok[:, None, :], cs[:, :-1, :] / np.where(ok, lead, 1.0)[:, None, :], 0.0).transpose(0, 2, 1)
        eig = np.linalg.eigvals(comp)  # (K, A, deg)
        real = np.abs(eig.imag) <= 1e-9 * np.maximum(1.0, np.abs(eig.real))
        out = np.where(real & ok[:, :, None] & (eig.real >= 0) & (eig.real <= 1), eig.real, 0.0) * hs[:, None, None]
    else:
        return np.zeros((K, A, 0))
    return np.clip(np.nan_to_num(out), 0.0, h[:, None, None])
