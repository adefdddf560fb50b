"""The oracle's shortcuts (everyone present; an empty scene) hand the planner exactly what the plain masked
form hands it, and draw the same noise."""

import numpy as np
import pytest

from viapath.observation import Obstacles
from viapath.perception.base import WorldSnapshot
from viapath.perception.oracle import OraclePerception


def _reference(world: WorldSnapshot, position_noise_m: float, velocity_noise_mps: float, rng) -> Obstacles:
    """The oracle as first written: masks for who is present, np.full for the σ."""
    present = np.isfinite(world.obstacle_positions).all(axis=1)
    positions = world.obstacle_positions[present]
    velocities = world.obstacle_velocities[present]
    if position_noise_m > 0:
        positions = positions + rng.normal(0.0, position_noise_m, positions.shape)
    if velocity_noise_mps > 0:
        velocities = velocities + rng.normal(0.0, velocity_noise_mps, velocities.shape)
    n = len(positions)
    return Obstacles(
        positions,
        velocities,
        world.obstacle_radii_m[present],
        np.full(n, position_noise_m),
        np.full(n, velocity_noise_mps),
        np.flatnonzero(present),
    )


@pytest.mark.parametrize("noise", [(0.0, 0.0), (0.05, 0.0), (0.0, 0.1), (0.03, 0.05)])
def test_oracle_matches_the_masked_form(noise):
    world_rng = np.random.default_rng(7)
    for trial in range(60):
        n = int(world_rng.integers(0, 7))
        positions = world_rng.uniform(-5, 5, (n, 2))
        if n and trial % 3 == 0:  # some people not in the scene yet (replays): NaN rows
            positions[world_rng.random(n) < 0.4] = np.nan
        world = WorldSnapshot(
            0.1 * trial, np.zeros(3), 0.25, positions, world_rng.uniform(-1, 1, (n, 2)), world_rng.uniform(0.2, 0.4, n)
        )
        oracle = OraclePerception(*noise)
        oracle.reset(np.random.default_rng(trial))
        expected_rng = np.random.default_rng(trial)
        got, expected = oracle.observe(world), _reference(world, *noise, expected_rng)
        for name in ("positions", "velocities", "radii_m", "position_sigma_m", "velocity_sigma_mps", "ids"):
            a, b = getattr(got, name), getattr(expected, name)
            assert a.dtype == b.dtype and a.shape == b.shape, name
            assert np.array_equal(a, b), name
        assert oracle.rng.bit_generator.state == expected_rng.bit_generator.state  # the same draws, no more


def test_oracle_arrays_are_its_own():
    positions = np.array([[1.0, 2.0], [3.0, 4.0]])
    world = WorldSnapshot(0.0, np.zeros(3), 0.25, positions, np.zeros((2, 2)), np.full(2, 0.3))
    oracle = OraclePerception()
    oracle.reset(np.random.default_rng(0))
    seen = oracle.observe(world)
    seen.positions[0, 0] = 99.0  # a planner that writes into its input must not move the world's people
    assert world.obstacle_positions[0, 0] == 1.0
