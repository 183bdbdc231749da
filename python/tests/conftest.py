"""Shared fixtures of the shadelab Python suite."""

import numpy as np
import pytest

import shadelab

LIGHT = (0.3, 0.4, 0.866)


@pytest.fixture(scope="session")
def sphere():
    """A 96×96 Lambertian sphere with its ground-truth layers."""
    return shadelab.render("sphere", shape=96, light=LIGHT, layers=True)


def angular_error_deg(a, b, inside):
    """Mean angle between unit normals a and b over the mask, degrees."""
    cos = np.clip(np.sum(a * b, axis=-1), -1.0, 1.0)
    return float(np.degrees(np.arccos(cos))[inside].mean())


def owns_rust_buffer(arr):
    """True when `arr` holds memory NumPy did not allocate: no array along its chain of
    bases owns data, and the chain ends in the object holding the library's buffer."""
    base = arr
    while isinstance(base, np.ndarray):
        if base.flags.owndata:
            return False
        base = base.base
    return base is not None
