"""The one decorator of the compiled steps: compiled and plain Python give the same answers."""

from __future__ import annotations

import math

import numpy as np

from viapath import jit


@jit.compiled(inline=True)
def _square(x):
    return x * x


@jit.compiled
def _norms(points):
    out = np.empty(points.shape[0])
    for i in range(points.shape[0]):
        out[i] = math.sqrt(_square(points[i, 0]) + _square(points[i, 1]))
    return out


def test_compiled_and_plain_python_agree_with_numpy():
    points = np.random.default_rng(3).normal(size=(50, 2))
    expected = np.hypot(points[:, 0], points[:, 1])
    np.testing.assert_allclose(_norms(points), expected, rtol=1e-15)
    plain = jit.python_function(_norms)
    np.testing.assert_allclose(plain(points), expected, rtol=1e-15)


def test_compiled_when_numba_is_enabled():
    if jit.enabled():
        assert jit.python_function(_norms) is not _norms  # a dispatcher around the plain function
    else:
        assert jit.python_function(_norms) is _norms
