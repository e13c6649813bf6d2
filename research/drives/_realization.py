"""The continuous-time state-space form every drive model hands to the simulator.

A model is linear apart from Coulomb friction, so it is written as

    z' = A z + B r + Bw w,        y = C z + D r + Dw w,

with the reference ``r = [x_r, x_r', x_r'']`` [mm, mm/s, mm/s^2], the friction inputs
``w = [f_c sigma(x'), f_ff sigma(x_r')]`` (actual Coulomb friction and its feed-forward compensation,
in the model's disturbance unit) and the outputs ``y = [x, x', u]`` [mm, mm/s, V]. The position and velocity
are always states (``position_index``, ``velocity_index``), so the friction sign needs no algebraic loop.
"""

from __future__ import annotations

from typing import NamedTuple

from jax import Array


class Realization(NamedTuple):
    """State-space matrices of one axis (see the module docstring for the signals and units)."""

    A: Array
    B: Array
    Bw: Array
    C: Array
    D: Array
    Dw: Array
    friction_amplitude: Array
    friction_feedforward: Array
    position_index: int
    velocity_index: int
    has_control: bool
