"""Input checks shared by the drive models.

Checks run only on concrete values: inside ``jit``/``grad`` tracing the parameters are abstract and
the checks are skipped, so models stay differentiable. Every failure raises
:class:`research.errors.ParameterError` naming the parameter and what was expected.
"""

from __future__ import annotations

import jax
import numpy as np

from research.errors import ParameterError


def is_concrete(*values) -> bool:
    """True when none of ``values`` (or their pytree leaves) is a JAX tracer."""
    leaves = jax.tree_util.tree_leaves(values)
    return not any(isinstance(x, jax.core.Tracer) for x in leaves)


def check_finite(owner: str, **fields) -> None:
    """Raise if any named field holds NaN or +-inf.

    Args:
        owner: class name used in the message, e.g. ``"ClosedLoopModel"``.
        fields: ``name=value`` pairs (scalars or arrays).
    """
    for name, value in fields.items():
        arr = np.asarray(value, dtype=np.float64)
        if not np.all(np.isfinite(arr)):
            raise ParameterError(f"{owner}.{name} must be finite, got {value!r}")


def check_positive(owner: str, **fields) -> None:
    """Raise unless every named field is > 0."""
    for name, value in fields.items():
        if not np.all(np.asarray(value, dtype=np.float64) > 0):
            raise ParameterError(f"{owner}.{name} must be > 0, got {value!r}")


def check_nonnegative(owner: str, **fields) -> None:
    """Raise unless every named field is >= 0."""
    for name, value in fields.items():
        if not np.all(np.asarray(value, dtype=np.float64) >= 0):
            raise ParameterError(f"{owner}.{name} must be >= 0, got {value!r}")


def check_unit_interval(owner: str, **fields) -> None:
    """Raise unless every named field lies in [0, 1] (feed-forward gains, thesis §6.2)."""
    for name, value in fields.items():
        v = np.asarray(value, dtype=np.float64)
        if not np.all((v >= 0) & (v <= 1)):
            raise ParameterError(f"{owner}.{name} is a feed-forward gain and must lie in [0, 1] (thesis §6.2), got {value!r}")


def format_poles(poles) -> str:
    """Poles as ``-85.5+172j rad/s (30.57 Hz, zeta 0.445)`` strings, comma separated."""
    out = []
    for p in np.atleast_1d(np.asarray(poles, dtype=np.complex128)):
        w = abs(p)
        zeta = -p.real / w if w > 0 else 1.0
        out.append(f"{p.real:.6g}{p.imag:+.6g}j rad/s ({w / (2 * np.pi):.4g} Hz, zeta {zeta:.3g})")
    return ", ".join(out)


def check_stable(name: str, poles) -> None:
    """Raise :class:`ParameterError` listing all poles if any has a real part >= 0.

    Args:
        name: what the poles belong to (used in the message).
        poles: continuous-time poles [rad/s].
    """
    poles = np.asarray(poles, dtype=np.complex128)
    if np.any(poles.real >= 0):
        raise ParameterError(
            f"{name} is not asymptotically stable: every pole needs a negative real part, but the poles are "
            f"{format_poles(poles)}"
        )


def check_sample_period(name: str, poles, sample_period: float) -> None:
    """Raise if the control period ``Ts`` [s] is too coarse for the fastest pole.

    The exact discretization is stable for any ``Ts``, but the friction sign and the reference are held
    over one period, so the fastest closed-loop dynamics must be resolved: we require the fastest pole
    magnitude to satisfy ``|lambda|max * Ts <= pi / 2`` (its frequency at most half the Nyquist frequency).
    """
    if not np.isfinite(sample_period) or sample_period <= 0:
        raise ParameterError(f"sample period Ts must be a finite number > 0 s, got {sample_period!r}")
    fastest = float(np.max(np.abs(np.asarray(poles, dtype=np.complex128)))) if np.size(poles) else 0.0
    if fastest * sample_period > np.pi / 2:
        raise ParameterError(
            f"sample period Ts = {sample_period:g} s is too coarse for {name}: its fastest pole has |lambda| = "
            f"{fastest:.6g} rad/s ({fastest / (2 * np.pi):.4g} Hz); need Ts <= pi/(2|lambda|) = "
            f"{np.pi / (2 * fastest):.3g} s"
        )
