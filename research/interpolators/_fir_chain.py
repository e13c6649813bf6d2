"""A chain of n moving-average (FIR) filters: impulse-response moments, spectrum, modal tuning.

Sencer, Ishizaki, Shamoto 2015 (CIRP Annals 64), section 2. Each filter is
``M_i(s) = (1 - exp(-s T_i)) / (s T_i)`` (eq 1), a rectangular impulse response of unit area and
length ``T_i`` (eq 2). The chain's impulse response ``h = m_1 * ... * m_n`` has support
``[0, T_d]`` with ``T_d = sum T_i`` (eq 6) and is symmetric about ``T_d / 2``.

All functions take ``delays`` as a 1-D array [s] and are written in ``jax.numpy`` so that they can
be differentiated with respect to the delays.
"""

from __future__ import annotations

import itertools
import math

import jax.numpy as jnp
import numpy as np
from jax import Array

from research.errors import ParameterError


def check_delays(delays) -> np.ndarray:
    """Validate filter delays: a non-empty 1-D sequence of finite values > 0 [s]."""
    d = np.atleast_1d(np.asarray(delays, dtype=np.float64))
    if d.ndim != 1 or d.size == 0:
        raise ParameterError(f"FIR delays must be a non-empty 1-D sequence [s], got shape {d.shape}")
    bad = ~(np.isfinite(d) & (d > 0))
    if bad.any():
        i = int(np.argmax(bad))
        raise ParameterError(f"FIR delay T_{i + 1} must be finite and > 0 s, got {d[i]!r}")
    return d


def total_delay(delays: Array) -> Array:
    """``T_d = T_1 + ... + T_n`` [s] (eq 6): the time the chain adds to every motion command."""
    return jnp.sum(jnp.asarray(delays))


def kernel_second_integral(r: Array, delays: Array) -> Array:
    """``H2(r) = integral_0^r (r - tau) h(tau) d tau`` of the chain's impulse response ``h``.

    Exact truncated-power form, from expanding ``prod_i (1 - exp(-s T_i)) / (s T_i)``::

        H2(r) = 1 / (n+1)! / prod(T) * sum_S (-1)^|S| (r - sum_{i in S} T_i)_+^(n+1)

    over all subsets ``S`` of the filters. ``H2`` is what sets the cornering error (see
    ``_fir_overlap``). Valid for ``0 <= r <= T_d / 2``, where it is evaluated.
    """
    delays = jnp.asarray(delays)
    n = delays.shape[0]
    r = jnp.asarray(r)
    total = jnp.zeros_like(r)
    for subset in itertools.product((0, 1), repeat=n):
        shift = jnp.sum(jnp.asarray(subset, dtype=delays.dtype) * delays)
        sign = (-1.0) ** sum(subset)
        total = total + sign * jnp.maximum(r - shift, 0.0) ** (n + 1)
    return total / (math.factorial(n + 1) * jnp.prod(delays))


def frequency_response(omega: Array, delays: Array) -> Array:
    """Complex response of the chain at angular frequencies ``omega`` [rad/s] (eq 8)::

        M_i(j w) = exp(-j w T_i / 2) sin(w T_i / 2) / (w T_i / 2)
    """
    w = jnp.asarray(omega, dtype=jnp.float64)[..., None]
    half = 0.5 * w * jnp.asarray(delays)
    return jnp.prod(jnp.exp(-1j * half) * jnp.sinc(half / jnp.pi), axis=-1)


def magnitude_response(omega: Array, delays: Array) -> Array:
    """``|M_1 ... M_n|(j w) = prod |sin(pi w / w_i) / (pi w / w_i)|`` with ``w_i = 2 pi / T_i`` (eq 9).

    The acceleration spectrum is this times ``|v(j w) j w|`` (eq 7): it vanishes at every multiple
    of each ``w_i``.
    """
    return jnp.abs(frequency_response(omega, delays))


def acceleration_spectrum(omega: Array, delays: Array, velocity_spectrum: Array) -> Array:
    """``|a'(j w)| = |v(j w)| w |M_1 ... M_n|(j w)`` (eq 7) for a given input velocity spectrum."""
    return jnp.abs(velocity_spectrum) * jnp.abs(jnp.asarray(omega)) * magnitude_response(omega, delays)


def delays_for_modes(mode_frequencies_hz, k=1) -> np.ndarray:
    """Filter delays that place a spectral zero on each structural mode (eq 10).

    ``T_i = k_i 2 pi / w_r,i = k_i / f_r,i``. Example (Sencer 2015 §4, beams at 6.8 Hz and
    11.4 Hz): ``delays_for_modes([6.8, 11.4])`` gives 147 ms and 88 ms; the paper rounds to
    148 ms and 89 ms.

    Args:
        mode_frequencies_hz: modal frequencies ``f_r`` [Hz], one per filter.
        k: positive integer ripple index (scalar or one per filter).

    Returns:
        Delays [s], in the order given.
    """
    f = np.atleast_1d(np.asarray(mode_frequencies_hz, dtype=np.float64))
    k = np.broadcast_to(np.asarray(k), f.shape)
    if not np.all(np.isfinite(f) & (f > 0)):
        raise ParameterError(f"modal frequencies must be finite and > 0 Hz, got {f.tolist()}")
    if not np.all((k >= 1) & (np.asarray(k) == np.round(k))):
        raise ParameterError(f"eq 10 ripple index k must be a positive integer, got {np.asarray(k).tolist()}")
    return k / f
