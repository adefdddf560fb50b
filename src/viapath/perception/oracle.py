"""The oracle perception model: true obstacle states, optionally with noise on every estimate.

To test planning under uncertainty without lasers: Gaussian noise (σ per axis) on each position and
velocity estimate, drawn anew every cycle from the episode's generator, and the σ handed to the
planner with the estimates (as a tracker would).
"""

from __future__ import annotations

import numpy as np

from viapath.observation import Obstacles
from viapath.perception.base import Perception, WorldSnapshot


class OraclePerception(Perception):
    """True obstacle states, with optional per-cycle Gaussian noise (σ per axis)."""

    name = "oracle"

    def __init__(self, position_noise_m: float = 0.0, velocity_noise_mps: float = 0.0):
        self.position_noise_m = float(position_noise_m)
        self.velocity_noise_mps = float(velocity_noise_mps)
        self.rng = np.random.default_rng(0)

    def observe(self, world: WorldSnapshot) -> Obstacles:
        present = world.present()
        positions = world.obstacle_positions[present]
        velocities = world.obstacle_velocities[present]
        if self.position_noise_m > 0:
            positions = positions + self.rng.normal(0.0, self.position_noise_m, positions.shape)
        if self.velocity_noise_mps > 0:
            velocities = velocities + self.rng.normal(0.0, self.velocity_noise_mps, velocities.shape)
        n = len(positions)
        # Every array here is new (indexing with a mask copies), so the estimates are handed over as they are.
        return Obstacles.of_fresh_arrays(
            positions,
            velocities,
            world.obstacle_radii_m[present],
            np.full(n, self.position_noise_m),
            np.full(n, self.velocity_noise_mps),
            np.flatnonzero(present),
        )
