"""Obstacles built from well-formed arrays (what perception hands over every cycle) take a shortcut
past the general conversions and checks (``Obstacles._set_well_formed``); it must build exactly what the
general path builds: same values, dtypes and shapes, and copies, never the caller's arrays."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from viapath.observation import Obstacles


@st.composite
def _fields(draw):
    n = draw(st.integers(0, 5))
    rng = np.random.default_rng(draw(st.integers(0, 2**31 - 1)))
    positions = rng.normal(0.0, 3.0, (n, 2))
    velocities = rng.normal(0.0, 1.0, (n, 2))
    radii = draw(st.sampled_from(["array", "scalar", "int-array"]))
    radii = {"array": rng.uniform(0.1, 0.4, n), "scalar": 0.3, "int-array": np.ones(n, dtype=int)}[radii]
    sigma = draw(st.sampled_from([None, "array", "scalar"]))
    sigma = {None: None, "array": rng.uniform(0.0, 0.1, n), "scalar": 0.05}[sigma]
    ids = draw(st.sampled_from([None, "int", "uint", "float", "huge", "list"]))
    ids = {
        None: None,
        "int": rng.integers(-5, 1000, n),
        "uint": rng.integers(0, 1000, n).astype(np.uint32),
        "float": np.arange(n, dtype=float),
        "huge": np.full(n, 2**60 + 1, dtype=np.int64),
        "list": list(range(n)),
    }[ids]
    if draw(st.booleans()) and n:
        positions = np.asfortranarray(np.concatenate([positions, positions]))[::2]  # a strided view
    return positions, velocities, radii, sigma, ids


def _general(*args):
    original = Obstacles._set_well_formed
    Obstacles._set_well_formed = lambda self: False
    try:
        return Obstacles(*args)
    finally:
        Obstacles._set_well_formed = original


@settings(max_examples=300, deadline=None, derandomize=True)
@given(_fields())
def test_shortcut_builds_what_the_general_path_builds(fields):
    positions, velocities, radii, sigma, ids = fields
    args = (positions, velocities, radii, sigma, sigma, ids)
    fast, general = Obstacles(*args), _general(*args)
    for name in ("positions", "velocities", "radii_m", "position_sigma_m", "velocity_sigma_mps", "ids"):
        a, b = getattr(fast, name), getattr(general, name)
        assert a.dtype == b.dtype and a.shape == b.shape, name
        np.testing.assert_array_equal(a, b, err_msg=name)
        assert a.flags.c_contiguous
        for given_array in args:
            assert a is not given_array, name  # a copy: the caller may reuse its arrays


def test_shortcut_keeps_the_shape_errors():
    from viapath.observation import ObservationError

    with pytest.raises(ObservationError, match="velocities"):
        Obstacles(np.zeros((3, 2)), np.zeros((2, 2)), np.zeros(3))
    with pytest.raises(ObservationError, match="radii_m"):
        Obstacles(np.zeros((3, 2)), np.zeros((3, 2)), np.zeros(2))
    with pytest.raises(ObservationError, match="ids"):
        Obstacles(np.zeros((3, 2)), np.zeros((3, 2)), np.zeros(3), ids=np.zeros(2, dtype=int))


@settings(max_examples=200, deadline=None, derandomize=True)
@given(_fields())
def test_fresh_arrays_make_the_obstacles_the_constructor_makes(fields):
    """A perception's fresh arrays are kept as they are (no copy) when well formed: the same values,
    dtypes and shapes as the constructor's; anything else goes through the constructor."""
    positions, velocities, radii, sigma, ids = fields
    n = len(positions)
    sigma = np.full(n, 0.05) if sigma is None else sigma
    candidates = [
        (positions, velocities, radii, sigma, sigma, ids),
        (
            np.ascontiguousarray(positions),
            velocities,
            np.broadcast_to(np.asarray(radii, float), (n,)).copy(),
            np.broadcast_to(np.asarray(sigma, float), (n,)).copy(),
            np.zeros(n),
            np.arange(n),
        ),
    ]
    for args in candidates:
        fresh, built = Obstacles.of_fresh_arrays(*args), Obstacles(*args)
        for name in ("positions", "velocities", "radii_m", "position_sigma_m", "velocity_sigma_mps", "ids"):
            a, b = getattr(fresh, name), getattr(built, name)
            assert a.dtype == b.dtype and a.shape == b.shape, name
            np.testing.assert_array_equal(a, b, err_msg=name)
    kept = Obstacles.of_fresh_arrays(*candidates[1])
    assert kept.positions is candidates[1][0]  # well formed: handed over, not copied


def test_oracle_observes_as_before():
    from viapath.perception.base import WorldSnapshot
    from viapath.perception.oracle import OraclePerception

    world = WorldSnapshot(
        0.0,
        np.zeros(3),
        0.25,
        np.array([[1.0, 2.0], [np.nan, np.nan], [3.0, -1.0]]),
        np.array([[0.1, 0.0], [0.0, 0.0], [-0.3, 0.2]]),
        np.array([0.3, 0.25, 0.35]),
    )
    for noise in (0.0, 0.05):
        oracle = OraclePerception(noise, noise)
        oracle.rng = np.random.default_rng(1)
        seen = oracle.observe(world)
        rng = np.random.default_rng(1)
        positions = world.obstacle_positions[[0, 2]] + (rng.normal(0.0, noise, (2, 2)) if noise else 0.0)
        velocities = world.obstacle_velocities[[0, 2]] + (rng.normal(0.0, noise, (2, 2)) if noise else 0.0)
        expected = Obstacles(
            positions, velocities, np.array([0.3, 0.35]), np.full(2, noise), np.full(2, noise), np.array([0, 2])
        )
        for name in ("positions", "velocities", "radii_m", "position_sigma_m", "velocity_sigma_mps", "ids"):
            a, b = getattr(seen, name), getattr(expected, name)
            assert a.dtype == b.dtype
            np.testing.assert_array_equal(a, b, err_msg=name)


def test_ids_at_the_ends_of_int64_keep_their_sign_on_every_path_without_a_warning():
    """Through float (as every path takes ids) int64's maximum becomes 2**63, one past it: it must stay the
    largest id, not wrap to the most negative one (with numpy's "invalid value in cast" warning)."""
    import warnings

    from viapath.observation import ObservationError

    ids = np.array([np.iinfo(np.int64).max, np.iinfo(np.int64).min, 7], dtype=np.int64)
    arrays = (np.zeros((3, 2)), np.zeros((3, 2)), np.full(3, 0.3), np.zeros(3), np.zeros(3))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        built = [Obstacles(*arrays, ids), _general(*arrays, ids), Obstacles.of_fresh_arrays(*arrays, ids)]
    for obstacles in built:
        assert obstacles.ids.dtype == np.int64
        assert obstacles.ids[0] > 2**62 and obstacles.ids[1] == np.iinfo(np.int64).min and obstacles.ids[2] == 7
        np.testing.assert_array_equal(obstacles.ids, built[0].ids)
    too_big = np.array([2**64 - 1, 1, 2], dtype=np.uint64)  # beyond int64: refused, naming the field
    with pytest.raises(ObservationError, match="ids"):
        Obstacles(*arrays, too_big)
