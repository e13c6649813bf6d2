"""``research._device``: NumPy results handed to JAX by a transfer, one or several at once.

Expected values are the inputs themselves (a transfer changes no value): float64, the same
shapes, the same numbers bit for bit, whatever the input's layout or dtype."""

import jax
import jax.numpy as jnp
import numpy as np

from research._device import device_array, device_arrays


def test_device_arrays_is_device_array_of_each():
    """Mixed inputs (a float64 array, a strided view, an int array, a 0-d value, a JAX array): each
    comes back a float64 JAX array holding the same values as ``device_array`` of it alone."""
    rng = np.random.default_rng(0)
    base = rng.normal(size=(6, 4))
    xs = (base, base[:, ::2], np.arange(5), 3.5, jnp.asarray(rng.normal(size=3)), np.zeros(0))
    got = device_arrays(*xs)
    assert len(got) == len(xs)
    for x, y in zip(xs, got):
        want = device_array(x)
        assert isinstance(y, jax.Array) and y.dtype == jnp.float64 and y.shape == want.shape
        np.testing.assert_array_equal(np.asarray(y), np.asarray(want))
        np.testing.assert_array_equal(np.asarray(y), np.asarray(x, dtype=np.float64))


def test_device_arrays_of_nothing_is_empty():
    assert device_arrays() == ()
